// Seeded scenario tests (GIVEN/WHEN/THEN) on the shipped vessels, with the shipped configs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "scenario_util.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::scenario {
namespace {

const std::string kSource = USV_FDI_SOURCE_DIR;

EngineConfig vessel_config(const std::string& vessel) {
  return io::load_engine_config(kSource + "/config/vessels/" + vessel + ".yaml");
}

VesselModel vessel(const std::string& name) {
  VesselModel v;
  EXPECT_TRUE(find_vessel(name, &v)) << name;
  return v;
}

/// First fault after identification converged and the isolation thread learned its scales.
double first_fault(const std::string& name) { return name == "mariner" ? 600.0 : 300.0; }

struct Case {
  std::string vessel;
  double rate_hz;
};
std::string case_name(const testing::TestParamInfo<Case>& info) {
  return info.param.vessel + "_" + std::to_string(static_cast<int>(info.param.rate_hz)) + "Hz";
}
const auto kCases = testing::Values(Case{"otter", 50.0}, Case{"otter", 10.0}, Case{"mariner", 50.0},
                                    Case{"mariner", 10.0});

// Kinds the detector may name for each injected kind. Exact where the signatures differ;
// where two kinds look alike in the first seconds (a scale error on a slowly varying signal
// is a bias, on a rising one a ramp; at 10 Hz a few spikes and a noise burst share one
// window), either is allowed.
const std::map<FaultKind, std::set<FaultKind>> kAllowedKinds = {
    {FaultKind::kBias, {FaultKind::kBias}},
    {FaultKind::kDrift, {FaultKind::kDrift, FaultKind::kBias}},
    {FaultKind::kStuck, {FaultKind::kStuck}},
    {FaultKind::kNoise, {FaultKind::kNoise, FaultKind::kSpikes}},
    {FaultKind::kSpikes, {FaultKind::kSpikes, FaultKind::kNoise}},
    {FaultKind::kScale, {FaultKind::kScale, FaultKind::kBias, FaultKind::kDrift}},
    {FaultKind::kStale, {FaultKind::kStale}},
    {FaultKind::kInvalid, {FaultKind::kInvalid}},
};

class EveryKind : public testing::TestWithParam<Case> {};

TEST_P(EveryKind, EveryInjectedFaultIsDetectedAndIsolatedWithoutFalseAlarms) {
  // GIVEN a vessel sailing under its autopilot with realistic INS noise, and one fault of
  // every kind on each sensor after the engine has converged and learned.
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  SimConfig sim;
  sim.vessel = v;
  sim.rate_hz = c.rate_hz;
  sim.seed = 11;
  sim.faults = every_kind(v, first_fault(c.vessel), 30.0, 60.0);
  sim.duration = sim.faults.back().t_end + 60.0;
  // WHEN the engine processes the voyage
  const RunResult r = run(sim, vessel_config(c.vessel));
  // THEN every fault raises an event naming the right sensor and a plausible kind
  ASSERT_FALSE(std::isnan(r.t_armed));
  EXPECT_LT(r.t_armed, first_fault(c.vessel) - 60.0);
  int exact_kinds = 0;
  std::map<FaultKind, std::vector<double>> recovery;
  for (const FaultScore& s : score(sim, r)) {
    SCOPED_TRACE(std::string(to_string(s.fault.sensor)) + " " + to_string(s.fault.kind) + " at " +
                 std::to_string(s.fault.t_start));
    EXPECT_TRUE(s.detected);
    EXPECT_TRUE(s.isolated);
    EXPECT_TRUE(kAllowedKinds.at(s.fault.kind).count(s.kind)) << "named " << to_string(s.kind);
    exact_kinds += s.kind == s.fault.kind;
    EXPECT_LT(s.delay, 10.0);
    // AND no raise of the other sensor (or of "unknown") while the fault lasts: the
    // structured entry of the healthy sensor is blind to the faulty one's fault
    EXPECT_EQ(s.misisolations, 0);
    // AND one fault is one event: raised once, cleared after the fault ended. A scale error
    // hides while the vessel holds its course (f = k x with x ~ 0), and no residual can
    // tell a hidden scale error from none: it may clear in a straight leg and raise again
    // in the next turn (at most once more in a 30 s fault)
    if (s.fault.kind == FaultKind::kScale) {
      EXPECT_GE(s.raises, 1);
      EXPECT_LE(s.raises, 2);
    } else {
      EXPECT_EQ(s.raises, 1);
      EXPECT_FALSE(s.early_clear) << "cleared " << -s.recovery << " s before the fault ended";
    }
    if (std::isfinite(s.recovery)) recovery[s.fault.kind].push_back(s.recovery);
  }
  for (const auto& [kind, delays] : recovery) {
    std::printf("[ recovery ] %s %g Hz: %s median %.2f s\n", c.vessel.c_str(), c.rate_hz,
                to_string(kind), median(delays));
  }
  // AND nothing is raised outside the fault windows
  for (const FaultEvent& e : false_alarms(sim, r)) {
    ADD_FAILURE() << "false alarm at t = " << e.t << ": " << to_string(e.sensor) << " "
                  << e.message;
  }
  RecordProperty("exact_kinds", exact_kinds);
  std::printf("[ kinds    ] %s %g Hz: %d of %zu named exactly\n", c.vessel.c_str(), c.rate_hz,
              exact_kinds, sim.faults.size());
}
INSTANTIATE_TEST_SUITE_P(Vessels, EveryKind, kCases, case_name);

class Healthy : public testing::TestWithParam<Case> {};

TEST_P(Healthy, NoFalseAlarmInThirtyMinutesOfHealthyData) {
  // GIVEN 30 minutes of healthy data after the engine armed
  const Case c = GetParam();
  SimConfig sim;
  sim.vessel = vessel(c.vessel);
  sim.rate_hz = c.rate_hz;
  sim.seed = 23;
  sim.duration = first_fault(c.vessel) + 1800.0;
  // WHEN the engine processes it
  const RunResult r = run(sim, vessel_config(c.vessel));
  // THEN it armed and raised nothing, and the estimate of A is within a few percent
  ASSERT_FALSE(std::isnan(r.t_armed));
  for (const FaultEvent& e : r.events) {
    ADD_FAILURE() << "false alarm at t = " << e.t << ": " << to_string(e.sensor) << " "
                  << to_string(e.state) << " " << e.message;
  }
  const Vec4 a = to_params(r.final_estimate.A), at = to_params(sim.vessel.A);
  for (int n = 0; n < 4; ++n) {
    EXPECT_LT(std::abs(a(n) - at(n)), 0.15 * std::abs(at(n))) << "a" << n + 1;
  }
}
INSTANTIATE_TEST_SUITE_P(Vessels, Healthy, kCases, case_name);

class Incipient : public testing::TestWithParam<Case> {};

TEST_P(Incipient, ARampReachingTenSigmaInThirtySecondsIsRaisedBeforeFiveSigma) {
  // GIVEN a slow drift on each sensor (issue 11, item 6: 10 sigma in 30 s, lasting 60 s)
  //   after the engine armed and learned: its own structured residual keeps only a small
  //   part of it, the other observer's cross residual all of it
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  SimConfig sim;
  sim.vessel = v;
  sim.rate_hz = c.rate_hz;
  sim.seed = 31;
  double t = first_fault(c.vessel);
  for (const Sensor sn :
       {Sensor::kAccelerometer, Sensor::kGyro, Sensor::kAccelerometer, Sensor::kGyro}) {
    const double sigma = sn == Sensor::kGyro ? v.sigma_r : v.sigma_v;
    const double sign = t > first_fault(c.vessel) + 250.0 ? -1.0 : 1.0;
    sim.faults.push_back(FaultInjection{sn, FaultKind::kDrift, t, t + 60.0, sign * sigma / 3.0});
    t += 60.0 + 120.0;
  }
  sim.duration = t;
  // WHEN the engine processes the voyage with the drift test on (isolation.drift_check: off
  //   by default and in the shipped configurations, which a manoeuvring voyage gives false
  //   drifts; docs/benchmark.md)
  EngineConfig cfg = vessel_config(c.vessel);
  cfg.isolation.drift_check = true;
  const RunResult r = run(sim, cfg);
  ASSERT_FALSE(std::isnan(r.t_armed));
  // THEN each drift is raised on its own sensor before it reaches 5 sigma (15 s)
  for (const FaultScore& s : score(sim, r)) {
    SCOPED_TRACE(std::string(to_string(s.fault.sensor)) + " drift at " +
                 std::to_string(s.fault.t_start));
    std::printf(
        "[ drift    ] %s %g Hz %s %+.0f sigma/30 s: delay %.1f s (%s), %d raise(s)\n",
        c.vessel.c_str(), c.rate_hz, to_string(s.fault.sensor),
        30.0 * s.fault.magnitude / (s.fault.sensor == Sensor::kGyro ? v.sigma_r : v.sigma_v),
        s.delay, s.detected ? to_string(s.kind) : "missed", s.raises);
    EXPECT_TRUE(s.detected);
    EXPECT_TRUE(s.isolated);
    EXPECT_LT(s.delay, 15.0);
    EXPECT_EQ(s.raises, 1);
    EXPECT_EQ(s.misisolations, 0);
  }
  // AND nothing is raised outside the fault windows
  for (const FaultEvent& e : false_alarms(sim, r)) {
    ADD_FAILURE() << "false alarm at t = " << e.t << ": " << to_string(e.sensor) << " "
                  << e.message;
  }
}
INSTANTIATE_TEST_SUITE_P(Vessels, Incipient, kCases, case_name);

class BiasDelay : public testing::TestWithParam<Case> {};

TEST_P(BiasDelay, MedianDetectionDelayOfATenSigmaBiasIsUnderOneSecond) {
  // GIVEN twelve 10-sigma biases, alternating between the sensors
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  SimConfig sim;
  sim.vessel = v;
  sim.rate_hz = c.rate_hz;
  sim.seed = 5;
  double t = first_fault(c.vessel);
  for (int i = 0; i < 12; ++i) {
    const Sensor s = i % 2 ? Sensor::kGyro : Sensor::kAccelerometer;
    const double sigma = s == Sensor::kGyro ? v.sigma_r : v.sigma_v;
    sim.faults.push_back({s, FaultKind::kBias, t, t + 20.0, (i % 4 < 2 ? 10.0 : -10.0) * sigma});
    t += 57.0;
  }
  sim.duration = t + 30.0;
  // WHEN the engine processes the voyage
  const RunResult r = run(sim, vessel_config(c.vessel));
  // THEN every bias is isolated and the median delay from onset to the event is < 1 s
  std::vector<double> delays;
  for (const FaultScore& s : score(sim, r)) {
    EXPECT_TRUE(s.detected && s.isolated) << to_string(s.fault.sensor) << " " << s.fault.t_start;
    if (s.detected) delays.push_back(s.delay);
  }
  const double med = median(delays);
  std::printf("[ delay    ] %s %g Hz: median detection delay of a 10-sigma bias %.3f s\n",
              c.vessel.c_str(), c.rate_hz, med);
  EXPECT_LT(med, 1.0);
  EXPECT_TRUE(false_alarms(sim, r).empty());
}
INSTANTIATE_TEST_SUITE_P(Vessels, BiasDelay, kCases, case_name);

// Faults before the engine has armed: no residual can see them (no model yet), and the
// identification learns from whatever comes. Each case: a fault of one kind on one sensor
// while the estimate of A is still being learned (the engine arms on healthy data at
// ~90 s on the Otter at 10 Hz, ~40 s at 50 Hz, ~310 s and ~160 s on the Mariner).
struct EarlyFault {
  double t0, t1;  ///< fault window [s]
};
EarlyFault early_fault(const Case& c) {
  if (c.vessel == "otter") return c.rate_hz < 20 ? EarlyFault{60, 70} : EarlyFault{20, 30};
  return c.rate_hz < 20 ? EarlyFault{150, 180} : EarlyFault{80, 100};
}

/// Two 10-sigma biases long after the early fault: the engine must see them.
void add_later_faults(const VesselModel& v, double t, SimConfig* sim) {
  sim->faults.push_back({Sensor::kGyro, FaultKind::kBias, t, t + 20.0, 10.0 * v.sigma_r});
  sim->faults.push_back(
      {Sensor::kAccelerometer, FaultKind::kBias, t + 60.0, t + 80.0, 10.0 * v.sigma_v});
}

/// Largest relative error of A^ over the samples at or after t.
double worst_error_after(const RunResult& r, const VesselModel& v, double t) {
  const Vec4 at = to_params(v.A);
  double worst = 0.0;
  for (const Estimate& e : r.estimates) {
    if (!(e.t >= t)) continue;
    worst = std::max(worst, ((to_params(e.A) - at).array() / at.array()).abs().maxCoeff());
  }
  return worst;
}

class FaultBeforeArming : public testing::TestWithParam<Case> {};

TEST_P(FaultBeforeArming, TheEstimateRecoversTheEngineArmsAndLaterFaultsAreSeen) {
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  const EarlyFault w = early_fault(c);
  // The identification's memory time (1 / lambda): A^ must be good again this long after
  // the fault, and the later faults come after the engine has armed and learned.
  const double memory = 1.0 / vessel_config(c.vessel).identification.lambda;
  const double t_later = w.t1 + memory + (c.vessel == "otter" ? 100.0 : 400.0);
  struct K {
    FaultKind kind;
    double mag;  // in units of the channel's noise (scale: relative gain)
  };
  const std::vector<K> kinds = {{FaultKind::kBias, 10.0},   {FaultKind::kDrift, 0.6},
                                {FaultKind::kStuck, 0.0},   {FaultKind::kNoise, 6.0},
                                {FaultKind::kSpikes, 25.0}, {FaultKind::kScale, 0.5}};
  for (const K& k : kinds) {
    for (const Sensor sn : {Sensor::kAccelerometer, Sensor::kGyro}) {
      // GIVEN a fault of this kind on this sensor while A is still being learned (seed 2:
      //   the reproduction is the Otter at 10 Hz, accelerometer bias 0.05 m/s on
      //   60-70 s, which once left A^ nonsense that 200 s of healthy data did not undo)
      const double sigma = sn == Sensor::kGyro ? v.sigma_r : v.sigma_v;
      SimConfig sim;
      sim.vessel = v;
      sim.rate_hz = c.rate_hz;
      sim.seed = 2;
      FaultInjection f;
      f.sensor = sn;
      f.kind = k.kind;
      f.t_start = w.t0;
      f.t_end = w.t1;
      f.magnitude = k.kind == FaultKind::kScale ? k.mag : k.mag * sigma;
      sim.faults.push_back(f);
      add_later_faults(v, t_later, &sim);
      sim.duration = t_later + 100.0;
      SCOPED_TRACE(std::string(to_string(sn)) + " " + to_string(k.kind));
      // WHEN the engine processes the voyage
      const RunResult r = run(sim, vessel_config(c.vessel));
      // THEN A^ is within 10 % of A from one memory time after the fault on
      const double err = worst_error_after(r, v, w.t1 + memory);
      std::printf(
          "[ early    ] %s %g Hz %s %s: armed at %.1f s, worst error of A^ after %.0f s "
          "%.3f\n",
          c.vessel.c_str(), c.rate_hz, to_string(sn), to_string(k.kind), r.t_armed, w.t1 + memory,
          err);
      EXPECT_LT(err, 0.10);
      // AND the engine armed before the later faults
      ASSERT_FALSE(std::isnan(r.t_armed));
      EXPECT_LT(r.t_armed, t_later - 100.0);
      // AND each later fault is raised once, on its own sensor, and nothing else is raised
      //   (a stuck channel is seen before arming too, by the sensor-level checks)
      const std::vector<FaultScore> scores = score(sim, r);
      for (std::size_t i = 1; i < scores.size(); ++i) {
        EXPECT_TRUE(scores[i].detected && scores[i].isolated)
            << to_string(scores[i].fault.sensor) << " bias at " << scores[i].fault.t_start;
        EXPECT_EQ(scores[i].raises, 1);
        EXPECT_EQ(scores[i].misisolations, 0);
      }
      for (const FaultEvent& e : r.events) {
        const bool early = e.sensor == sn && e.t >= w.t0 && e.t <= w.t1 + 2.0;
        if (is_raise(e) && e.t < t_later && !early) {
          ADD_FAILURE() << "raise at " << e.t << " before the later faults: " << e.message;
        }
      }
    }
  }
}
INSTANTIATE_TEST_SUITE_P(Vessels, FaultBeforeArming, kCases, case_name);

TEST(FaultFromTheStart, TheEstimateRecoversOnceTheRecentDataContradictTheMemory) {
  // GIVEN the Otter at 10 and 50 Hz with a fault present from the very first sample that
  //   ends after 60 s (80 s): the memory has nothing healthy to compare it with, and the
  //   healthy data after it do not outweigh it for a long time
  const VesselModel v = vessel("otter");
  const EngineConfig cfg = vessel_config("otter");
  const double memory = 1.0 / cfg.identification.lambda;
  for (const double rate : {10.0, 50.0}) {
    for (const FaultInjection& f :
         {FaultInjection{Sensor::kAccelerometer, FaultKind::kBias, 0.0, 60.0, 10.0 * v.sigma_v},
          FaultInjection{Sensor::kGyro, FaultKind::kScale, 0.0, 80.0, 0.5}}) {
      SimConfig sim;
      sim.vessel = v;
      sim.rate_hz = rate;
      sim.seed = 2;
      sim.faults = {f};
      const double t_later = f.t_end + memory + 100.0;
      add_later_faults(v, t_later, &sim);
      sim.duration = t_later + 100.0;
      SCOPED_TRACE(std::to_string(rate) + " Hz " + to_string(f.sensor) + " " + to_string(f.kind));
      // WHEN the engine processes the voyage
      const RunResult r = run(sim, cfg);
      // THEN once the recent data contradict the memory it is rebuilt from them: A^ is
      //   within 10 % one memory time after the fault, the engine arms, and the later
      //   faults are isolated
      const double err = worst_error_after(r, v, f.t_end + memory);
      std::printf(
          "[ start    ] otter %g Hz %s %s: armed at %.1f s, memory rebuilt %llu times, "
          "worst error after %.0f s %.3f\n",
          rate, to_string(f.sensor), to_string(f.kind), r.t_armed,
          static_cast<unsigned long long>(r.final_estimate.resets), f.t_end + memory, err);
      EXPECT_LT(err, 0.10);
      ASSERT_FALSE(std::isnan(r.t_armed));
      const std::vector<FaultScore> scores = score(sim, r);
      for (std::size_t i = 1; i < scores.size(); ++i) {
        EXPECT_TRUE(scores[i].detected && scores[i].isolated);
      }
    }
  }
}

TEST(FaultFromTheStart, APermanentBiasKeepsTheEngineFromArmingAndSaysWhy) {
  // GIVEN the Otter at 10 Hz whose accelerometer is biased by 10 sigma from the first sample
  //   to the end: nothing healthy to learn from (a constant bias is a constant sway
  //   disturbance, which no residual can tell from the vessel)
  const VesselModel v = vessel("otter");
  SimConfig sim;
  sim.vessel = v;
  sim.rate_hz = 10.0;
  sim.seed = 2;
  sim.duration = 900.0;
  sim.faults = {{Sensor::kAccelerometer, FaultKind::kBias, 0.0, 1000.0, 10.0 * v.sigma_v}};
  // WHEN the engine processes it
  const RunResult r = run(sim, vessel_config("otter"));
  // THEN it does not arm on the inconsistent data, and the estimate says why
  EXPECT_TRUE(std::isnan(r.t_armed));
  EXPECT_FALSE(r.final_estimate.converged);
  EXPECT_NE(r.final_estimate.status, IdentStatus::kConverged);
  std::printf("[ start    ] otter 10 Hz, accelerometer biased throughout: %s\n",
              to_string(r.final_estimate.status));
}

TEST(Relearning, ARedesignLearningThroughADriftsOnsetLearnsAgainAndKeepsItsChannelOpen) {
  // GIVEN the Mariner at 10 Hz (seed 11) with one fault of every kind from 600 s: the
  // accelerometer's drift (780-810 s) grows for 8 s before it is raised at 788 s, while a
  // redesign of the observers is learning its bars
  const VesselModel v = vessel("mariner");
  SimConfig sim;
  sim.vessel = v;
  sim.rate_hz = 10.0;
  sim.seed = 11;
  sim.faults = every_kind(v, first_fault("mariner"), 30.0, 60.0);
  sim.duration = 1000.0;
  for (const bool relearn : {true, false}) {
    SCOPED_TRACE(relearn ? "relearns after a raise" : "keeps its learning");
    EngineConfig cfg = vessel_config("mariner");
    cfg.isolation.relearn_after_raise = relearn;
    double closed_from = kNaN;
    run(sim, cfg, [&](const SimRow& row, const FdiEngine& engine) {
      if (row.t > 780.0 && engine.isolation_status().bar_unreachable[0] &&
          std::isnan(closed_from)) {
        closed_from = row.t;
      }
    });
    // WHEN the raise restarts that learning (the shipped configuration), THEN the redesign
    // learns on healthy data after the fault and the accelerometer's channel stays open.
    // Kept, the learning holds the drift's first seconds: the learned bar had to be capped
    // and the channel closes (at 825.7 s): its residual is blind to the faults after it.
    if (relearn) {
      EXPECT_TRUE(std::isnan(closed_from)) << "closed at " << closed_from << " s";
    } else {
      EXPECT_TRUE(closed_from > 810.0 && closed_from < 840.0) << "closed at " << closed_from;
    }
  }
}

class GuardArming : public testing::TestWithParam<Case> {};

TEST_P(GuardArming, TheGuardDoesNotDelayArmingOnHealthyData) {
  // GIVEN twelve healthy voyages per vessel and rate
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  EngineConfig with = vessel_config(c.vessel), without = with;
  without.identification.guard = false;
  std::vector<double> t_with, t_without;
  std::uint64_t rejected = 0;
  for (std::uint64_t seed = 401; seed <= 412; ++seed) {
    SimConfig sim;
    sim.vessel = v;
    sim.rate_hz = c.rate_hz;
    sim.seed = seed;
    sim.duration = c.vessel == "otter" ? 400.0 : 900.0;
    // WHEN the engine processes each with and without the consistency guard
    const RunResult a = run(sim, with), b = run(sim, without);
    ASSERT_FALSE(std::isnan(a.t_armed)) << "seed " << seed;
    ASSERT_FALSE(std::isnan(b.t_armed)) << "seed " << seed;
    t_with.push_back(a.t_armed);
    t_without.push_back(b.t_armed);
    rejected += a.final_estimate.rejected_windows + a.final_estimate.removed_windows;
  }
  const double m_with = median(t_with), m_without = median(t_without);
  std::printf(
      "[ arming   ] %s %g Hz: median arming %.1f s with the guard, %.1f s without; %llu "
      "healthy windows kept out in %zu voyages\n",
      c.vessel.c_str(), c.rate_hz, m_with, m_without, static_cast<unsigned long long>(rejected),
      t_with.size());
  // THEN the median arming time is within 10 % of the unguarded one (the guard's only cost
  // on healthy data is the judging delay, one and a half windows)
  EXPECT_LT(m_with, 1.1 * m_without);
}
INSTANTIATE_TEST_SUITE_P(Vessels, GuardArming, kCases, case_name);

class SeedSweep : public testing::TestWithParam<Case> {};

TEST_P(SeedSweep, EightMoreSeedsOfHealthyAndEveryKindVoyages) {
  // GIVEN eight seeds other than the tests' own, per vessel and rate: 30 minutes of healthy
  //   data after arming, and the every-kind voyage
  const Case c = GetParam();
  const VesselModel v = vessel(c.vessel);
  int faults = 0, detected = 0, isolated = 0, false_raises = 0;
  double hours = 0.0;
  for (std::uint64_t seed = 1001; seed <= 1008; ++seed) {
    SimConfig healthy;
    healthy.vessel = v;
    healthy.rate_hz = c.rate_hz;
    healthy.seed = seed;
    healthy.duration = first_fault(c.vessel) + 1800.0;
    SimConfig faulty = healthy;
    faulty.faults = every_kind(v, first_fault(c.vessel), 30.0, 60.0);
    faulty.duration = faulty.faults.back().t_end + 60.0;
    // WHEN the engine processes each
    const RunResult h = run(healthy, vessel_config(c.vessel));
    const RunResult f = run(faulty, vessel_config(c.vessel));
    ASSERT_FALSE(std::isnan(h.t_armed)) << "seed " << seed;
    ASSERT_LT(f.t_armed, first_fault(c.vessel)) << "seed " << seed;
    for (const FaultEvent& e : h.events) false_raises += e.state == FaultState::kRaised;
    false_raises += static_cast<int>(false_alarms(faulty, f).size());
    hours += (healthy.duration - h.t_armed + faulty.duration - f.t_armed) / 3600.0;
    for (const FaultScore& s : score(faulty, f)) {
      ++faults;
      detected += s.detected;
      isolated += s.detected && s.isolated;
      if (!(s.detected && s.isolated)) {
        std::printf("[ sweep    ] seed %llu: %s %s at %g %s\n",
                    static_cast<unsigned long long>(seed), to_string(s.fault.sensor),
                    to_string(s.fault.kind), s.fault.t_start,
                    s.detected ? "named the wrong sensor" : "missed");
      }
    }
  }
  std::printf(
      "[ sweep    ] %s %g Hz: %d of %d faults detected, %d isolated; %d false raises in "
      "%.1f h\n",
      c.vessel.c_str(), c.rate_hz, detected, faults, isolated, false_raises, hours);
  // THEN every fault is detected, at most one in a hundred is put on the wrong sensor, and
  //   at most one raise in the ~8 h is false
  EXPECT_EQ(detected, faults);
  EXPECT_GE(isolated, faults - faults / 100);
  EXPECT_LE(false_raises, 1);
}
INSTANTIATE_TEST_SUITE_P(Vessels, SeedSweep, kCases, case_name);

// The same over many seeds, for the figures of merit (opt-in, several minutes on one core):
//   [USV_FDI_SWEEP_SEEDS=101-300, the default] build/tests/usv_fdi_scenario_tests
//     --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_ManySeeds*'
// USV_FDI_SWEEP_CASES=otter10,mariner50 limits the vessels and rates.
TEST(SeedSweep, DISABLED_ManySeeds) {
  std::uint64_t s0 = 101, s1 = 300;
  if (const char* env = std::getenv("USV_FDI_SWEEP_SEEDS")) {
    unsigned long long a = 0, b = 0;
    ASSERT_EQ(std::sscanf(env, "%llu-%llu", &a, &b), 2) << "USV_FDI_SWEEP_SEEDS=" << env;
    s0 = a;
    s1 = b;
  }
  const char* only = std::getenv("USV_FDI_SWEEP_CASES");
  for (const Case& c :
       {Case{"otter", 50.0}, Case{"otter", 10.0}, Case{"mariner", 50.0}, Case{"mariner", 10.0}}) {
    const std::string tag = c.vessel + std::to_string(static_cast<int>(c.rate_hz));
    if (only && std::string(only).find(tag) == std::string::npos) continue;
    const VesselModel v = vessel(c.vessel);
    EngineConfig cfg = vessel_config(c.vessel);
    // USV_FDI_SWEEP_GUARD=0 turns identification's consistency guard off (to compare).
    if (const char* g = std::getenv("USV_FDI_SWEEP_GUARD"))
      cfg.identification.guard = std::string(g) != "0";
    int faults = 0, detected = 0, isolated = 0, biases = 0, bias_ok = 0;
    std::vector<double> armed;
    int raises_healthy = 0, fa_every = 0, fa_bias = 0;
    int misisolations = 0, flickers = 0, early_clears = 0;
    double h_healthy = 0, h_every = 0, h_bias = 0;
    std::vector<double> delays;
    struct PerKind {
      int n = 0, one = 0, more = 0, early = 0, mis = 0;
      std::vector<double> delay, recovery;
    };
    std::map<std::pair<Sensor, FaultKind>, PerKind> per_kind;
    const auto count = [&](const FaultScore& s) {
      PerKind& k = per_kind[{s.fault.sensor, s.fault.kind}];
      ++k.n;
      k.one += s.raises == 1;
      k.more += s.raises > 1;
      k.early += s.early_clear;
      k.mis += s.misisolations;
      if (s.detected && s.isolated) k.delay.push_back(s.delay);
      if (s.detected && s.isolated && std::isfinite(s.recovery)) k.recovery.push_back(s.recovery);
      misisolations += s.misisolations;
      flickers += s.raises > 1;
      early_clears += s.early_clear;
    };
    for (std::uint64_t seed = s0; seed <= s1; ++seed) {
      SimConfig sim;
      sim.vessel = v;
      sim.rate_hz = c.rate_hz;
      sim.seed = seed;
      // 30 minutes of healthy data after the first-fault time
      sim.duration = first_fault(c.vessel) + 1800.0;
      const RunResult h = run(sim, cfg);
      ASSERT_FALSE(std::isnan(h.t_armed));
      armed.push_back(h.t_armed);
      for (const FaultEvent& e : h.events) raises_healthy += is_raise(e);
      h_healthy += (sim.duration - h.t_armed) / 3600.0;
      // one fault of every kind on each sensor
      sim.faults = every_kind(v, first_fault(c.vessel), 30.0, 60.0);
      sim.duration = sim.faults.back().t_end + 60.0;
      const RunResult f = run(sim, cfg);
      for (const FaultScore& s : score(sim, f)) {
        ++faults;
        detected += s.detected;
        isolated += s.detected && s.isolated;
        count(s);
        if (s.misisolations > 0 || s.raises != 1 || s.early_clear) {
          std::printf("[ sweep    ] %s seed %llu: %s %s at %g: %d raises, %d misisolated%s\n",
                      tag.c_str(), static_cast<unsigned long long>(seed), to_string(s.fault.sensor),
                      to_string(s.fault.kind), s.fault.t_start, s.raises, s.misisolations,
                      s.early_clear ? ", cleared early" : "");
        }
      }
      fa_every += static_cast<int>(false_alarms(sim, f).size());
      h_every += (sim.duration - f.t_armed) / 3600.0;
      // twelve 10-sigma biases
      sim.faults.clear();
      double t = first_fault(c.vessel);
      for (int i = 0; i < 12; ++i) {
        const Sensor sn = i % 2 ? Sensor::kGyro : Sensor::kAccelerometer;
        const double sigma = sn == Sensor::kGyro ? v.sigma_r : v.sigma_v;
        sim.faults.push_back(
            {sn, FaultKind::kBias, t, t + 20.0, (i % 4 < 2 ? 10.0 : -10.0) * sigma});
        t += 57.0;
      }
      sim.duration = t + 30.0;
      const RunResult b = run(sim, cfg);
      for (const FaultScore& s : score(sim, b)) {
        ++biases;
        bias_ok += s.detected && s.isolated;
        if (s.detected) delays.push_back(s.delay);
        misisolations += s.misisolations;
        flickers += s.raises > 1;
        early_clears += s.early_clear;
      }
      fa_bias += static_cast<int>(false_alarms(sim, b).size());
      h_bias += (sim.duration - b.t_armed) / 3600.0;
    }
    const int fa = raises_healthy + fa_every + fa_bias;
    const double hours = h_healthy + h_every + h_bias;
    std::printf(
        "[ sweep    ] %s %g Hz, seeds %llu-%llu: healthy %d raises in %.1f h; every kind "
        "%d/%d detected, %d/%d isolated, %d false in %.1f h; 10-sigma biases %d/%d "
        "isolated, median delay %.3f s, %d false in %.1f h; false alarms %.3f /h; "
        "misisolations %d, faults raised more than once %d, cleared early %d (of %d)\n",
        c.vessel.c_str(), c.rate_hz, static_cast<unsigned long long>(s0),
        static_cast<unsigned long long>(s1), raises_healthy, h_healthy, detected, faults, isolated,
        faults, fa_every, h_every, bias_ok, biases, median(delays), fa_bias, h_bias, fa / hours,
        misisolations, flickers, early_clears, faults + biases);
    std::printf(
        "[ sweep    ] %s %g Hz: median arming time (healthy voyages) %.1f s, latest %.1f s\n",
        c.vessel.c_str(), c.rate_hz, median(armed), *std::max_element(armed.begin(), armed.end()));
    std::printf("[ sweep    ] %-13s %-7s %5s %5s %5s %5s %5s %9s %9s\n", "sensor", "kind", "n",
                "once", "more", "early", "mis", "delay", "recovery");
    for (auto& [key, k] : per_kind) {
      std::printf("[ sweep    ] %-13s %-7s %5d %5d %5d %5d %5d %8.2fs %8.2fs\n",
                  to_string(key.first), to_string(key.second), k.n, k.one, k.more, k.early, k.mis,
                  median(k.delay), median(k.recovery));
    }
    EXPECT_EQ(detected, faults) << c.vessel << " " << c.rate_hz;
    EXPECT_GE(isolated, faults - faults / 200) << c.vessel << " " << c.rate_hz;
    EXPECT_LT(median(delays), 1.0) << c.vessel << " " << c.rate_hz;
    EXPECT_LT(fa / hours, 0.1) << c.vessel << " " << c.rate_hz;
  }
}

TEST(NoiseFree, EveryShippedVesselsAIsFoundToOneInTenThousandAtTenFiftyAndHundredHertz) {
  for (const std::string name : {"otter", "mariner"}) {
    for (const Steering steering : {Steering::kSine, Steering::kAutopilot}) {
      for (const double rate : {10.0, 50.0, 100.0}) {
        // GIVEN ten noise-free minutes of the vessel under a smooth rudder (sines) or its
        //   digital autopilot, with the shipped configuration
        SimConfig sim;
        sim.vessel = vessel(name);
        sim.rate_hz = rate;
        sim.duration = 600.0;
        sim.sigma_v = sim.sigma_r = 0.0;
        sim.steering = steering;
        const EngineConfig cfg = vessel_config(name);
        Identifier id(cfg.identification, cfg.B);
        // WHEN the identification sees every sample
        for (const SimRow& row : simulate(sim)) {
          ASSERT_TRUE(id.update(Sample{row.t, row.v, row.r, row.delta}, false));
        }
        // THEN every a_n is within 1e-4 of its value (relative). The autopilot's rudder is
        //   a servo answering a command held over each sample: its rate jumps at every
        //   sample, so no polynomial through the samples follows it and the error is
        //   O(h^2) there; at 10 Hz on the Otter (the fastest vessel) that is 1.8e-4.
        const Vec4 a = to_params(sim.vessel.A), e = to_params(id.estimate().A) - a;
        const double worst = (e.array() / a.array()).abs().maxCoeff();
        const bool kinked_10hz = steering == Steering::kAutopilot && rate == 10.0;
        EXPECT_LT(worst, kinked_10hz ? 3e-4 : 1e-4)
            << name << (steering == Steering::kSine ? " sine " : " autopilot ") << rate << " Hz";
        std::printf("[ noise-0  ] %s %s %g Hz: worst relative error of A %.2g\n", name.c_str(),
                    steering == Steering::kSine ? "sine" : "autopilot", rate, worst);
      }
    }
  }
}

TEST(MeasuredAutopilot, TheRudderInstrumentsStayUnbiasedWhenTheAutopilotSteersOnTheINS) {
  // GIVEN the Otter (the fastest shipped vessel, the largest noise feedback) steered by an
  //   autopilot on the measured v, r and heading, so the rudder carries a filtered trace of
  //   the INS noise, at 10 and 50 Hz, over three seeds of 25 minutes
  const VesselModel v = vessel("otter");
  const EngineConfig cfg = vessel_config("otter");
  for (const double rate : {10.0, 50.0}) {
    Vec4 bias[2] = {Vec4::Zero(), Vec4::Zero()};
    for (const bool measured : {false, true}) {
      for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        SimConfig sim;
        sim.vessel = v;
        sim.rate_hz = rate;
        sim.seed = seed;
        sim.duration = 1500.0;
        sim.autopilot_on_measurement = measured;
        Identifier id(cfg.identification, cfg.B);
        // WHEN identification sees every sample
        for (const SimRow& r : simulate(sim)) id.update(Sample{r.t, r.v, r.r, r.delta}, false);
        const Vec4 at = to_params(v.A);
        bias[measured] += ((to_params(id.estimate().A) - at).array() / at.array()).matrix() / 3.0;
      }
    }
    std::printf(
        "[ autopilot] otter %g Hz: mean relative error of a1..a4, true-state autopilot "
        "%+.4f %+.4f %+.4f %+.4f, measured-state %+.4f %+.4f %+.4f %+.4f\n",
        rate, bias[0](0), bias[0](1), bias[0](2), bias[0](3), bias[1](0), bias[1](1), bias[1](2),
        bias[1](3));
    // THEN the feedback of the noise through the rudder moves no a_n by more than 1 % (its
    //   correlation with the instruments is second order), and the estimate stays within
    //   the accuracy of the true-state case (3 % at 10 Hz, 1 % at 50 Hz)
    for (int n = 0; n < 4; ++n) {
      EXPECT_LT(std::abs(bias[1](n) - bias[0](n)), 0.01) << "a" << n + 1 << " " << rate << " Hz";
      EXPECT_LT(std::abs(bias[1](n)), rate < 20 ? 0.03 : 0.01) << "a" << n + 1 << " " << rate;
    }
  }
}

TEST(PaperScenario, BothFaultsAreDetectedIsolatedAndTheEstimateConvergesMonotonically) {
  // GIVEN the paper's scenario on the Otter (noise-free, as the paper's Simulink model):
  // gyro fault on (20, 40) s, accelerometer fault on (60, 80) s, with the config that
  // arms the isolation thread before 20 s
  const VesselModel v = vessel("otter");
  SimConfig sim = paper_scenario(v, 50.0, 1);
  sim.sigma_v = 0.0;
  sim.sigma_r = 0.0;
  const EngineConfig cfg = io::load_engine_config(kSource + "/config/scenarios/paper.yaml");
  // WHEN the engine processes it
  const RunResult r = run(sim, cfg);
  // THEN it armed before the first fault, and each fault raised one event on its sensor
  // with a confidence of at least 0.9, cleared within 3 s of the fault's end
  ASSERT_LT(r.t_armed, 20.0);
  const auto scores = score(sim, r);
  ASSERT_EQ(scores.size(), 2u);
  for (const FaultScore& s : scores) {
    EXPECT_TRUE(s.detected && s.isolated) << to_string(s.fault.sensor);
    EXPECT_LT(s.delay, 1.0);
    EXPECT_GE(s.recovery, 0.0);
    EXPECT_LT(s.recovery, 3.0);
  }
  for (const FaultEvent& e : r.events) {
    if (e.state != FaultState::kRaised) continue;
    EXPECT_GE(e.sensor == Sensor::kGyro ? e.c_g : e.c_a, 0.9);
  }
  EXPECT_TRUE(false_alarms(sim, r).empty());
  // AND every parameter error shrinks monotonically (frozen while a fault is suspected) down
  // to the discretisation floor, and stays there
  const double floor = 1e-4;
  const Vec4 at = to_params(v.A);
  Vec4 prev = Vec4::Constant(1e300);
  for (const Estimate& e : r.estimates) {
    if (std::isnan(e.t) || e.updates == 0) continue;
    const Vec4 err = ((to_params(e.A) - at).array() / at.array()).abs();
    for (int n = 0; n < 4; ++n) {
      if (prev(n) > floor) {
        EXPECT_LE(err(n), prev(n) * (1.0 + 1e-9) + 1e-12) << "a" << n + 1 << " at t = " << e.t;
      } else {
        EXPECT_LT(err(n), floor) << "a" << n + 1 << " at t = " << e.t;
      }
    }
    prev = err;
  }
  EXPECT_LT(prev.maxCoeff(), floor);
}

}  // namespace
}  // namespace usvfdi::scenario
