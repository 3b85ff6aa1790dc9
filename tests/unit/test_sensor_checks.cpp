// The sensor-level checks (core/sensor_checks.hpp, docs/design.md section 8.3): stale,
// stuck (with the channel's learned quantisation), invalid, and timing errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "usv_fdi/core/isolation.hpp"
#include "usv_fdi/core/sensor_checks.hpp"

namespace usvfdi {
namespace {

constexpr double kDt = 0.1;

struct Feed {
  SensorChecks checks{IsolationParams{}};
  InputHealth input;
  double t = 0.0;  ///< the next sample's time, for move_v and hold_v
  void sample(double t, double v, double r = 0.0, double delta = 0.0) {
    checks.update(Sample{t, v, r, delta}, {true, true}, &input);
  }
  /// v = value(t) every kDt for span seconds; whether v was ever taken for stuck.
  template <class F>
  bool move_v(double span, F value) {
    bool ever_stuck = false;
    for (const double t0 = t; t < t0 + span; t += kDt) {
      sample(t, value(t));
      ever_stuck = ever_stuck || checks.verdict(kInputV).stuck;
    }
    return ever_stuck;
  }
  /// v held at value every kDt for span seconds; how long after the first of them v was first
  /// taken for stuck (NaN: never).
  double hold_v(double value, double span) {
    double stuck_at = NAN;
    for (const double t0 = t; t < t0 + span; t += kDt) {
      sample(t, value);
      if (checks.verdict(kInputV).stuck && std::isnan(stuck_at)) stuck_at = t - t0;
    }
    return stuck_at;
  }
};

TEST(SensorChecks, AFullPrecisionChannelHeldForStuckTimeIsStuckAndMovingAgainIsNot) {
  Feed f;
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 0.01);
  double t = 0.0;
  for (; t < 60.0; t += kDt) f.sample(t, n(rng), n(rng));
  EXPECT_FALSE(f.checks.verdict(kInputV).stuck);
  const double held = 0.123456;
  double stuck_at = NAN;
  for (const double t0 = t; t < t0 + 2.0; t += kDt) {
    f.sample(t, held, n(rng));
    if (f.checks.verdict(kInputV).stuck && std::isnan(stuck_at)) stuck_at = t - t0;
  }
  ASSERT_FALSE(std::isnan(stuck_at));
  EXPECT_LE(stuck_at, IsolationParams{}.stuck_time + 2 * kDt);
  EXPECT_FALSE(f.checks.verdict(kInputR).stuck);  // the other channel moves
  f.sample(t, held + 0.01, n(rng));
  EXPECT_FALSE(f.checks.verdict(kInputV).stuck);
  EXPECT_EQ(f.checks.repeats(kInputV), 0);
}

// A slow swing printed to 0.01, with noise e added before printing.
double quantised(double t, double e) {
  return std::round(100.0 * (0.05 * std::sin(0.05 * t) + e)) / 100.0;
}

TEST(SensorChecks, AQuantisedChannelThatMovesIsNotStuckButAFrozenOneIs) {
  // A noisy signal printed to 0.01 (its noise about half a quantum): it repeats its value on
  // about half of the samples, sometimes many times in a row.
  Feed f;
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 0.005);
  EXPECT_FALSE(f.move_v(600.0, [&](double t) { return quantised(t, n(rng)); }));
  // Frozen: caught at the latest after stuck_time_max.
  f.hold_v(0.42, IsolationParams{}.stuck_time_max + 0.5);
  EXPECT_TRUE(f.checks.verdict(kInputV).stuck);
}

// v printed to 3 significant digits, as the proving ground's MEMS voyages print it.
double three_digits(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return std::strtod(buf, nullptr);
}

TEST(SensorChecks, AChannelPrintedToSignificantDigitsIsJudgedByTheRateOfItsOwnDecade) {
  // Below 1 m/s the quantum is 1 mm/s, a sixth of the noise, and values seldom repeat; above
  // it the quantum is 1 cm/s and they repeat on about half of the samples. Learned over all
  // decades at once, the first seconds above 1 m/s read as a frozen output (the proving
  // ground's Mariner in its turns, "output frozen at 1.020000").
  Feed f;
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.006);
  const auto mean = [](double t) {
    return t < 300.0 ? 0.6 + 0.2 * std::sin(0.02 * t) : std::min(1.03, 0.6 + 0.01 * (t - 300.0));
  };
  EXPECT_FALSE(f.move_v(600.0, [&](double t) { return three_digits(mean(t) + n(rng)); }));
  // Frozen above 1 m/s, where the channel has moved long enough to learn its rate there:
  // caught by the improbable run before stuck_time_max.
  const IsolationParams p;
  double stuck_at = f.hold_v(1.02, p.stuck_time_max + 0.5);
  ASSERT_FALSE(std::isnan(stuck_at));
  EXPECT_LT(stuck_at, p.stuck_time_max - 1.0);
  // Moving again below 1 m/s, then frozen there: caught within a second, by the rate of its
  // own decade (a run of about 7 samples is improbable there; the rate over all decades, raised
  // by the repeats above 1 m/s, needed 1.4 s).
  f.move_v(60.0, [&](double) { return three_digits(0.6 + n(rng)); });
  EXPECT_FALSE(f.checks.verdict(kInputV).stuck);
  stuck_at = f.hold_v(0.613, 2.0);
  ASSERT_FALSE(std::isnan(stuck_at));
  EXPECT_LT(stuck_at, 1.0);
}

TEST(SensorChecks, AGapInTheStreamNeitherTeachesTheRateNorHoldsTheValue) {
  // A quantised channel that repeats on about half of its samples, then two minutes without a
  // sample (a recording paused, a link down). The gap says nothing about how the channel
  // repeats, and its first value after the gap is no repeat of the last one before: moving
  // again, it is not taken for stuck.
  Feed f;
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 0.005);
  const auto moving = [&](double t) { return quantised(t, n(rng)); };
  ASSERT_FALSE(f.move_v(600.0, moving));
  const double before_gap = f.checks.verdict(kInputV).value;
  f.t += 120.0;
  // resuming at the value it stopped at, for a few samples, then moving again
  EXPECT_TRUE(std::isnan(f.hold_v(before_gap, 0.45)));
  EXPECT_FALSE(f.move_v(120.0, moving));
  // still caught when frozen
  f.hold_v(0.42, IsolationParams{}.stuck_time_max + 0.5);
  EXPECT_TRUE(f.checks.verdict(kInputV).stuck);
}

TEST(SensorChecks, NoValidValueForStaleTimeoutIsStale) {
  Feed f;
  f.sample(0.0, 0.1);
  f.sample(0.1, NAN);
  EXPECT_FALSE(f.checks.verdict(kInputV).stale);
  f.sample(0.7, NAN);
  EXPECT_TRUE(f.checks.verdict(kInputV).stale);
  EXPECT_NEAR(f.checks.verdict(kInputV).since_valid, 0.7, 1e-12);
  f.sample(0.8, 0.2);
  EXPECT_FALSE(f.checks.verdict(kInputV).stale);
}

TEST(SensorChecks, InvalidCountAbsurdValuesWithinTheWindowAreInvalidAndAgeOut) {
  Feed f;
  const IsolationParams p;
  double t = 0.0;
  for (int k = 0; k < p.invalid_count; ++k, t += kDt) f.sample(t, 0.0, 1e3);  // |r| > max_abs_r
  EXPECT_TRUE(f.checks.verdict(kInputR).invalid);
  EXPECT_FALSE(f.checks.verdict(kInputV).invalid);
  EXPECT_EQ(f.input.invalid_values, static_cast<std::uint64_t>(p.invalid_count));
  for (const double t0 = t; t < t0 + p.spike_window + 0.5; t += kDt) f.sample(t, 0.0, 0.01);
  EXPECT_FALSE(f.checks.verdict(kInputR).invalid);
}

TEST(SensorChecks, TimingErrorsRaiseAfterInvalidCountAndClearAfterTheWindow) {
  Feed f;
  const IsolationParams p;
  for (int k = 1; k < p.invalid_count; ++k) EXPECT_FALSE(f.checks.timing_error(10.0));
  EXPECT_TRUE(f.checks.timing_error(10.0));
  EXPECT_FALSE(f.checks.timing_clear(10.0 + 0.5 * p.spike_window));
  EXPECT_TRUE(f.checks.timing_clear(10.0 + p.spike_window + 0.1));
}

}  // namespace
}  // namespace usvfdi
