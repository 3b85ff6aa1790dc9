// Threading tests of the service pipeline (no middleware): deterministic because the
// inputs carry source time and stop() drains every queue before joining.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/service/pipeline.hpp"

namespace usvfdi {
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
  Collected c;
  PipelineOptions opt;
  opt.input_capacity = 1 << 16;  // the test pushes faster than real time: no drops
  opt.lockstep = true;
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

}  // namespace
}  // namespace usvfdi
