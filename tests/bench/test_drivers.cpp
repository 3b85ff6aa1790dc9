// The benchmark's detectors on a short simulated run: the oracle (the isolation stage handed
// the true A) arms after settling and learning and raises an injected gyro bias at once, on
// the gyro; raises and clears come out as alarm condition changes in time order.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <optional>
#include <string>

#include "drivers.hpp"
#include "runner.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"

namespace usvfdi::bench {
namespace {

std::vector<Sample> otter_run(bool fault) {
  SimConfig c;
  c.vessel = otter();
  c.rate_hz = 50.0;
  c.duration = 200.0;
  c.seed = 5;
  if (fault) {
    FaultInjection f;
    f.sensor = Sensor::kGyro;
    f.kind = FaultKind::kBias;
    f.t_start = 120.0;
    f.t_end = 150.0;
    f.magnitude = 10.0 * otter().sigma_r;
    c.faults.push_back(f);
  }
  std::vector<Sample> out;
  for (const SimRow& r : simulate(c)) out.push_back(Sample{r.t, r.v, r.r, r.delta});
  return out;
}

TEST(BenchDrivers, TheOracleArmsAfterLearningAndRaisesTheGyroBias) {
  const IsolationParams p;
  const MethodResult r = run_oracle(p, otter().B, otter().A, otter_run(true));
  // Settling 3 / 0.5 s = 6 s and learning 60 s after the first sample.
  EXPECT_GT(r.t_armed, 60.0);
  EXPECT_LT(r.t_armed, 75.0);
  ASSERT_FALSE(r.alarms.empty());
  const Alarm& first = r.alarms.front();
  EXPECT_TRUE(first.raised);
  EXPECT_EQ(first.sensor, Sensor::kGyro);
  EXPECT_GE(first.t, 120.0);
  EXPECT_LT(first.t, 121.0);
  // Cleared after the fault ended; conditions alternate per sensor, in time order.
  bool cleared = false;
  for (std::size_t k = 0; k < r.alarms.size(); ++k) {
    if (k > 0) {
      EXPECT_GE(r.alarms[k].t, r.alarms[k - 1].t);
    }
    if (r.alarms[k].sensor == Sensor::kGyro && !r.alarms[k].raised) cleared = r.alarms[k].t > 150;
  }
  EXPECT_TRUE(cleared);
  EXPECT_EQ(r.A_final, otter().A);
}

TEST(BenchDrivers, HealthyDataRaiseNothingOnTheOracle) {
  const IsolationParams p;
  const MethodResult r = run_oracle(p, otter().B, otter().A, otter_run(false));
  EXPECT_TRUE(r.alarms.empty());
  EXPECT_TRUE(std::isfinite(r.t_armed));
}

TEST(BenchDrivers, TheEngineReportsItsEstimateAndArming) {
  EngineConfig cfg;
  cfg.B = otter().B;
  const MethodResult r = run_engine(cfg, otter_run(false));
  EXPECT_TRUE(r.A_final.allFinite());
  // Arming, when it happens, needs a converged estimate (sticky) and comes after the
  // isolation stage's own settling and learning.
  if (std::isfinite(r.t_armed)) {
    EXPECT_TRUE(r.converged);
    EXPECT_GT(r.t_armed, 66.0);
  }
}

/// The proving ground's run of that table, voyage, seed and kind, as the full mode of
/// `usv-fdi-bench-detection` builds it, and the shipped engine configuration with its B (what
/// a user gives); none when the proving ground no longer has it.
std::optional<Case> proving_ground_run(const std::string& table, const std::string& voyage,
                                       std::uint64_t seed, bool faulty, EngineConfig* engine_cfg) {
  BenchOptions opt;
  opt.config_dir = std::string(USV_FDI_SOURCE_DIR) + "/config";
  EngineConfig paper_cfg;
  load_configs(opt.config_dir, engine_cfg, &paper_cfg);
  for (const Case& c : make_cases(opt)) {
    if (c.table == table && c.voyage == voyage && c.seed == seed && c.faulty == faulty) {
      engine_cfg->B = c.B;
      return c;
    }
  }
  return std::nullopt;
}

/// Every raise of the engine's run is a failure (the run is healthy).
void expect_no_raise(const MethodResult& r) {
  for (const Alarm& a : r.alarms) {
    if (a.raised) ADD_FAILURE() << "raised " << to_string(a.sensor) << " at " << a.t << " s";
  }
}

// Issue 11, item 7, end to end: an estimate that loses convergence un-arms detection, which
// arms again once the estimate converges again, and then finds the fault; the benchmark
// scores only the live spans as armed.
TEST(BenchDrivers, TheEngineUnarmsWhenItsEstimateLosesConvergenceAndArmsAgain) {
  // GIVEN a proving-ground run (the Mariner, 50 Hz, calm course changes) whose estimate
  // converges, loses convergence and converges again before the injected fault (a gyro bias
  // from 1121 s; at stop 49 live 307-623 s and from 952 s)
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run("mariner @ 50 Hz", "course/calm",
                                                      10203985545584359410ull, true, &engine_cfg);
  ASSERT_TRUE(pick) << "the proving ground no longer has this run";
  const Stream data = pick->make();
  const MethodResult r = run_engine(engine_cfg, data.samples);
  for (const LiveSpan& l : r.live) {
    std::cout << "[ INFO     ] live from " << l.from << " s to " << l.to << " s\n";
  }
  std::cout << "[ INFO     ] " << to_string(pick->fault.sensor) << " "
            << to_string(pick->fault.kind) << " from " << pick->fault.t_start << " s\n";
  // THEN detection was live, went off (an un-arm) and came back before the fault
  ASSERT_GE(r.live.size(), 2u);
  EXPECT_GE(r.unarms, 1u);
  EXPECT_EQ(r.t_armed, r.live.front().from);
  EXPECT_LT(r.live.front().to, r.live[1].from);
  EXPECT_FALSE(live_at(r.live, (r.live.front().to + r.live[1].from) / 2));
  EXPECT_LT(r.live.back().from, pick->fault.t_start);
  EXPECT_TRUE(std::isinf(r.live.back().to));
  // AND the fault is found on its sensor at once, nothing else is raised, and the score
  // counts it armed at its onset
  const RunScore score =
      score_run(data.faults, r.alarms, data.samples.front().t, data.samples.back().t, r.live);
  ASSERT_EQ(score.faults.size(), 1u);
  EXPECT_TRUE(score.faults[0].armed_at_onset);
  EXPECT_TRUE(score.faults[0].detected);
  EXPECT_TRUE(score.faults[0].isolated);
  EXPECT_LT(score.faults[0].delay, 2.0);
  EXPECT_EQ(score.false_alarms(), 0u);
  // AND the healthy time counted as armed leaves out the span it was off
  EXPECT_LT(score.healthy_armed_time,
            data.samples.back().t - r.t_armed - (r.live[1].from - r.live.front().to) + 1e-6);
}

TEST(BenchDrivers, AResidualAboveItsBarWhenDetectionGoesLiveIsNotRaised) {
  // GIVEN a proving-ground run (the Otter, 10 Hz, sea state 3) that arms at 901 s in the
  // middle of a +-20 deg zigzag the linear model does not hold: the gyro's J_N has been pegged
  // at clip^2 since 881 s, above its bar from the first live sample on, and falls at 907.9 s
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run("otter @ 10 Hz", "voyage/sea3/mems",
                                                      14519301653455217402ull, true, &engine_cfg);
  ASSERT_TRUE(pick) << "the proving ground no longer has this run";
  const Stream data = pick->make();
  const MethodResult r = run_engine(engine_cfg, data.samples);
  ASSERT_TRUE(std::isfinite(r.t_armed));
  ASSERT_GT(r.t_armed, 895.0);
  ASSERT_LT(r.t_armed, 904.0);
  // THEN nothing is raised before the injected fault (an accelerometer scale error from 975 s):
  // the rise began before detection went live, so it is not a sensor's onset (up to stop 43
  // the gyro was raised at 904.8 s, 1.5 enter_time after arming, and cleared 3 s later)
  for (const Alarm& a : r.alarms) {
    if (a.raised && a.t < pick->fault.t_start) {
      ADD_FAILURE() << "raised " << to_string(a.sensor) << " at " << a.t << " s";
    }
  }
  // AND the status says why. The gyro's bar, learned on J_N that sat at the clip for the last
  // 20 s of learning, had to be capped: the shipped configuration closes the channel
  // (bar_unreachable from the first live sample). With capped bars left standing the gyro
  // awaits its onset from the first live sample until its J_N falls (907.9 s). The
  // accelerometer, below its bar, does neither.
  for (const bool close : {true, false}) {
    SCOPED_TRACE(close ? "capped bars close" : "capped bars stand");
    EngineConfig cfg = engine_cfg;
    cfg.isolation.close_capped_bars = close;
    FdiEngine engine(cfg);
    std::vector<FaultEvent> events;
    double first = kNaN, last = kNaN, closed_from = kNaN;
    bool accelerometer = false;
    for (const Sample& s : data.samples) {
      if (s.t > 960.0) break;
      events.clear();
      engine.process(s, &events);
      const IsolatorStatus& st = engine.isolation_status();
      if (st.awaiting_onset[1]) {
        if (std::isnan(first)) first = s.t;
        last = s.t;
      }
      if (st.bar_unreachable[1] && std::isnan(closed_from)) closed_from = s.t;
      accelerometer = accelerometer || st.awaiting_onset[0];
    }
    EXPECT_FALSE(accelerometer);
    if (close) {
      EXPECT_TRUE(std::isnan(first)) << "awaiting its onset at " << first << " s";
      ASSERT_TRUE(std::isfinite(closed_from));
      EXPECT_NEAR(closed_from, r.t_armed, 0.5);
      continue;
    }
    EXPECT_FALSE(closed_from < first + 1.0) << "closed at " << closed_from << " s";
    ASSERT_TRUE(std::isfinite(first));
    EXPECT_NEAR(first, r.t_armed, 0.5);
    EXPECT_GT(last, 905.0);
    EXPECT_LT(last, 909.0);
  }
}

TEST(BenchDrivers, ABiasTheJumpCheckRaisedIsNotShownRectifiedBeforeHoldMax) {
  // GIVEN a proving-ground run (Esso Osaka, 50 Hz, calm course changes) with a 10 sigma
  // accelerometer bias on [1106.1, 1166.1) s, raised by the jump check once the observers are
  // live. Up to stop 30 the observers alone held it and showed it rectified 3 s after its
  // raise (5 % of its time shown).
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run("esso-tanker @ 50 Hz", "course/calm",
                                                      12323007886022702073ull, true, &engine_cfg);
  ASSERT_TRUE(pick) << "the proving ground no longer has this run";
  ASSERT_EQ(pick->fault.sensor, Sensor::kAccelerometer);
  ASSERT_EQ(pick->fault.kind, FaultKind::kBias);
  const Stream data = pick->make();
  const MethodResult r = run_engine(engine_cfg, data.samples);
  ASSERT_TRUE(std::isfinite(r.t_armed));
  ASSERT_LT(r.t_armed, pick->fault.t_start);
  // THEN the accelerometer is raised within a second of the onset, and the jump check holds
  // it with the observers: it is not shown rectified before jump.hold_max has passed (there
  // is no jump back within it)
  double raised = kNaN, cleared = kNaN;
  for (const Alarm& a : r.alarms) {
    if (a.sensor != Sensor::kAccelerometer || a.t < pick->fault.t_start) continue;
    if (a.raised && std::isnan(raised)) raised = a.t;
    if (!a.raised && std::isfinite(raised) && std::isnan(cleared)) cleared = a.t;
  }
  ASSERT_TRUE(std::isfinite(raised));
  EXPECT_LT(raised, pick->fault.t_start + 1.0);
  ASSERT_LT(raised + engine_cfg.isolation.jump.hold_max, pick->fault.t_end);
  if (std::isfinite(cleared)) {
    EXPECT_GE(cleared + 1e-9, raised + engine_cfg.isolation.jump.hold_max)
        << "shown rectified while the bias was still there";
  }
}

TEST(BenchDrivers, ShortResidualRisesOfAManoeuvringHullInWavesRaiseNothing) {
  // GIVEN a healthy proving-ground run (Mariner, 10 Hz, 4 h of every manoeuvre in sea state 3
  // with MEMS-grade sensors) on which the observers, confirming a raise over 2 s, raised 18
  // false accelerometer faults after 13 100 s, each of the residual's rises lasting little
  // more than the confirmation
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run("mariner @ 10 Hz", "voyage/sea3/mems",
                                                      13566731111258911605ull, false, &engine_cfg);
  ASSERT_TRUE(pick) << "the proving ground no longer has this run";
  const Stream data = pick->make();
  // WHEN the engine with the shipped configuration replays it
  const MethodResult r = run_engine(engine_cfg, data.samples);
  // THEN it raises nothing (isolation.enter_time 2.5 s)
  expect_no_raise(r);
}

TEST(BenchDrivers, TheFirstZigzagExecuteOfAFastHullIsNoGyroJump) {
  // GIVEN a healthy proving-ground run of a hull whose yaw rate answers the rudder within a
  // quarter of a second (the nonlinear Otter, 50 Hz, sea state 3, MEMS-grade sensors): two
  // minutes of course changes, then the first 10 deg zigzag at 120 s. Its rudder swing bends
  // z = r - b int(delta) by a_row B int int(delta), more than anything the jump check learned
  // before and not yet seen before the onset; up to stop 34 the jump check raised a gyro bias
  // at 121.4 s (in 35 of the table's 53 such runs) and again at 125 s, held for 30 s
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run("otter3dof @ 50 Hz", "voyage/sea3/mems",
                                                      15504103307926617233ull, false, &engine_cfg);
  ASSERT_TRUE(pick) << "the proving ground no longer has this run";
  Stream data = pick->make();
  // (its first 300 s: the zigzag and the speed changes' start)
  std::vector<Sample> first;
  for (const Sample& s : data.samples) {
    if (s.t <= 300.0) first.push_back(s);
  }
  // WHEN the engine with the shipped configuration replays it
  const MethodResult r = run_engine(engine_cfg, first);
  // THEN it raises nothing
  expect_no_raise(r);
}

/// The engine with the shipped configuration (as the proving ground runs it) on the healthy
/// first `until` seconds of a proving-ground run (one with a fault, which begins later).
MethodResult replay_healthy_start(const std::string& table, const std::string& voyage,
                                  std::uint64_t seed, double until, bool close_capped_bars = true) {
  EngineConfig engine_cfg;
  const std::optional<Case> pick = proving_ground_run(table, voyage, seed, true, &engine_cfg);
  engine_cfg.isolation.close_capped_bars = close_capped_bars;
  if (!pick) {
    ADD_FAILURE() << "the proving ground no longer has run " << seed;
    return {};
  }
  EXPECT_GT(pick->fault.t_start, until);
  const Stream data = pick->make();
  std::vector<Sample> first;
  for (const Sample& s : data.samples) {
    if (s.t <= until) first.push_back(s);
  }
  return run_engine(engine_cfg, first);
}

TEST(BenchDrivers, AGyroResidualThatComesBackAfterARaiseNothingHeldIsModelMismatch) {
  // GIVEN the healthy first 1400 s of two proving-ground runs of the nonlinear Otter (10 Hz,
  // sea state 3, MEMS-grade sensors) whose voyage slows to half throttle after 900 s: B,
  // given for full speed, overstates the rudder's effect about fourfold there, and the gyro
  // channel's structured residual keeps rising. Up to stop 36 each rise raised a gyro fault
  // that neither the cross residual nor the monitor held (cleared after min_active_time):
  // 9 false gyro faults from 967 to 1064 s in the first, rises 11-12 s apart, and 8 from 956
  // to 1074 s in the second (the rule without its chain left 4 there, the later ones 15-17 s
  // apart, each after a verdict had ended)
  for (const std::uint64_t seed : {8068231856934621647ull, 15453939662217126967ull}) {
    SCOPED_TRACE(seed);
    // WHEN the engine with the shipped configuration replays it up to 1400 s
    const MethodResult r = replay_healthy_start("otter @ 10 Hz", "voyage/sea3/mems", seed, 1400.0);
    // THEN the slow passage raises the gyro at most once; its rises after that are reported
    // as model mismatch, named so
    int gyro_raises = 0, repeats = 0, verdicts = 0;
    for (const Alarm& a : r.alarms) {
      gyro_raises += a.raised && a.sensor == Sensor::kGyro && a.t > 900.0;
    }
    for (const MismatchVerdict& m : r.mismatches) {
      if (m.t <= 900.0) continue;
      ++verdicts;
      repeats += m.reason.find("soon after a gyro raise that nothing held") != std::string::npos;
    }
    EXPECT_LE(gyro_raises, 1);
    EXPECT_GT(repeats, 0) << verdicts << " verdicts after 900 s";
  }
}

TEST(BenchDrivers, ACourseChangeJudgedTheModelsIsNotRaisedAgainAtTheNextOne) {
  // GIVEN the healthy first 900 s of a proving-ground run of the 3-DOF Otter (50 Hz, calm
  // water, +-10 deg course changes every 20 s; its gyro scale error begins at 975 s). Every
  // course change takes the gyro's J_N to the clip (16) for a moment, above its bar (12): up
  // to stop 38 that raised the gyro 16 times from 245 to 764 s. Each raise, and each
  // model-mismatch verdict on such a rise, kept the peak out of the healthy maxima the bar
  // follows, so the next course change met the same bar.
  // WHEN the engine replays it with a capped bar left standing (close_capped_bars false: the
  // shipped configuration closes this gyro channel, whose bar had to be capped, see below)
  const MethodResult r = replay_healthy_start("otter3dof @ 50 Hz", "course/calm",
                                              13365152606205054189ull, 900.0, false);
  // THEN once a rise has been judged the model's, the peaks it brought are part of the
  // healthy maxima and the course changes after it raise nothing
  ASSERT_FALSE(r.mismatches.empty());
  const double judged = r.mismatches.front().t;
  int raises = 0, after = 0;
  for (const Alarm& a : r.alarms) {
    if (!a.raised) continue;
    ++raises;
    after += a.t > judged;
  }
  EXPECT_EQ(after, 0) << "the first verdict at " << judged << " s";
  EXPECT_LE(raises, 5);
  // AND with the shipped configuration the gyro channel, whose healthy J_N went to the clip
  // while its first design learned, is closed: no course change raises it, none is judged
  const MethodResult shipped =
      replay_healthy_start("otter3dof @ 50 Hz", "course/calm", 13365152606205054189ull, 900.0);
  expect_no_raise(shipped);
  EXPECT_TRUE(shipped.mismatches.empty()) << "first verdict at " << shipped.mismatches.front().t;
  ASSERT_TRUE(std::isfinite(shipped.t_armed));
}

}  // namespace
}  // namespace usvfdi::bench
