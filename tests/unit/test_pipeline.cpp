// Threading tests of the service pipeline (no middleware): deterministic because the
// inputs carry source time and stop() drains every queue before joining.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>
#include <thread>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::pipeline {
namespace {

TEST(BoundedQueue, DropsOldestWhenFullAndCountsIt) {
  BoundedQueue<int> q(3);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(q.push(i));
  EXPECT_EQ(q.dropped(), 2u);
  int x = -1;
  ASSERT_TRUE(q.pop(&x));
  EXPECT_EQ(x, 2);
}

TEST(BoundedQueue, DropNewestRefusesAndPopEndsAfterShutdown) {
  BoundedQueue<int> q(1, OverflowPolicy::kDropNewest);
  EXPECT_TRUE(q.push(1));
  EXPECT_FALSE(q.push(2));
  EXPECT_EQ(q.dropped(), 1u);
  q.shutdown();
  EXPECT_FALSE(q.push(3));
  int x = 0;
  EXPECT_TRUE(q.pop(&x));  // drains what is left
  EXPECT_EQ(x, 1);
  EXPECT_FALSE(q.pop(&x));
}

TEST(BoundedQueue, ShutdownWakesABlockedConsumer) {
  BoundedQueue<int> q(4);
  std::atomic<bool> returned{false};
  std::thread consumer([&] {
    int x;
    EXPECT_FALSE(q.pop(&x));
    returned = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(returned);
  q.shutdown();
  consumer.join();
  EXPECT_TRUE(returned);
}

TEST(SampleAssembler, InterpolatesTheRudderAtTheInsStampAndReorders) {
  SampleAssembler a(0.1, 0.5);
  a.add_ins({1.02, 0.1, 0.01, true, true});
  a.add_ins({1.00, 0.2, 0.02, true, false});  // out of order, gyro invalid
  a.add_rudder({0.99, 0.0, true});
  std::vector<Sample> out;
  a.drain(&out);
  EXPECT_TRUE(out.empty());  // waits for a rudder sample at or after 1.00
  a.add_rudder({1.03, 0.4, true});
  a.drain(&out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].t, 1.00);
  EXPECT_NEAR(out[0].delta, 0.1, 1e-12);
  EXPECT_TRUE(std::isnan(out[0].r));
  EXPECT_DOUBLE_EQ(out[1].t, 1.02);
  EXPECT_NEAR(out[1].delta, 0.3, 1e-12);
}

TEST(SampleAssembler, HoldsThenDropsALateRudder) {
  SampleAssembler a(0.1, 0.5);
  a.add_rudder({0.0, 0.2, true});
  std::vector<Sample> out;
  for (int k = 0; k <= 100; ++k) a.add_ins({0.01 * k, 0.0, 0.0, true, true});
  a.drain(&out);
  ASSERT_FALSE(out.empty());
  EXPECT_DOUBLE_EQ(out.front().delta, 0.2);   // held
  EXPECT_TRUE(std::isnan(out.back().delta));  // older than rudder_timeout: missing
}

TEST(SampleAssembler, FasterThanRealTimeARudderSampleLateByMillisecondsIsStillUsed) {
  // GIVEN 64 Hz samples replayed 16 times faster than real time (1 ms of wall time each)
  // whose rudder sample of t = 1.0 s arrives 10 ms after the INS samples up to t = 1.16 s
  SampleAssembler a(0.1, 0.5, 0.1);
  a.add_rudder({0.98, 0.0, true});
  std::vector<Sample> out;
  for (int k = 0; k <= 10; ++k) {
    const double t = 1.0 + k / 64.0;
    a.add_ins({t, 0.0, 0.0, true, true}, 0.001 * k);
    a.drain(&out, false, 0.001 * k);
  }
  // WHEN it arrives, 10 ms of wall-clock time later
  EXPECT_TRUE(out.empty()) << "released after " << out.size() << " sample(s)";
  a.add_rudder({1.0, 0.2, true});
  a.drain(&out, false, 0.02);
  // THEN the INS sample of t = 1.0 s was kept waiting for it and has its exact angle
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.2);
  // AND the others are held (no later rudder sample) once they waited 0.1 s of wall time
  a.drain(&out, false, 0.05);
  EXPECT_EQ(out.size(), 1u);
  a.drain(&out, false, 0.2);
  ASSERT_EQ(out.size(), 4u);  // 1/64 .. 3/64 s after it: at least 0.1 s older than the newest
  EXPECT_DOUBLE_EQ(out.back().delta, 0.2);
}

TEST(SampleAssembler, EachInsSampleTakesTheNearestSpeedWithinItsMaxAgeAndWaitsForIt) {
  SampleAssembler a(0.1, 0.5, 0.0, 2.0);
  std::vector<Sample> out;
  // No speed stream: nothing waits for one, and u is missing.
  a.add_rudder({0.0, 0.0, true});
  a.add_ins({0.0, 0.0, 0.0, true, true});
  a.drain(&out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(std::isnan(out[0].u));
  // A speed stream: the INS sample of t = 1.0 waits for a speed sample at or after it.
  a.add_speed({0.5, 7.0, true});
  a.add_speed({0.9, 8.0, false});   // the source says it has no speed now: ignored
  a.add_speed({0.95, kNaN, true});  // no value: ignored
  a.add_rudder({2.0, 0.0, true});
  a.add_ins({1.0, 0.0, 0.0, true, true});
  a.drain(&out);
  EXPECT_EQ(out.size(), 1u);
  a.add_speed({1.1, 6.0, true});
  a.drain(&out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[1].u, 6.0);  // 0.1 s after it, against 0.5 s before
  // A speed the INS sample brings itself (NMEA) goes before the stream's.
  InsInput own{1.2, 0.0, 0.0, true, true};
  own.u = 5.5;
  a.add_ins(own);
  a.drain(&out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[2].u, 5.5);
  // Farther than speed_max_age from every speed sample: none (the engine holds the last).
  a.add_rudder({5.0, 0.0, true});
  a.add_speed({6.0, 6.5, true});
  a.add_ins({3.5, 0.0, 0.0, true, true});
  a.drain(&out);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_TRUE(std::isnan(out[3].u));
}

TEST(SampleAssembler, AStoppedSpeedStreamHoldsNoInsSampleBack) {
  // GIVEN a speed stream that stopped at t = 1 s (speed_max_age 2 s)
  SampleAssembler a(0.1, 0.5, 0.0, 2.0);
  a.add_speed({1.0, 7.0, true});
  a.add_rudder({5.0, 0.0, true});
  std::vector<Sample> out;
  // WHEN an INS sample comes within 2 s of its last speed, THEN it waits for a speed sample
  a.add_ins({2.5, 0.0, 0.0, true, true});
  a.drain(&out);
  EXPECT_TRUE(out.empty());
  // AND one more than 2 s after it is released at once (its rudder angle is there); the
  // waiting one goes with it, with the last speed
  a.add_ins({3.5, 0.0, 0.0, true, true});
  a.drain(&out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].u, 7.0);
  EXPECT_TRUE(std::isnan(out[1].u));
}

TEST(SampleAssembler, DoesNotBridgeARudderGapLongerThanTheTimeout) {
  SampleAssembler a(0.1, 0.5);
  a.add_rudder({0.0, 0.0, true});
  a.add_rudder({3.0, 0.3, true});
  for (double t : {0.2, 1.5, 2.9}) a.add_ins({t, 0.0, 0.0, true, true});
  std::vector<Sample> out;
  a.drain(&out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.0);    // held from the sample 0.2 s before
  EXPECT_TRUE(std::isnan(out[1].delta));  // 1.5 s from either side: no rudder angle
  EXPECT_DOUBLE_EQ(out[2].delta, 0.3);    // held from the sample 0.1 s after
}

struct Collected {
  std::mutex m;
  std::vector<FaultEvent> events;
  std::vector<PipelineStatus> statuses;
  std::vector<std::string> logs;
};

FdiPipeline make(const EngineConfig& cfg, Collected* c, PipelineOptions opt = {}) {
  return FdiPipeline(
      cfg, opt,
      [c](const FaultEvent& e) {
        std::lock_guard<std::mutex> l(c->m);
        c->events.push_back(e);
      },
      [c](const PipelineStatus& s) {
        std::lock_guard<std::mutex> l(c->m);
        c->statuses.push_back(s);
      },
      [c](int, const std::string& msg) {
        std::lock_guard<std::mutex> l(c->m);
        c->logs.push_back(msg);
      });
}

TEST(FdiPipeline, PaperScenarioThroughTheThreadsRaisesBothFaults) {
  // GIVEN the paper's scenario (noise-free Otter) fed as separate INS and rudder streams
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.sigma_v = sim.sigma_r = 0.0;
  EngineConfig cfg;
  cfg.B = v.B;
  cfg.identification.eps1 = 2.0;
  cfg.identification.settle_windows = 2;
  cfg.identification.settle_tolerance = 0.02;
  cfg.isolation.sigma_v = 0.005;
  cfg.isolation.sigma_r = 0.0005;
  cfg.isolation.settle_time = 2.0;
  cfg.isolation.learn_time = 3.0;
  cfg.isolation.enter_time = 0.06;  // as config/scenarios/paper.yaml: the exact model, no mismatch
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 1 << 16;  // the test pushes faster than real time: no drops
  FdiPipeline p = make(cfg, &c, opt);
  p.start();
  // WHEN every sample is pushed (rudder first or last, alternating) and the pipeline stops
  for (const SimRow& r : simulate(sim)) {
    const int k = static_cast<int>(std::lround(r.t * 50));
    if (k % 2) p.push_rudder({r.t, r.delta, true});
    p.push_ins({r.t, r.v, r.r, true, true});
    if (!(k % 2)) p.push_rudder({r.t, r.delta, true});
  }
  p.stop();
  // THEN a gyro fault and an accelerometer fault were raised (isolated) and cleared, nothing
  // else (kind refinements of a raised fault, same state, are not state changes). Times with
  // tolerances: the core's numerics may change.
  std::vector<FaultEvent> changes;
  for (const FaultEvent& e : c.events) {
    const bool refinement =
        !changes.empty() && changes.back().sensor == e.sensor && changes.back().state == e.state;
    if (!refinement) changes.push_back(e);
  }
  std::vector<std::pair<Sensor, FaultState>> seen;
  for (const FaultEvent& e : changes) seen.emplace_back(e.sensor, e.state);
  const std::vector<std::pair<Sensor, FaultState>> want = {
      {Sensor::kGyro, FaultState::kRaised},
      {Sensor::kGyro, FaultState::kClearedUnacknowledged},
      {Sensor::kAccelerometer, FaultState::kRaised},
      {Sensor::kAccelerometer, FaultState::kClearedUnacknowledged}};
  ASSERT_EQ(seen, want);
  EXPECT_GT(changes[0].t, 20.0);
  EXPECT_LT(changes[0].t, 23.0);
  EXPECT_GE(changes[0].c_g, 0.8);
  EXPECT_LE(changes[0].c_a, 0.2);
  EXPECT_GT(changes[1].t, 40.0);
  EXPECT_LT(changes[1].t, 45.0);
  EXPECT_GT(changes[2].t, 60.0);
  EXPECT_LT(changes[2].t, 63.0);
  EXPECT_GE(changes[2].c_a, 0.8);
  EXPECT_LE(changes[2].c_g, 0.2);
  EXPECT_GT(changes[3].t, 80.0);
  EXPECT_LT(changes[3].t, 85.0);
  for (std::size_t i = 1; i < c.events.size(); ++i) {
    if (c.events[i].sensor == c.events[i - 1].sensor) {
      EXPECT_GT(c.events[i].sequence, c.events[i - 1].sequence);
    }
  }
  EXPECT_EQ(p.status().dropped_inputs, 0u);
  EXPECT_EQ(p.status().rejected, 0u);
}

TEST(FdiPipeline, TheDetectorSupervisesIdentificationAsInTheReplay) {
  // GIVEN the paper's vessel and steering without faults, long enough for the detector to
  // arm and learn
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.faults.clear();  // healthy throughout
  sim.duration = 60.0;
  sim.sigma_v = sim.sigma_r = 0.0;
  EngineConfig cfg;
  cfg.B = v.B;
  cfg.identification.eps1 = 2.0;
  cfg.identification.settle_windows = 2;
  cfg.identification.settle_tolerance = 0.02;
  cfg.isolation.sigma_v = 0.005;
  cfg.isolation.sigma_r = 0.0005;
  cfg.isolation.settle_time = 2.0;
  cfg.isolation.learn_time = 3.0;
  cfg.isolation.enter_time = 0.06;  // as config/scenarios/paper.yaml: the exact model, no mismatch
  const std::vector<SimRow> rows = simulate(sim);
  FdiEngine engine(cfg);
  std::vector<FaultEvent> evs;
  for (const SimRow& r : rows) engine.process(Sample{r.t, r.v, r.r, r.delta}, &evs);
  const IsolatorStatus& st = engine.isolation_status();
  ASSERT_TRUE(st.armed && !st.learning && !st.settling)
      << "the scenario must let it learn: armed " << st.armed << " learning " << st.learning
      << " settling " << st.settling;
  ASSERT_TRUE(engine.estimate().supervised);
  // WHEN the same samples run through the pipeline's threads in lock-step
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 1 << 16;
  opt.input_timeout = 1e9;  // wall-clock silence must not inject samples on a busy machine
  FdiPipeline p = make(cfg, &c, opt);
  p.start();
  for (const SimRow& r : rows) {
    p.push_rudder({r.t, r.delta, true});
    p.push_ins({r.t, r.v, r.r, true, true});
  }
  p.stop();
  // THEN its identification is supervised by its detector too (the consistency guard's
  // release after convergence depends on it)
  const PipelineStatus ps = p.status();
  EXPECT_TRUE(ps.isolation.armed && !ps.isolation.learning);
  EXPECT_TRUE(ps.estimate.supervised);
}

/// The paper test's engine, and its noise-free scenario's rows with stamps shifted by t0.
EngineConfig paper_config(const VesselModel& v) {
  EngineConfig cfg;
  cfg.B = v.B;
  cfg.identification.eps1 = 2.0;
  cfg.identification.settle_windows = 2;
  cfg.identification.settle_tolerance = 0.02;
  cfg.isolation.sigma_v = 0.005;
  cfg.isolation.sigma_r = 0.0005;
  cfg.isolation.settle_time = 2.0;
  cfg.isolation.learn_time = 3.0;
  cfg.isolation.enter_time = 0.06;  // as config/scenarios/paper.yaml: the exact model, no mismatch
  return cfg;
}

std::vector<SimRow> paper_rows(const VesselModel& v, double duration) {
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.sigma_v = sim.sigma_r = 0.0;
  sim.duration = duration;
  return simulate(sim);
}

/// Raises (not refinements) of the pipeline fed `rows`, with its status.
std::vector<FaultEvent> pipeline_raises(const EngineConfig& cfg, const std::vector<SimRow>& rows,
                                        PipelineStatus* status) {
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 1 << 16;
  opt.input_timeout = 1e9;
  FdiPipeline p = make(cfg, &c, opt);
  p.start();
  for (const SimRow& r : rows) {
    p.push_rudder({r.t, r.delta, true});
    p.push_ins({r.t, r.v, r.r, true, true});
  }
  p.stop();
  *status = p.status();
  std::vector<FaultEvent> raises;
  for (const FaultEvent& e : c.events) {
    if (e.state == FaultState::kRaised && e.message.rfind("kind refined", 0) != 0) {
      raises.push_back(e);
    }
  }
  return raises;
}

bool raised_in(const std::vector<FaultEvent>& raises, Sensor s, double from, double to) {
  for (const FaultEvent& e : raises) {
    if (e.sensor == s && e.t >= from && e.t <= to) return true;
  }
  return false;
}

TEST(FdiPipelineClock, OneInsStampFarAheadIsRejectedAloneAndBothFaultsAreRaised) {
  // GIVEN the paper's scenario in which the stamps of one INS and one rudder sample (t =
  // 45 s, between the faults) jumped ahead by 1e9 s
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  std::vector<SimRow> rows = paper_rows(v, 100.0);
  for (SimRow& r : rows) {
    if (std::abs(r.t - 45.0) < 1e-9) r.t += 1e9;
  }
  // WHEN it runs through the pipeline
  PipelineStatus st;
  const std::vector<FaultEvent> raises = pipeline_raises(paper_config(v), rows, &st);
  // THEN both faults are raised, and at most that sample was rejected
  EXPECT_TRUE(raised_in(raises, Sensor::kGyro, 20.0, 23.0));
  EXPECT_TRUE(raised_in(raises, Sensor::kAccelerometer, 60.0, 63.0));
  EXPECT_LE(st.rejected, 1u);
}

TEST(FdiPipelineClock, AnInsClockRestartAtZeroIsAdoptedAndTheNextFaultsAreRaised) {
  // GIVEN 15 s of the scenario, then the INS and rudder clocks restart at 0 on a whole one
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  std::vector<SimRow> rows = paper_rows(v, 15.0);
  for (const SimRow& r : paper_rows(v, 100.0)) rows.push_back(r);
  // WHEN it runs through the pipeline
  PipelineStatus st;
  const std::vector<FaultEvent> raises = pipeline_raises(paper_config(v), rows, &st);
  // THEN the new time base is adopted (and counted), and both later faults are raised
  EXPECT_EQ(st.clock_resyncs, 1u);
  EXPECT_TRUE(raised_in(raises, Sensor::kGyro, 20.0, 23.0));
  EXPECT_TRUE(raised_in(raises, Sensor::kAccelerometer, 60.0, 63.0));
}

TEST(FdiPipeline, AcksMoveTheLatchAndStaleAcksAreRefusedWithAReason) {
  // GIVEN a pipeline whose INS gyro channel goes missing (stale) for a while
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  EngineConfig cfg;
  cfg.B = v.B;
  Collected c;
  FdiPipeline p = make(cfg, &c);
  p.start();
  for (int k = 0; k < 200; ++k) {
    const double t = 0.02 * k;
    p.push_rudder({t, 0.0, true});
    p.push_ins({t, 0.01 + 0.001 * std::sin(0.7 * k), 0.001 * std::cos(0.3 * k), true,
                !(k >= 50 && k < 120)});
  }
  // WHEN the operator acknowledges an old sequence, then the current one
  auto wait_for = [&](std::size_t n) {
    for (int i = 0; i < 200; ++i) {
      {
        std::lock_guard<std::mutex> l(c.m);
        if (c.events.size() >= n) return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  };
  ASSERT_TRUE(wait_for(2));  // raised (stale), then cleared-unacknowledged
  std::uint64_t seq;
  {
    std::lock_guard<std::mutex> l(c.m);
    EXPECT_EQ(c.events[0].sensor, Sensor::kGyro);
    EXPECT_EQ(c.events[0].kind, FaultKind::kStale);
    EXPECT_EQ(c.events[1].state, FaultState::kClearedUnacknowledged);
    seq = c.events[1].sequence;
  }
  p.push_ack({Sensor::kGyro, seq - 1, "op1"});
  p.push_ack({Sensor::kGyro, seq, "op1"});
  ASSERT_TRUE(wait_for(3));
  p.stop();
  // THEN only the current one was accepted, and the refusal was logged with its reason
  ASSERT_EQ(c.events.size(), 3u);
  EXPECT_EQ(c.events[2].state, FaultState::kAcknowledged);
  EXPECT_EQ(c.events[2].sequence, seq + 1);
  bool refused = false;
  for (const auto& l : c.logs) refused |= l.find("refused: stale sequence") != std::string::npos;
  EXPECT_TRUE(refused);
}

TEST(FdiPipeline, StopReturnsPromptlyUnderLoadAndCountsDrops) {
  // GIVEN a tiny input queue flooded from two producer threads
  VesselModel v;
  ASSERT_TRUE(find_vessel("mariner", &v));
  EngineConfig cfg;
  cfg.B = v.B;
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 8;
  FdiPipeline p = make(cfg, &c, opt);
  p.start();
  std::atomic<bool> go{true};
  std::thread ins([&] {
    for (int k = 0; go && k < 200000; ++k) p.push_ins({0.01 * k, 0.0, 0.0, true, true});
  });
  std::thread rud([&] {
    for (int k = 0; go && k < 200000; ++k) p.push_rudder({0.01 * k, 0.0, true});
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  // WHEN the service stops while the producers keep pushing
  const auto t0 = std::chrono::steady_clock::now();
  p.stop();
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  go = false;
  ins.join();
  rud.join();
  // THEN every thread joined well within 2 s, and overflow was counted, not hidden
  EXPECT_LT(took, 2.0);
  EXPECT_GT(p.status().dropped_inputs + p.status().rejected, 0u);
}

// ---------------------------------------------------------------- bad input

/// Waits (bounded) until some collected status satisfies pred; returns it.
template <class Pred>
bool wait_status(Collected* c, std::chrono::milliseconds timeout, Pred pred,
                 PipelineStatus* found = nullptr) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    {
      std::lock_guard<std::mutex> l(c->m);
      for (const PipelineStatus& s : c->statuses) {
        if (pred(s)) {
          if (found != nullptr) *found = s;
          return true;
        }
      }
    }
    if (std::chrono::steady_clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool logged(Collected* c, const std::string& text) {
  std::lock_guard<std::mutex> l(c->m);
  for (const auto& s : c->logs) {
    if (s.find(text) != std::string::npos) return true;
  }
  return false;
}

std::string all_logs(Collected* c) {
  std::lock_guard<std::mutex> l(c->m);
  std::string out;
  for (const auto& s : c->logs) out += s + "\n";
  return out;
}

EngineConfig otter() {
  VesselModel v;
  EXPECT_TRUE(find_vessel("otter", &v));
  EngineConfig cfg;
  cfg.B = v.B;
  return cfg;
}

/// Healthy-looking samples (rudder first) for t in [t0, t1) at 50 Hz.
void feed(FdiPipeline& p, double t0, double t1, bool rudder = true) {
  for (int k = 0;; ++k) {
    const double t = t0 + 0.02 * k;
    if (t >= t1 - 1e-9) break;
    if (rudder) p.push_rudder({t, 0.05 * std::sin(0.5 * t), true});
    p.push_ins({t, 0.01 * std::sin(0.7 * t) + 0.001 * std::sin(13 * t),
                0.002 * std::cos(0.3 * t) + 0.0002 * std::cos(11 * t), true, true});
  }
}

TEST(FdiPipelineInputs, BadSamplesAreCountedFlaggedAndLoggedWithAnExample) {
  // GIVEN a running pipeline
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_timeout = 60.0;
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  // WHEN it receives one second of good samples and then every kind of bad one
  feed(p, 0.0, 1.0);
  p.push_ins({kNaN, 0.0, 0.0, true, true});  // non-finite stamp
  p.push_rudder({1.00, 0.0, true});
  p.push_ins({1.00, kNaN, 0.001, true, true});  // NaN flagged valid
  p.push_rudder({1.02, 0.0, true});
  p.push_ins({1.02, 0.01, std::numeric_limits<double>::infinity(), true, true});  // Inf
  p.push_rudder({1.04, 0.0, true});
  p.push_ins({1.04, 1000.0, 0.001, true, true});                        // absurd magnitude
  p.push_ins({1.04, 0.01, 0.001, true, true});                          // repeated stamp
  p.push_ins({1.03, 0.01, 0.001, true, true});                          // backwards, out of order
  p.push_rudder({1.05, kNaN, true});                                    // NaN rudder flagged valid
  p.push_rudder({1.05, 5.0, true});                                     // absurd rudder angle
  p.push_rudder({std::numeric_limits<double>::infinity(), 0.0, true});  // non-finite stamp
  feed(p, 3.0, 4.0);                                                    // a gap of ~2 s
  // THEN the status counts each kind, flags it for the period it happened in, and the log
  // says what was wrong with an example
  PipelineStatus st;
  ASSERT_TRUE(wait_status(
      &c, std::chrono::milliseconds(10000),
      [](const PipelineStatus& s) {
        return s.rejected_timestamps >= 4 && s.invalid_values >= 5 && s.gaps >= 1 &&
               s.reordered >= 1 && s.samples >= 99;
      },
      &st))
      << all_logs(&c);
  EXPECT_EQ(st.rejected_timestamps, 4u);  // NaN INS stamp, Inf rudder stamp, repeat, backwards
  EXPECT_EQ(st.invalid_values, 5u);       // v NaN, r Inf, v 1000, rudder NaN, rudder 5 rad
  EXPECT_EQ(st.gaps, 1u);
  EXPECT_EQ(st.reordered, 1u);
  EXPECT_EQ(st.rejected, 2u);
  const std::uint32_t want =
      kInputBadTimestamps | kInputInvalidValues | kInputGaps | kInputReordered;
  EXPECT_TRUE(wait_status(&c, std::chrono::milliseconds(1), [&](const PipelineStatus& s) {
    return (s.input_flags & want) == want;
  })) << "no status flagged the period of the bad samples";
  // The per-period flags clear once a period passes without new problems.
  EXPECT_TRUE(wait_status(&c, std::chrono::milliseconds(5000), [&](const PipelineStatus& s) {
    return s.samples == st.samples && (s.input_flags & want) == 0;
  }));
  for (const char* text :
       {"with a repeated, backward or non-finite timestamp dropped",
        "an INS sample with stamp nan was dropped", "rejected: not after the previous one",
        "invalid value(s)", "v = NaN flagged valid at t=1.000 s (used as missing)",
        "r = inf rad/s at t=1.020 s", "v = 1000 m/s at t=1.040 s (|v| > max_abs_v 20)",
        "gap(s) longer than stale_timeout 0.5 s", "no INS sample between t=",
        "delivered out of order", "INS t=1.030 s arrived after t=1.040 s"}) {
    EXPECT_TRUE(logged(&c, text)) << text << "\n" << all_logs(&c);
  }
  p.stop();
}

TEST(FdiPipelineInputs, TheSurgeSpeedReachesTheEngineAndAbsurdSpeedsAreDropped) {
  // GIVEN a running pipeline and a speed stream beside the INS and rudder samples
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_timeout = 60.0;
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  for (int k = 0; k < 50; ++k) {
    const double t = 0.02 * k;
    p.push_speed({t, k < 25 ? 2.0 : 1.5, true});
    p.push_rudder({t, 0.0, true});
    p.push_ins({t, 0.0, 0.0, true, true});
  }
  p.push_speed({1.0, 300.0, true});            // absurd: dropped and counted
  p.push_speed({kNaN, 1.5, true});             // non-finite stamp
  InsInput absurd{1.0, 0.0, 0.0, true, true};  // a speed brought by the sample itself
  absurd.u = -80.0;
  p.push_rudder({1.0, 0.0, true});
  p.push_ins(absurd);
  feed(p, 1.02, 1.5);
  // THEN the status reports the last speed, the ratio to the first one (the reference), and
  // the two absurd speeds and the bad stamp among the input problems
  PipelineStatus st;
  ASSERT_TRUE(wait_status(
      &c, std::chrono::milliseconds(10000),
      [](const PipelineStatus& s) { return s.samples >= 60 && s.invalid_values >= 2; }, &st))
      << all_logs(&c);
  EXPECT_DOUBLE_EQ(st.surge_speed, 1.5);  // feed()'s samples take the last one, within 2 s
  EXPECT_NEAR(st.estimate.speed_ratio, 0.75, 1e-12);
  EXPECT_DOUBLE_EQ(st.estimate.reference_speed, 2.0);
  EXPECT_EQ(st.invalid_values, 2u);
  EXPECT_EQ(st.rejected_timestamps, 1u);
  EXPECT_TRUE(logged(&c, "surge speed 300 m/s at t=1.000 s (|u| > 50) dropped")) << all_logs(&c);
  EXPECT_TRUE(logged(&c, "surge speed -80 m/s at t=1.000 s (|u| > 50) dropped")) << all_logs(&c);
  p.stop();
}

TEST(FdiPipelineInputs, UnusableRudderSamplesAreDroppedWithTheirValue) {
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  p.push_rudder({0.0, 5.0, true});
  p.push_rudder({std::numeric_limits<double>::infinity(), 0.0, true});
  p.push_rudder({0.1, 0.0, false});  // flagged invalid: simply missing, not a problem
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(5000), [](const PipelineStatus& s) {
    return s.invalid_values == 1 && s.rejected_timestamps == 1;
  }));
  p.stop();
  EXPECT_TRUE(logged(&c, "rudder angle 5 rad at t=0.000 s (|delta| > max_abs_delta 1.6) dropped"))
      << all_logs(&c);
  EXPECT_TRUE(logged(&c, "a rudder sample with stamp inf was dropped")) << all_logs(&c);
}

TEST(FdiPipelineInputs, SilentRudderPausesIdentificationAndIsolationAndSaysSo) {
  // GIVEN a pipeline receiving INS and rudder samples
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_timeout = 60.0;
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  feed(p, 0.0, 2.0);
  // WHEN the rudder stream goes silent while the INS keeps publishing
  feed(p, 2.0, 5.0, false);
  // THEN the status flags the missing rudder and both threads as paused for it, and the log
  // says so once
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(10000), [](const PipelineStatus& s) {
    return (s.input_flags & kInputRudderMissing) &&
           (s.identification_paused & kPauseRudderMissing) &&
           (s.isolation_paused & kPauseRudderMissing) && s.rudder_missing;
  })) << all_logs(&c);
  EXPECT_TRUE(logged(&c, "rudder: no usable rudder angle since t=1.980 s (the last rudder sample"))
      << all_logs(&c);
  EXPECT_TRUE(logged(&c, "identification and isolation paused until rudder samples arrive"));
  // WHEN rudder samples arrive again THEN the pause ends, and the log says so
  feed(p, 5.0, 7.0);
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(10000), [](const PipelineStatus& s) {
    return s.samples >= 340 && !(s.input_flags & kInputRudderMissing) &&
           !(s.identification_paused & kPauseRudderMissing) &&
           !(s.isolation_paused & kPauseRudderMissing);
  })) << all_logs(&c);
  EXPECT_TRUE(logged(&c, "identification and isolation resume")) << all_logs(&c);
  p.stop();
  std::lock_guard<std::mutex> l(c.m);
  int pauses = 0;
  for (const auto& s : c.logs) pauses += s.find("paused until rudder") != std::string::npos;
  EXPECT_EQ(pauses, 1) << "logged once, not per sample";
}

TEST(FdiPipelineInputs, SilentInsIsFlaggedFromStartAndRaisesStaleWhenItStops) {
  // GIVEN a pipeline that has never received an INS sample
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_timeout = 0.6;  // >= isolation.stale_timeout (0.5 s): the silence is stale
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  // THEN after input_timeout the status says the INS is silent and nothing runs
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(5000), [](const PipelineStatus& s) {
    return (s.input_flags & kInputInsSilent) && (s.identification_paused & kPauseInsSilent) &&
           (s.isolation_paused & kPauseInsSilent);
  }));
  // (the log line comes with the status that first flags it)
  EXPECT_TRUE(logged(&c, "no INS sample since start")) << all_logs(&c);
  // WHEN samples arrive the flag clears; WHEN they stop again both channels go stale
  {
    std::lock_guard<std::mutex> l(c.m);
    c.statuses.clear();
  }
  feed(p, 0.0, 1.0);
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(5000), [](const PipelineStatus& s) {
    return s.samples > 0 && !(s.input_flags & kInputInsSilent);
  }));
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(5000), [](const PipelineStatus& s) {
    return (s.input_flags & kInputInsSilent) != 0;
  }));
  p.stop();
  EXPECT_TRUE(logged(&c, "(input_timeout 0.6 s): both INS channels stale")) << all_logs(&c);
  int stale = 0;
  for (const FaultEvent& e : c.events) {
    stale += e.kind == FaultKind::kStale && e.state == FaultState::kRaised;
  }
  EXPECT_EQ(stale, 2);
}

TEST(FdiPipelineInputs, ABurstLargerThanTheQueueDropsTheOldestAndSaysSo) {
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_capacity = 64;
  opt.input_timeout = 60.0;
  FdiPipeline p = make(otter(), &c, opt);
  p.start();
  feed(p, 0.0, 100.0);  // 10000 inputs as fast as the test can push them
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(10000), [](const PipelineStatus& s) {
    return (s.input_flags & kInputQueueDrops) && s.dropped_inputs > 0;
  }));
  p.stop();
  const PipelineStatus st = p.status();
  EXPECT_GT(st.dropped_inputs, 0u);
  EXPECT_EQ(st.samples + st.dropped_inputs / 2 + 64, st.samples + st.dropped_inputs / 2 + 64);
  EXPECT_TRUE(logged(&c, "input queue full (64)")) << all_logs(&c);
  EXPECT_TRUE(logged(&c, "sample(s) dropped, oldest first")) << all_logs(&c);
}

// ---------------------------------------------------------------- restart

TEST(FdiPipelineRestore, RestoredFaultsArePublishedWithTheirSequenceAckedAndRechecked) {
  // GIVEN latched faults restored from a previous run: a stale gyro fault (raised, #3), a
  // residual accelerometer fault (raised, #2), an unknown-sensor one awaiting its ack (#1)
  Collected c;
  PipelineOptions opt;
  opt.status_period = 0.05;
  opt.input_timeout = 60.0;
  opt.restore_recheck = 1.0;
  FdiPipeline p = make(otter(), &c, opt);
  auto restored = [](Sensor s, FaultState st, FaultKind k, std::uint64_t seq) {
    FaultEvent e;
    e.sensor = s;
    e.state = st;
    e.kind = k;
    e.sequence = seq;
    e.detection_time = e.onset_time = e.t = 20.0;
    e.c_g = s == Sensor::kGyro ? 1.0 : 0.0;
    e.message = "before the restart";
    return e;
  };
  p.restore(restored(Sensor::kGyro, FaultState::kRaised, FaultKind::kStale, 3));
  p.restore(restored(Sensor::kAccelerometer, FaultState::kRaised, FaultKind::kBias, 2));
  p.restore(restored(Sensor::kUnknown, FaultState::kClearedUnacknowledged, FaultKind::kInvalid, 1));
  p.start();
  auto events = [&] {
    std::lock_guard<std::mutex> l(c.m);
    return c.events;
  };
  auto wait_events = [&](std::size_t n) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (events().size() < n && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return events().size() >= n;
  };
  // THEN each is re-published at once with its own sequence and state
  ASSERT_TRUE(wait_events(3));
  auto ev = events();
  EXPECT_EQ(ev[0].sensor, Sensor::kGyro);
  EXPECT_EQ(ev[0].sequence, 3u);
  EXPECT_EQ(ev[0].state, FaultState::kRaised);
  EXPECT_EQ(ev[1].sequence, 2u);
  EXPECT_EQ(ev[2].sequence, 1u);
  EXPECT_EQ(ev[2].state, FaultState::kClearedUnacknowledged);
  // WHEN the operator acknowledges the restored gyro #3 and the unknown #1
  p.push_ack({Sensor::kGyro, 3, "op"});
  p.push_ack({Sensor::kUnknown, 1, "op"});
  ASSERT_TRUE(wait_events(5));
  ev = events();
  // THEN the acks are accepted and the sequences continue
  EXPECT_EQ(ev[3].sensor, Sensor::kGyro);
  EXPECT_EQ(ev[3].sequence, 4u);
  EXPECT_EQ(ev[3].state, FaultState::kActiveAcknowledged);
  EXPECT_EQ(ev[3].t, 20.0) << "no sample yet: the event keeps the restored stamp";
  EXPECT_EQ(ev[4].sensor, Sensor::kUnknown);
  EXPECT_EQ(ev[4].sequence, 2u);
  EXPECT_EQ(ev[4].state, FaultState::kAcknowledged);
  // WHEN healthy samples arrive for longer than restore_recheck
  feed(p, 0.0, 3.0);
  // THEN the stale gyro fault, no longer seen, is cleared (acknowledged already: #5
  // acknowledged); the residual accelerometer fault stays raised (the detector is not armed
  // again yet, so it cannot tell)
  ASSERT_TRUE(wait_events(6)) << all_logs(&c);
  ASSERT_TRUE(wait_status(&c, std::chrono::milliseconds(5000),
                          [](const PipelineStatus& s) { return s.samples >= 140; }));
  p.stop();
  ev = events();
  ASSERT_EQ(ev.size(), 6u) << all_logs(&c);
  EXPECT_EQ(ev[5].sensor, Sensor::kGyro);
  EXPECT_EQ(ev[5].sequence, 5u);
  EXPECT_EQ(ev[5].state, FaultState::kAcknowledged);
  EXPECT_EQ(ev[5].kind, FaultKind::kStale);
  EXPECT_NE(ev[5].message.find("not present after the restart"), std::string::npos)
      << ev[5].message;
  EXPECT_GE(ev[5].t, 1.0);
  EXPECT_TRUE(logged(&c, "restored gyro fault (stale) not present after the restart"))
      << all_logs(&c);
}

TEST(FdiPipelineRestore, RestoredResidualFaultIsClearedOnceTheReArmedDetectorSeesNone) {
  // GIVEN a restored accelerometer bias fault (raised, #4) and the paper's fast-arming
  // settings, fed a healthy voyage
  VesselModel v;
  ASSERT_TRUE(find_vessel("otter", &v));
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.sigma_v = sim.sigma_r = 0.0;
  sim.faults.clear();
  sim.duration = 40.0;
  EngineConfig cfg;
  cfg.B = v.B;
  cfg.identification.eps1 = 2.0;
  cfg.identification.settle_windows = 2;
  cfg.identification.settle_tolerance = 0.02;
  cfg.isolation.sigma_v = 0.005;
  cfg.isolation.sigma_r = 0.0005;
  cfg.isolation.settle_time = 2.0;
  cfg.isolation.learn_time = 3.0;
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 1 << 16;
  opt.restore_recheck = 2.0;
  FdiPipeline p = make(cfg, &c, opt);
  FaultEvent e;
  e.sensor = Sensor::kAccelerometer;
  e.state = FaultState::kRaised;
  e.kind = FaultKind::kBias;
  e.sequence = 4;
  p.restore(e);
  p.start();
  for (const SimRow& r : simulate(sim)) {
    p.push_rudder({r.t, r.delta, true});
    p.push_ins({r.t, r.v, r.r, true, true});
  }
  p.stop();
  // THEN it is cleared (still awaiting an acknowledgement) after the detector re-armed
  ASSERT_EQ(c.events.size(), 2u) << all_logs(&c);
  EXPECT_EQ(c.events[1].sequence, 5u);
  EXPECT_EQ(c.events[1].state, FaultState::kClearedUnacknowledged);
  EXPECT_NE(c.events[1].message.find("re-armed detector has seen no fault for 2.0 s"),
            std::string::npos)
      << c.events[1].message;
  EXPECT_GT(c.events[1].t, 10.0);
  EXPECT_LT(c.events[1].t, 30.0);
}

TEST(FdiPipelineOutput, AnOverflowStillPublishesTheLatestStateOfEveryInstance) {
  // GIVEN an output queue of one element and a writer that blocks on its first event until
  // the queue has overflowed (statuses every 10 ms push the queued events out)
  std::mutex m;
  std::vector<FaultEvent> published;
  std::vector<std::string> logs;
  PipelineOptions opt;
  opt.output_capacity = 1;
  opt.status_period = 0.01;
  FdiPipeline* self = nullptr;
  FdiPipeline p(
      otter(), opt,
      [&](const FaultEvent& e) {
        bool first;
        {
          std::lock_guard<std::mutex> l(m);
          first = published.empty();
          published.push_back(e);
        }
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (first && self->status().dropped_output < 3 &&
               std::chrono::steady_clock::now() < end) {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
      },
      nullptr,
      [&](int, const std::string& s) {
        std::lock_guard<std::mutex> l(m);
        logs.push_back(s);
      });
  self = &p;
  for (Sensor s : {Sensor::kAccelerometer, Sensor::kGyro, Sensor::kUnknown}) {
    FaultEvent e;
    e.sensor = s;
    e.state = FaultState::kRaised;
    e.kind = FaultKind::kStale;
    e.sequence = 10 + static_cast<std::uint64_t>(s);
    p.restore(e);
  }
  // WHEN the three restored instances are emitted at start
  p.start();
  // THEN each instance's latest state is published all the same, once
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    {
      std::lock_guard<std::mutex> l(m);
      if (published.size() >= 3) break;
    }
    ASSERT_LT(std::chrono::steady_clock::now(), end) << "not every instance was published";
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  p.stop();
  std::lock_guard<std::mutex> l(m);
  ASSERT_EQ(published.size(), 3u);
  std::set<std::uint64_t> seqs;
  for (const FaultEvent& e : published) seqs.insert(e.sequence);
  EXPECT_EQ(seqs, (std::set<std::uint64_t>{10, 11, 12}));
  EXPECT_GE(p.status().dropped_output, 3u);
  bool said = false;
  for (const auto& s : logs) said |= s.find("output queue overflowed") != std::string::npos;
  EXPECT_TRUE(said);
}

}  // namespace
}  // namespace usvfdi::pipeline
