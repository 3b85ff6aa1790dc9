// The fault-kind functions (core/fault_kind.hpp, docs/design.md section 8.3): spikes and
// noise from the energy of whitened residuals, bias, drift and scale from the cross
// residual's shape, a noise rise from its spread, the onset from the abnormal run.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "usv_fdi/core/fault_kind.hpp"

namespace usvfdi {
namespace {

constexpr double kDt = 0.1;

std::vector<double> white(std::size_t n, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::vector<double> x(n);
  for (double& v : x) v = g(rng);
  return x;
}

/// d and x over 8 s at 10 Hz: d = noise + fault(t, x), x a slow sinusoid (the channel).
struct Shape {
  TimedValues d, x;
  template <class Fault>
  Shape(Fault fault, unsigned seed) {
    const std::vector<double> n = white(80, 0.05, seed);
    for (std::size_t i = 0; i < n.size(); ++i) {
      const double t = 100.0 + kDt * static_cast<double>(i);
      const double xi = 2.0 * std::sin(0.8 * t);
      x.emplace_back(t, xi);
      d.emplace_back(t, n[i] + fault(t, xi));
    }
  }
};

TEST(FaultKind, EnergyInOneOrTwoSamplesIsSpikesAndSignlessEnergyIsNoise) {
  std::vector<double> w = white(40, 1.0, 1);
  EXPECT_EQ(energy_kind(w), FaultKind::kNoise);  // healthy energy has no sign either
  w[17] += 25.0;
  EXPECT_EQ(energy_kind(w), FaultKind::kSpikes);
  std::vector<double> wide = white(40, 3.0, 2);
  EXPECT_EQ(energy_kind(wide), FaultKind::kNoise);
  std::vector<double> offset = white(40, 1.0, 3);
  for (double& v : offset) v += 4.0;
  EXPECT_EQ(energy_kind(offset), FaultKind::kUnknown);  // its shape decides
  EXPECT_EQ(energy_kind({}), FaultKind::kUnknown);
}

TEST(FaultKind, AStepIsBiasARampIsDriftAGainOnTheSignalIsScale) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const Shape step([](double t, double) { return t >= 103.0 ? 1.0 : 0.0; }, seed);
    EXPECT_EQ(shape_kind(step.d, step.x), FaultKind::kBias);
    const Shape ramp([](double t, double) { return std::max(0.0, 0.4 * (t - 102.0)); }, seed);
    EXPECT_EQ(shape_kind(ramp.d, ramp.x), FaultKind::kDrift);
    const Shape scale([](double t, double x) { return t >= 102.0 ? 0.5 * x : 0.0; }, seed);
    EXPECT_EQ(shape_kind(scale.d, scale.x), FaultKind::kScale);
  }
}

TEST(FaultKind, TooShortOrMismatchedHistoriesAreBias) {
  const Shape ramp([](double t, double) { return std::max(0.0, 0.4 * (t - 102.0)); }, 1);
  TimedValues shortd(ramp.d.begin(), ramp.d.begin() + 7),
      shortx(ramp.x.begin(), ramp.x.begin() + 7);
  EXPECT_EQ(shape_kind(shortd, shortx), FaultKind::kBias);
  TimedValues fewer_x(ramp.x.begin(), ramp.x.end() - 1);
  EXPECT_EQ(shape_kind(ramp.d, fewer_x), FaultKind::kBias);
}

TEST(FaultKind, ANoiseRiseSpreadsTheCrossResidualWithoutMovingIt) {
  const double t_raise = 105.0;
  const auto series = [&](double after_sigma, double after_offset, unsigned seed) {
    const std::vector<double> before = white(50, 0.05, seed),
                              after = white(30, after_sigma, seed + 7);
    TimedValues d;
    for (std::size_t i = 0; i < 50; ++i) d.emplace_back(100.0 + kDt * i, before[i]);
    for (std::size_t i = 0; i < 30; ++i) d.emplace_back(t_raise + kDt * i, after[i] + after_offset);
    return d;
  };
  EXPECT_TRUE(noise_rise_like(series(0.4, 0.0, 1), t_raise, 0.05));
  EXPECT_FALSE(noise_rise_like(series(0.05, 0.0, 2), t_raise, 0.05));  // nothing changed
  EXPECT_FALSE(noise_rise_like(series(0.05, 1.0, 3), t_raise, 0.05));  // an offset
  // The learned spread is the floor: a rise that stays within it is no noise rise.
  EXPECT_FALSE(noise_rise_like(series(0.4, 0.0, 4), t_raise, 0.5));
  // Too few samples after the raise to tell.
  EXPECT_FALSE(noise_rise_like(series(0.4, 0.0, 5), t_raise + 3.0, 0.05));
}

TEST(FaultKind, TheOnsetIsTheStartOfTheLatestAbnormalRun) {
  TimedValues s;
  for (int i = 0; i < 60; ++i) {
    const double t = 10.0 + kDt * i;
    double v = 0.3 * std::sin(i);
    if (i >= 20 && i < 24) v = 5.0;                   // an earlier run, separated by quiet samples
    if (i >= 40) v = i == 45 || i == 46 ? 0.1 : 4.0;  // two quiet samples inside the run
    s.emplace_back(t, v);
  }
  EXPECT_DOUBLE_EQ(abnormal_run_onset(s, 16.0), 14.0);
  TimedValues quiet(s.begin(), s.begin() + 15);
  EXPECT_DOUBLE_EQ(abnormal_run_onset(quiet, 11.5), 11.5);
}

}  // namespace
}  // namespace usvfdi
