// The thresholds that follow the healthy past (core/healthy_maxima.hpp, docs/design.md
// sections 8.3 and 8.6).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/healthy_maxima.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"

namespace usvfdi {
namespace {

TEST(HealthyMaxima, AreTheLargestValuesOfTheHistoryAndForgetOlderBlocks) {
  HealthyMaxima<2> h(10.0, 30.0);  // three blocks of 10 s
  EXPECT_TRUE(h.empty());
  EXPECT_EQ(h.max(0), 0.0);
  h.add(0.0, {5.0, 1.0});
  h.add(5.0, {2.0, 7.0});
  EXPECT_EQ(h.max(0), 5.0);
  EXPECT_EQ(h.max(1), 7.0);
  // 5 s of a 30 s history seen: the largest value so far, scaled by ln(31) / ln(6).
  EXPECT_DOUBLE_EQ(h.covered(), 5.0);
  EXPECT_NEAR(h.extrapolated_max(0), 5.0 * std::log(31.0) / std::log(6.0), 1e-12);
  for (double t = 10.0; t < 40.0; t += 1.0) h.add(t, {1.0, 1.0});
  // The first block (5, 7) is still one of the last three.
  EXPECT_EQ(h.max(0), 5.0);
  EXPECT_EQ(h.max(1), 7.0);
  h.add(40.0, {1.0, 1.0});  // closes the fourth block: the first is forgotten
  EXPECT_EQ(h.max(0), 1.0);
  EXPECT_EQ(h.max(1), 1.0);
  // The history is full: no extrapolation.
  EXPECT_DOUBLE_EQ(h.covered(), 30.0);
  EXPECT_DOUBLE_EQ(h.extrapolated_max(0), 1.0);
  h.clear();
  EXPECT_TRUE(h.empty());
}

/// The shipped Otter's healthy course changes at 10 Hz (core/simulator.hpp), for `duration`
/// seconds from `seed`.
SimConfig otter_course_changes(double duration, std::uint64_t seed) {
  SimConfig sim;
  EXPECT_TRUE(find_vessel("otter", &sim.vessel));
  sim.rate_hz = 10.0;
  sim.duration = duration;
  sim.seed = seed;
  return sim;
}

/// Runs the isolation stage given A from the first sample on (an oracle: a converged
/// estimate) over the simulated run, and calls each(row, detections, status) after every
/// sample.
template <typename Each>
void run_given_A(const IsolationParams& p, const Mat2& A, const SimConfig& sim, Each each) {
  Isolator iso(p, sim.vessel.B);
  Estimate est;
  est.A = A;
  est.converged = true;
  est.warming_up = false;
  est.status = IdentStatus::kConverged;
  bool given = false;
  std::vector<Detection> dets;
  for (const SimRow& r : simulate(sim)) {
    dets.clear();
    iso.update({r.t, r.v, r.r, r.delta}, &dets);
    if (!given) {
      est.t = r.t;
      iso.set_estimate(est);
      given = true;
    }
    each(r, dets, iso.status());
  }
}

/// The Otter's A with its second row (a3, a4) scaled by `yaw_scale`.
Mat2 otter_A_yaw_scaled(double yaw_scale) {
  VesselModel v;
  EXPECT_TRUE(find_vessel("otter", &v));
  Mat2 A = v.A;
  A(1, 0) *= yaw_scale;
  A(1, 1) *= yaw_scale;
  return A;
}

/// Raises of the isolation stage given A (an oracle) on the Otter's healthy course changes,
/// with the hull's true A off by 20 % in a3 and a4: every course change carries model
/// mismatch of the same size.
int raises_after(const IsolationParams& p, double after) {
  int raises = 0;
  run_given_A(p, otter_A_yaw_scaled(0.8), otter_course_changes(1500.0, 3),
              [&](const SimRow& r, const std::vector<Detection>& dets, const IsolatorStatus&) {
                for (const Detection& d : dets) raises += d.active && !d.update && r.t > after;
              });
  return raises;
}

TEST(IsolatorThresholds, AModelMismatchMetInHealthyManoeuvresRaisesTheBar) {
  // GIVEN the same course changes again and again, with a model that is off in each
  IsolationParams p;
  p.jump.enabled = false;       // the observers alone
  p.enter_time = 0.06;          // and no confirmation time: the thresholds alone
  p.close_capped_bars = false;  // and a bar capped within reach, not closed
  // WHEN the thresholds remember the healthy past (10 minutes) THEN after the first ten
  // minutes nothing is raised
  EXPECT_EQ(raises_after(p, 600.0), 0);
  // AND with a memory shorter than the time between course changes (10 s) they do raise:
  // the mismatch of each course change is taken for a fault
  p.history = 10.0;
  EXPECT_GT(raises_after(p, 600.0), 0);
}

/// Times of the gyro's raises on the Otter's course changes, the isolation stage given the
/// true A (an oracle), with a gyro drift injected on each of the given intervals.
std::vector<double> gyro_raises(const IsolationParams& p,
                                const std::vector<std::pair<double, double>>& drifts) {
  SimConfig sim = otter_course_changes(1000.0, 5);
  for (const auto& [from, to] : drifts) {
    sim.faults.push_back({Sensor::kGyro, FaultKind::kDrift, from, to, 0.002});
  }
  std::vector<double> raises;
  run_given_A(p, sim.vessel.A, sim,
              [&](const SimRow& r, const std::vector<Detection>& dets, const IsolatorStatus&) {
                for (const Detection& d : dets) {
                  if (d.sensor == Sensor::kGyro && d.active && !d.update) raises.push_back(r.t);
                }
              });
  return raises;
}

TEST(IsolatorThresholds, WhileTheBarsAreYoungAResidualRaiseIsConfirmedLonger) {
  // GIVEN a gyro drift while the healthy maxima cover less than `history` (at 200 s) and
  // one after (at 900 s, `history` being 600 s), seen by the observers alone
  IsolationParams p;
  p.jump.enabled = false;
  const std::vector<std::pair<double, double>> drifts = {{200.0, 230.0}, {900.0, 930.0}};
  // WHEN the young bars' confirmation is that of the older ones, and when it is twice as long
  p.young_enter_ratio = 1.0;
  const std::vector<double> same = gyro_raises(p, drifts);
  p.young_enter_ratio = 2.0;
  const std::vector<double> longer = gyro_raises(p, drifts);
  // THEN each drift is raised once either way; the young one enter_time later with the
  // longer confirmation, the later one at the same sample
  ASSERT_EQ(same.size(), 2u);
  ASSERT_EQ(longer.size(), 2u);
  EXPECT_NEAR(longer[0] - same[0], p.enter_time, 0.15);
  EXPECT_NEAR(longer[1], same[1], 1e-9);
}

/// The share of live samples (armed, learned, settled) with each channel's bar flagged
/// unreachable, the isolation stage given the Otter's A with its second row (a3, a4) scaled by
/// `yaw_scale` on its healthy course changes.
Vec2 unreachable_share(double yaw_scale) {
  const IsolationParams p;
  Vec2 flagged = Vec2::Zero();
  double live = 0.0;
  run_given_A(p, otter_A_yaw_scaled(yaw_scale), otter_course_changes(600.0, 7),
              [&](const SimRow&, const std::vector<Detection>&, const IsolatorStatus& st) {
                if (!st.armed || st.learning || st.settling) return;
                live += 1.0;
                for (int c = 0; c < 2; ++c) {
                  // the flag says exactly that the bar is at or above what J_N can reach
                  EXPECT_EQ(st.bar_unreachable[c], st.thresholds(c) >= p.clip * p.clip);
                  if (st.bar_unreachable[c]) flagged(c) += 1.0;
                }
              });
  EXPECT_GT(live, 0.0);
  return flagged / std::max(live, 1.0);
}

TEST(IsolatorThresholds, ABarTheStatisticCannotPassIsFlagged) {
  // GIVEN the isolation stage on the Otter's healthy course changes
  // WHEN it has the true A THEN no bar is flagged
  EXPECT_EQ(unreachable_share(1.0), Vec2::Zero());
  // WHEN its a3 and a4 are 20 % off, THEN each course change pegs the gyro's J_N, the
  // healthy maximum reaches the clip, and the gyro's bar stands above clip^2 (flagged) on
  // nearly all the live samples, the accelerometer's on almost none
  const Vec2 off = unreachable_share(0.8);
  EXPECT_GT(off(1), 0.9) << off.transpose();
  EXPECT_LT(off(0), 0.05) << off.transpose();
}

/// The gyro's bar and flag at the first live sample, and the gyro's raises, the isolation
/// stage (the observers alone) given the Otter's A with a3, a4 20 % off on its course changes.
struct FirstLive {
  double bar = 0.0;
  bool flagged = false;
  int raises = 0;
};
FirstLive gyro_first_live(bool close_capped_bars) {
  IsolationParams p;
  p.jump.enabled = false;
  p.close_capped_bars = close_capped_bars;
  FirstLive f;
  bool seen = false;
  run_given_A(p, otter_A_yaw_scaled(0.8), otter_course_changes(600.0, 7),
              [&](const SimRow&, const std::vector<Detection>& dets, const IsolatorStatus& st) {
                for (const Detection& d : dets) {
                  f.raises += d.sensor == Sensor::kGyro && d.active && !d.update;
                }
                if (seen || !st.armed || st.learning || st.settling || !(st.thresholds(1) > 0)) {
                  return;
                }
                seen = true;
                f.bar = st.thresholds(1);
                f.flagged = st.bar_unreachable[1];
              });
  EXPECT_TRUE(seen);
  return f;
}

TEST(IsolatorThresholds, ABarThatHadToBeCappedClosesTheChannelFromGoingLive) {
  // GIVEN the Otter's course changes with a model 20 % off in a3 and a4: the gyro's J_N in
  // learning already went where a fault would take it
  const double c2 = IsolationParams{}.clip * IsolationParams{}.clip;
  // WHEN the capped bar stands THEN the gyro goes live with a bar J_N can pass
  const FirstLive capped = gyro_first_live(false);
  EXPECT_LT(capped.bar, c2);
  EXPECT_FALSE(capped.flagged);
  // WHEN it closes the channel (the default) THEN the gyro goes live closed, flagged, and
  // its residual raises nothing
  const FirstLive closed = gyro_first_live(true);
  EXPECT_GE(closed.bar, c2);
  EXPECT_TRUE(closed.flagged);
  EXPECT_EQ(closed.raises, 0);
}

TEST(IsolatorThresholds, TheHistoryBarNeverFallsAsTheHealthyMaximumRisesAndStaysReachable) {
  const double clip = 4.0, knee = 0.8 * clip * clip;
  for (const double margin : {1.2, 4.0 / 3.0, 1.5, 2.0}) {
    // GIVEN healthy maxima from 0 to past the clip, in small steps
    double last = 0.0;
    for (double h = 0.0; h <= 1.2 * clip * clip; h += 0.001) {
      const double bar = history_bar(h, margin, clip);
      // THEN the bar never falls as the maximum rises (a falling bar restarts the
      // confirmation of a rise that the rising maximum follows)
      ASSERT_GE(bar, last) << "margin " << margin << ", healthy maximum " << h;
      last = bar;
      // AND it is margin x the maximum wherever that leaves the statistic room above it
      if (margin * h <= knee) {
        ASSERT_DOUBLE_EQ(bar, margin * h) << "margin " << margin;
      }
      // AND a statistic pegged at the clip (clip^2) passes it while the maximum leaves room
      if (1.05 * h < clip * clip) {
        ASSERT_LT(bar, clip * clip) << "margin " << margin << ", healthy maximum " << h;
      }
    }
  }
}

TEST(IsolatorThresholds, AnOnsetBeforeGoingLiveNeedsARecentQuietSampleAndAQuietPast) {
  const double thr = 12.0;
  const std::size_t back = 50;
  // GIVEN 300 learning values of J_N at 1 (quiet) ...
  std::vector<double> J(300, 1.0);
  // ... WHEN the last 9 rise to the clip (a fault that began 0.9 s before going live)
  std::fill(J.end() - 9, J.end(), 16.0);
  // THEN it is an onset
  EXPECT_TRUE(onset_before_live(J, back, thr));
  // WHEN the rise covers the whole look-back, THEN it is not (no quiet sample in it)
  std::fill(J.end() - static_cast<std::ptrdiff_t>(back), J.end(), 16.0);
  EXPECT_FALSE(onset_before_live(J, back, thr));
  // WHEN the past was pegged every few seconds (waves), 3 of its 250 values above the bar,
  // THEN a recent dip is not an onset from a quiet state
  std::vector<double> waves(300, 1.0);
  for (std::size_t i = 10; i < 250; i += 80) waves[i] = 16.0;
  waves.back() = 16.0;
  EXPECT_FALSE(onset_before_live(waves, back, thr));
  // WHEN 2 of the 250 are above (within 1 %), THEN it still is
  waves[10] = 1.0;
  EXPECT_TRUE(onset_before_live(waves, back, thr));
  // AND a value equal to the bar counts as at or below it; nothing learned is no onset
  std::vector<double> at(100, thr);
  EXPECT_TRUE(onset_before_live(at, back, thr));
  EXPECT_FALSE(onset_before_live({}, back, thr));
}
TEST(IsolatorKinds, AFrozenOutputIsNamedStuckWhateverRaisedItFirst) {
  // GIVEN a gyro that moves (a slow swing and white noise), then jumps by 20 sigma and
  // freezes at 100 s: the jump check raises it before the stuck check has seen enough
  // repeats
  IsolationParams p;
  Isolator iso(p, Vec2(0.1, -0.05));
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sigma = 5e-4;
  std::vector<Detection> dets, gyro;
  double frozen = kNaN;
  for (int k = 0; k <= 1100; ++k) {
    const double t = 0.1 * k;
    double r = 0.02 * std::sin(0.05 * t) + sigma * n01(rng);
    if (t >= 100.0) {
      if (std::isnan(frozen)) frozen = r + 20.0 * sigma;
      r = frozen;
    }
    dets.clear();
    iso.update({t, 0.01 * n01(rng), r, 0.0}, &dets);
    for (const Detection& d : dets) {
      if (d.sensor == Sensor::kGyro) gyro.push_back(d);
    }
  }
  // THEN it is raised once as a jump (a bias), then named stuck
  ASSERT_GE(gyro.size(), 2u);
  EXPECT_TRUE(gyro[0].active && !gyro[0].update);
  EXPECT_EQ(gyro[0].kind, FaultKind::kBias);
  EXPECT_TRUE(gyro.back().active);
  EXPECT_EQ(gyro.back().kind, FaultKind::kStuck);
  EXPECT_TRUE(gyro.back().update);
}

}  // namespace
}  // namespace usvfdi
