// The speed input (core/speed.hpp, docs/design.md section 2.4): x' = s A0 x + s^2 B0 delta.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/speed.hpp"

namespace usvfdi {
namespace {

Sample at(double t, double u) {
  Sample s{t, 0.0, 0.0, 0.0};
  s.u = u;
  return s;
}

TEST(SpeedRatio, IsOneUntilMeasuredThenHeldOverMissingValuesAndClamped) {
  SpeedRatio s{SpeedParams{}};
  EXPECT_EQ(s.update(at(0, kNaN)), 1.0);
  EXPECT_FALSE(s.measured());
  EXPECT_TRUE(std::isnan(s.reference_speed()));
  EXPECT_EQ(s.update(at(1, 2.0)), 1.0);  // the first speed is the reference
  EXPECT_EQ(s.reference_speed(), 2.0);
  EXPECT_DOUBLE_EQ(s.update(at(2, 1.5)), 0.75);
  EXPECT_DOUBLE_EQ(s.update(at(3, kNaN)), 0.75);  // held
  EXPECT_DOUBLE_EQ(s.update(at(4, 0.0)), 0.25);   // a log reading 0: clamped
  EXPECT_DOUBLE_EQ(s.update(at(5, 100.0)), 4.0);
  SpeedParams p;
  p.reference_speed = 4.0;
  SpeedRatio r{p};
  EXPECT_DOUBLE_EQ(r.update(at(0, 2.0)), 0.5);
  EXPECT_DOUBLE_EQ(r.input_factor(0.5), 0.25);
}

TEST(SpeedRatio, BadParametersNameTheKey) {
  SpeedParams p;
  p.reference_speed = -1.0;
  try {
    p.validate();
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("model.reference_speed"), std::string::npos) << e.what();
  }
  p = SpeedParams{};
  p.max_ratio = 0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

struct SpeedRun {
  int raised = 0;
  double a_error = 1.0;  ///< relative error of the final estimate against A0
  bool armed = false;
};

/// A linear vessel whose dynamics follow its speed exactly (x' = s A0 x + s^2 B0 delta),
/// at 10 Hz with white INS noise, steered by a multisine rudder; the speed falls by 30 %
/// and recovers. with_u: the samples carry the speed.
SpeedRun run_speed_change(bool with_u) {
  Mat2 A0;
  A0 << -0.5, -0.3, -0.8, -1.2;
  const Vec2 B0(0.165, -2.19);
  EngineConfig cfg;
  cfg.B = B0;
  FdiEngine eng(cfg);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01;
  const double dt = 0.1, U0 = 2.0;
  const auto speed = [&](double t) {
    if (t < 1000) return U0;
    if (t < 1500) return U0 * (1.0 - 0.3 * (t - 1000) / 500);
    if (t < 2000) return 0.7 * U0;
    return U0 * (0.7 + 0.3 * std::min(1.0, (t - 2000) / 300));
  };
  const auto delta = [](double t) {
    return 0.1 * std::sin(0.21 * t) + 0.05 * std::sin(0.73 * t + 1) + 0.03 * std::sin(1.3 * t);
  };
  Vec2 x = Vec2::Zero();
  SpeedRun out;
  std::vector<FaultEvent> ev;
  for (int k = 0; k < 30000; ++k) {
    const double t = k * dt, s = speed(t) / U0;
    const auto f = [&](const Vec2& xx, double tt) {
      return Vec2(s * A0 * xx + s * s * B0 * delta(tt));
    };
    const int sub = 10;
    const double h = dt / sub;
    for (int j = 0; j < sub; ++j) {  // RK4
      const double tt = t + j * h;
      const Vec2 k1 = f(x, tt), k2 = f(x + 0.5 * h * k1, tt + 0.5 * h),
                 k3 = f(x + 0.5 * h * k2, tt + 0.5 * h), k4 = f(x + h * k3, tt + h);
      x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    Sample smp{t + dt, x(0) + 0.01 * n01(rng), x(1) + 0.0005 * n01(rng), delta(t + dt)};
    if (with_u) smp.u = speed(t + dt);
    ev.clear();
    eng.process(smp, &ev);
    for (const FaultEvent& e : ev) out.raised += e.state == FaultState::kRaised;
  }
  out.a_error = (eng.estimate().A - A0).norm() / A0.norm();
  out.armed = eng.isolation_status().armed;
  return out;
}

TEST(SpeedInput, ASpeedChangeIsFollowedAndRaisesNoFault) {
  const SpeedRun with = run_speed_change(true);
  EXPECT_TRUE(with.armed);
  EXPECT_EQ(with.raised, 0);
  EXPECT_LT(with.a_error, 0.02);
  // The same data without the speed: the slower vessel contradicts the model learned at
  // U0 (the failure the input removes).
  const SpeedRun without = run_speed_change(false);
  EXPECT_GT(without.raised, 0);
}

}  // namespace
}  // namespace usvfdi

namespace usvfdi {
namespace {

TEST(ModelMismatch, DynamicsThatChangeOnBothChannelsAreAMismatchNotASensorFault) {
  // The isolation stage on the true model, then the vessel's dynamics change at once (A and
  // B as at 60 % of the speed, without a speed input): both structured residuals leave
  // their healthy range, which no single sensor fault does. The verdict is a model
  // mismatch (status, reason, count); no sensor fault from the residuals stays raised.
  Mat2 A0;
  A0 << -0.5, -0.3, -0.8, -1.2;
  const Vec2 B0(0.165, -2.19);
  Isolator iso(IsolationParams{}, B0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  const double dt = 0.1;
  const auto delta = [](double t) {
    return 0.1 * std::sin(0.21 * t) + 0.05 * std::sin(0.73 * t + 1) + 0.03 * std::sin(1.3 * t);
  };
  Vec2 x = Vec2::Zero();
  std::vector<Detection> out;
  bool mismatch_seen = false;
  for (int k = 0; k < 8000; ++k) {
    const double t = k * dt;
    const double s = t < 400.0 ? 1.0 : 0.6;
    const int sub = 10;
    const double h = dt / sub;
    for (int j = 0; j < sub; ++j) {  // Euler substeps suffice for this purpose
      const double tt = t + j * h;
      x += h * (s * A0 * x + s * s * B0 * delta(tt));
    }
    const Sample smp{t + dt, x(0) + 0.01 * n01(rng), x(1) + 0.0005 * n01(rng), delta(t + dt)};
    iso.update(smp, &out);
    if (k == 0) {
      Estimate est;
      est.A = A0;
      est.converged = true;
      iso.set_estimate(est);
    }
    if (t < 400.0) {
      ASSERT_TRUE(out.empty()) << "healthy: " << out.front().message;
    }
    mismatch_seen = mismatch_seen || iso.status().model_mismatch;
    if (iso.status().model_mismatch) {
      EXPECT_FALSE(iso.status().mismatch_reason.empty());
    }
  }
  EXPECT_TRUE(mismatch_seen);
  EXPECT_GE(iso.status().mismatches, 1u);
  // Every residual raise after the change was withdrawn as the mismatch it was.
  int raised = 0, withdrawn = 0;
  for (const Detection& d : out) {
    if (d.sensor == Sensor::kUnknown) ADD_FAILURE() << "an unknown-sensor fault: " << d.message;
    if (d.active && !d.update) ++raised;
    if (!d.active && d.message.find("withdrawn: model mismatch") != std::string::npos) ++withdrawn;
  }
  EXPECT_EQ(raised, withdrawn);
}

}  // namespace
}  // namespace usvfdi
