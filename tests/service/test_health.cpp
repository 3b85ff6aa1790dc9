// The health file and its judge (`usv-fdi health`), and the pipeline's liveness: a wedged
// isolation or identification thread makes the sidecar unhealthy, a silent input does not.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/dds_service/health.hpp"

namespace usvfdi::dds_service {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string temp_file(const std::string& name) {
  return ::testing::TempDir() + "usv_fdi_health_" + name + "_" + std::to_string(::getpid()) +
         ".json";
}

HealthReport running_report() {
  HealthReport r;
  r.time = unix_now();
  r.pid = 1234;
  r.mmsi = 257000001;
  r.state = "running";
  r.period = 1.0;
  r.stall_limit = 5.0;
  r.live.isolation = 0.02;
  r.live.identification = 0.05;
  r.live.publisher = 0.08;
  r.samples = 500;
  return r;
}

HealthVerdict write_and_check(const std::string& path, const HealthReport& r, double max_age,
                              double now) {
  std::string err;
  EXPECT_TRUE(write_health_file(path, r, &err)) << err;
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  return check_health_file(path, max_age, now);
}

TEST(HealthFile, FreshRunningIsHealthyWhateverTheInputs) {
  const std::string path = temp_file("fresh");
  HealthReport r = running_report();
  HealthVerdict v = write_and_check(path, r, 10.0, r.time + 0.5);
  EXPECT_TRUE(v.healthy) << v.line;
  EXPECT_EQ(v.line.rfind("healthy: running", 0), 0u) << v.line;
  // A silent INS, a missing rudder, queue drops: reported, not a health problem.
  r.input_flags =
      pipeline::kInputInsSilent | pipeline::kInputRudderMissing | pipeline::kInputQueueDrops;
  r.live.ins_age = 42.0;
  r.isolation_paused = pipeline::kPauseInsSilent;
  v = write_and_check(path, r, 10.0, r.time + 0.5);
  EXPECT_TRUE(v.healthy) << v.line;
  EXPECT_NE(v.line.find("ins_silent,rudder_missing,queue_drops (not a health problem)"),
            std::string::npos)
      << v.line;
  // "starting" is healthy (the container's start period covers it).
  r.state = "starting";
  EXPECT_TRUE(write_and_check(path, r, 10.0, r.time).healthy);
  fs::remove(path);
}

TEST(HealthFile, StaleFailedStoppedMissingAndGarbageAreUnhealthyWithTheReason) {
  const std::string path = temp_file("bad");
  HealthReport r = running_report();
  HealthVerdict v = write_and_check(path, r, 10.0, r.time + 14.2);
  EXPECT_FALSE(v.healthy);
  EXPECT_NE(v.line.find("is 14.2 s old (max 10 s)"), std::string::npos) << v.line;
  // Default max age: three periods.
  v = write_and_check(path, r, 0.0, r.time + 3.5);
  EXPECT_FALSE(v.healthy) << v.line;
  EXPECT_TRUE(write_and_check(path, r, 0.0, r.time + 2.5).healthy);
  r.state = "failed";
  r.reason = "cannot start the DDS service: no participant";
  v = write_and_check(path, r, 10.0, r.time);
  EXPECT_FALSE(v.healthy);
  EXPECT_EQ(v.line, "unhealthy: failed: cannot start the DDS service: no participant");
  r.state = "stopped";
  r.reason = "signal 15";
  EXPECT_EQ(write_and_check(path, r, 10.0, r.time).line, "unhealthy: stopped: signal 15");
  // A thread that has not gone round its loop for longer than max-age.
  r = running_report();
  r.live.identification = 12.3;
  v = write_and_check(path, r, 10.0, r.time);
  EXPECT_FALSE(v.healthy);
  EXPECT_NE(v.line.find("identification thread has not advanced for 12.3 s"), std::string::npos)
      << v.line;
  {
    std::ofstream f(path);
    f << "{\"version\": 1, \"time\": ";
  }
  v = check_health_file(path, 10.0, unix_now());
  EXPECT_FALSE(v.healthy);
  EXPECT_NE(v.line.find("is not a health file"), std::string::npos) << v.line;
  {
    std::ofstream f(path);
    f << "{\"version\": 1, \"time\": \"noon\"}";
  }
  v = check_health_file(path, 10.0, unix_now());
  EXPECT_NE(v.line.find("wrong type"), std::string::npos) << v.line;
  fs::remove(path);
  v = check_health_file(path, 10.0, unix_now());
  EXPECT_FALSE(v.healthy);
  EXPECT_NE(v.line.find("no health file " + path), std::string::npos) << v.line;
}

TEST(HealthFile, AHealthFileThatCannotBeReadIsNamedWithTheSystemsReason) {
  // Reasons provoked whatever the user (root ignores mode bits): a path under a plain file, a
  // directory. Neither is "no health file".
  const std::string plain = temp_file("plain");
  std::ofstream(plain) << "not a directory";
  const std::string under = plain + "/health.json";
  HealthVerdict v = check_health_file(under, 10.0, unix_now());
  EXPECT_FALSE(v.healthy);
  EXPECT_EQ(v.line, "unhealthy: cannot read " + under + ": Not a directory");
  const std::string dir = ::testing::TempDir();
  v = check_health_file(dir, 10.0, unix_now());
  EXPECT_FALSE(v.healthy);
  EXPECT_EQ(v.line, "unhealthy: cannot read " + dir + ": Is a directory");
  fs::remove(plain);
}

TEST(HealthFile, JudgeNamesEveryStalledThread) {
  HealthReport r = running_report();
  judge_threads(&r);
  EXPECT_EQ(r.state, "running");
  r.live.isolation = 7.5;
  r.live.publisher = 6.0;
  judge_threads(&r);
  EXPECT_EQ(r.state, "failed");
  EXPECT_NE(r.reason.find("isolation thread stalled: it has not advanced for 7.5 s (limit 5 s)"),
            std::string::npos)
      << r.reason;
  EXPECT_NE(r.reason.find("publisher thread stalled"), std::string::npos) << r.reason;
  EXPECT_EQ(r.reason.find("identification"), std::string::npos) << r.reason;
}

/// A log sink that blocks the thread that logs a message containing `trap` until released:
/// a logger that wedges (e.g. writing to a full pipe) is one real way a thread stops.
class TrapLog {
 public:
  explicit TrapLog(std::string trap) : trap_(std::move(trap)) {}
  pipeline::FdiPipeline::LogSink sink() {
    return [this](int, const std::string& msg) {
      if (msg.find(trap_) == std::string::npos) return;
      std::unique_lock<std::mutex> lock(m_);
      caught_ = true;
      cv_.notify_all();
      cv_.wait(lock, [&] { return released_; });
    };
  }
  bool wait_caught(milliseconds timeout) {
    std::unique_lock<std::mutex> lock(m_);
    return cv_.wait_for(lock, timeout, [&] { return caught_; });
  }
  void release() {
    std::lock_guard<std::mutex> lock(m_);
    released_ = true;
    cv_.notify_all();
  }

 private:
  std::string trap_;
  std::mutex m_;
  std::condition_variable cv_;
  bool caught_ = false, released_ = false;
};

/// Waits (bounded) until pred(liveness) holds.
template <class Pred>
bool wait_liveness(const pipeline::FdiPipeline& p, milliseconds timeout, Pred pred) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    if (pred(p.liveness())) return true;
    std::this_thread::sleep_for(milliseconds(20));
  }
  return pred(p.liveness());
}

EngineConfig otter_config() {
  VesselModel v;
  EXPECT_TRUE(find_vessel("otter", &v));
  EngineConfig cfg;
  cfg.B = v.B;
  cfg.identification.eps1 = 2.0;
  cfg.identification.settle_windows = 2;
  cfg.identification.settle_tolerance = 0.02;
  return cfg;
}

TEST(PipelineLiveness, AWedgedIsolationThreadIsReportedStalled) {
  // GIVEN a running pipeline, idle: every thread goes round its loop
  TrapLog trap("ack of");
  pipeline::PipelineOptions opt;
  pipeline::FdiPipeline p(otter_config(), opt, nullptr, nullptr, trap.sink());
  p.start();
  ASSERT_TRUE(wait_liveness(p, milliseconds(5000), [](const pipeline::PipelineLiveness& l) {
    return l.isolation < 0.5 && l.identification < 0.5 && l.publisher < 0.5;
  }));
  HealthReport r = running_report();
  r.live = p.liveness();
  r.stall_limit = 1.0;
  judge_threads(&r);
  EXPECT_EQ(r.state, "running") << r.reason;
  EXPECT_LT(r.live.ins_age, 0.0) << "no INS sample yet";
  // WHEN the isolation thread wedges (its logger blocks while it reports an ack)
  p.push_ack({Sensor::kGyro, 5, "op"});
  ASSERT_TRUE(trap.wait_caught(milliseconds(5000)));
  ASSERT_TRUE(wait_liveness(p, milliseconds(10000),
                            [](const pipeline::PipelineLiveness& l) { return l.isolation > 1.5; }));
  // THEN its age grows while the other threads still go round, and the judge says which
  r.live = p.liveness();
  judge_threads(&r);
  EXPECT_EQ(r.state, "failed");
  EXPECT_NE(r.reason.find("isolation thread stalled"), std::string::npos) << r.reason;
  EXPECT_LT(r.live.identification, 1.0);
  EXPECT_LT(r.live.publisher, 1.0);
  const std::string path = temp_file("wedged");
  r.state = "running";  // as written before the judge: the checker looks at the ages too
  const HealthVerdict v = write_and_check(path, r, 1.0, r.time);
  EXPECT_FALSE(v.healthy);
  EXPECT_NE(v.line.find("isolation thread has not advanced"), std::string::npos) << v.line;
  fs::remove(path);
  // AND once it is released it goes round again
  trap.release();
  EXPECT_TRUE(wait_liveness(p, milliseconds(5000),
                            [](const pipeline::PipelineLiveness& l) { return l.isolation < 0.5; }));
  p.stop();
}

TEST(PipelineLiveness, AWedgedIdentificationThreadIsReportedStalled) {
  // GIVEN a pipeline fed the paper's scenario (noise-free Otter) until A converges, whose
  // identification thread wedges when it reports the convergence
  TrapLog trap("identification: A converged");
  pipeline::PipelineOptions opt;
  opt.input_capacity = 1 << 16;
  pipeline::FdiPipeline p(otter_config(), opt, nullptr, nullptr, trap.sink());
  p.start();
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.sigma_v = sim.sigma_r = 0.0;
  sim.duration = 19.0;
  for (const SimRow& row : simulate(sim)) {
    p.push_rudder({row.t, row.delta, true});
    p.push_ins({row.t, row.v, row.r, true, true});
  }
  ASSERT_TRUE(trap.wait_caught(milliseconds(20000))) << "A never converged";
  // WHEN it stays wedged
  ASSERT_TRUE(wait_liveness(p, milliseconds(10000), [](const pipeline::PipelineLiveness& l) {
    return l.identification > 1.5;
  }));
  // THEN the judge names it, while the isolation thread still goes round
  HealthReport r = running_report();
  r.live = p.liveness();
  r.stall_limit = 1.0;
  judge_threads(&r);
  EXPECT_EQ(r.state, "failed");
  EXPECT_NE(r.reason.find("identification thread stalled"), std::string::npos) << r.reason;
  EXPECT_EQ(r.reason.find("isolation thread"), std::string::npos) << r.reason;
  EXPECT_GE(r.live.ins_age, 0.0);
  trap.release();
  EXPECT_TRUE(wait_liveness(p, milliseconds(5000), [](const pipeline::PipelineLiveness& l) {
    return l.identification < 0.5;
  }));
  p.stop();
}

}  // namespace
}  // namespace usvfdi::dds_service
