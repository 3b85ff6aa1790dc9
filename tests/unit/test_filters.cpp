// Property tests of the exact sampled low-pass F(p) = eps / (p + eps) (FohLowPass).
//
// The reference is the closed-form response of z' = eps (u - z) to an input that is a
// polynomial of degree <= 3 over the step, evaluated in long double by a route that is
// independent of the filter's own coefficient formulas:
//   z(h) = e^{-x} z0 + a J0 + b J1 + c J2 + d J3,   u(s) = a + b s + c s^2 + d s^3,
//   J_k = int_0^h eps e^{-eps (h - s)} s^k ds
//       = h^k x sum_n (-x)^n k! / (n + k + 1)!      (series, x < 1)
//       = h^k - (k / eps) J_{k-1},  J0 = 1 - e^{-x}  (integration by parts, x >= 1)
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "usv_fdi/core/filters.hpp"

namespace usvfdi {
namespace {

using ld = long double;

/// J_0..J_3 of the header comment.
void moments(ld eps, ld h, ld J[4]) {
  const ld x = eps * h;
  if (x < 1.0L) {
    for (int k = 0; k < 4; ++k) {
      ld kfact = 1.0L;
      for (int i = 2; i <= k; ++i) kfact *= i;
      // term_n = (-x)^n k! / (n + k + 1)!
      ld denom = 1.0L;
      for (int i = 2; i <= k + 1; ++i) denom *= i;
      ld term = kfact / denom;
      ld sum = 0.0L;
      for (int n = 0; n < 40; ++n) {
        sum += term;
        term *= -x / (n + k + 2);
      }
      J[k] = std::pow(h, static_cast<ld>(k)) * x * sum;
    }
  } else {
    J[0] = -std::expm1(-x);
    J[1] = h - J[0] / eps;
    J[2] = h * h - 2.0L / eps * J[1];
    J[3] = h * h * h - 3.0L / eps * J[2];
  }
}

/// Exact response over one step to u(s) = a + b s + c s^2 + d s^3.
ld exact_step(ld z0, ld a, ld b, ld c, ld eps, ld h, ld d = 0.0L) {
  ld J[4];
  moments(eps, h, J);
  return std::exp(-eps * h) * z0 + a * J[0] + b * J[1] + c * J[2] + d * J[3];
}

/// Draws eps * h log-uniformly in [1e-6, 50] and eps log-uniformly in [1e-2, 1e2].
struct StepDraw {
  double eps, h;
};
StepDraw draw_step(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> lx(std::log(1e-6), std::log(50.0));
  std::uniform_real_distribution<double> le(std::log(1e-2), std::log(1e2));
  const double x = std::exp(lx(rng));
  const double eps = std::exp(le(rng));
  return {eps, x / eps};
}

TEST(FohLowPass, ExactForInputsLinearBetweenSamples) {
  // GIVEN random eps*h in [1e-6, 50] (plus the branch points of the coefficient formulas)
  //   and a random input that is linear between samples (random values at each sample)
  std::mt19937_64 rng(0xF0A1);
  std::uniform_real_distribution<double> uval(-5.0, 5.0);
  std::vector<double> xs = {1e-6, 1e-3 * (1 - 1e-12), 1e-3, 1e-3 * (1 + 1e-12), 1.0 - 1e-12,
                            1.0,  1.0 + 1e-12,        50.0};
  for (int i = 0; i < 400; ++i) xs.push_back(-1.0);  // random
  for (double xfix : xs) {
    StepDraw d = draw_step(rng);
    if (xfix > 0) d.h = xfix / d.eps;
    FohLowPass f(d.eps);
    f.set_step(d.h);
    double z = uval(rng);
    double u_prev = uval(rng);
    for (int k = 0; k < 20; ++k) {
      const double u_new = uval(rng);
      // WHEN the filter advances one step from a state on the reference trajectory
      const double z_new = f.step(u_prev, u_new, z);
      // THEN it matches the analytic response to the ramp u_prev -> u_new to rounding, and
      //   the error is tiny even relative to how far the state moved over the step (a
      //   zero-order hold would be off by about b h x / 2)
      const double b = (u_new - u_prev) / d.h;
      const ld ref = exact_step(z, u_prev, b, 0.0L, d.eps, d.h);
      const double x = d.eps * d.h;
      const double tol =
          1e-14 * (std::abs(z) + std::abs(u_prev) + std::abs(u_new)) +
          1e-9 * std::min(1.0, x) * (std::abs(u_prev - z) + std::abs(u_new - u_prev));
      ASSERT_NEAR(z_new, static_cast<double>(ref), tol)
          << "eps=" << d.eps << " h=" << d.h << " x=" << x << " k=" << k;
      z = z_new;
      u_prev = u_new;
    }
  }
}

TEST(FohLowPass, TracksAContinuousRampWithTheAnalyticLag) {
  // GIVEN u(t) = a + b t, z(0) = z0, random eps, and random (non-uniform) sample times
  std::mt19937_64 rng(0xF0A2);
  std::uniform_real_distribution<double> uval(-3.0, 3.0);
  std::uniform_real_distribution<double> jitter(0.5, 1.5);
  for (int c = 0; c < 200; ++c) {
    const StepDraw d = draw_step(rng);
    const double a = uval(rng), b = uval(rng), z0 = uval(rng);
    FohLowPass f(d.eps);
    double t = 0.0, z = z0;
    for (int k = 0; k < 200; ++k) {
      const double h = d.h * jitter(rng);
      f.set_step(h);
      // WHEN it is fed the samples of the ramp
      z = f.step(a + b * t, a + b * (t + h), z);
      t += h;
    }
    // THEN z(t) = a + b t - b / eps + (z0 - a + b / eps) e^{-eps t} (analytic; for a
    //   steady ramp the lag is b / eps)
    const ld eps = d.eps;
    const ld ref = a + b * static_cast<ld>(t) - b / eps +
                   (z0 - a + b / eps) * std::exp(-eps * static_cast<ld>(t));
    const double scale = std::abs(a) + std::abs(b) * (t + 1.0 / d.eps) + std::abs(z0);
    ASSERT_NEAR(z, static_cast<double>(ref), 1e-11 * scale) << "eps=" << d.eps << " h=" << d.h;
  }
}

TEST(FohLowPass, SteadyStateGainIsOne) {
  std::mt19937_64 rng(0xF0A3);
  std::uniform_real_distribution<double> uval(-100.0, 100.0);
  for (int c = 0; c < 500; ++c) {
    // GIVEN any eps*h in [1e-6, 50] and a constant input u
    const StepDraw d = draw_step(rng);
    FohLowPass f(d.eps);
    f.set_step(d.h);
    const double u = uval(rng);
    // WHEN the state already equals u
    // THEN it stays there (the three coefficients sum to one)
    ASSERT_NEAR(f.step(u, u, u), u, 4e-16 * std::abs(u)) << "x=" << d.eps * d.h;
    ASSERT_NEAR(f.step_curved(u, u, 0.0, u), u, 4e-16 * std::abs(u));
    // AND from rest the state approaches u as 1 - e^{-eps t}
    double z = 0.0;
    const int n = 7;
    for (int k = 0; k < n; ++k) z = f.step(u, u, z);
    const double expect = -std::expm1(-d.eps * d.h * n) * u;
    ASSERT_NEAR(z, expect, 1e-13 * std::abs(u)) << "x=" << d.eps * d.h;
  }
}

TEST(FohLowPass, CurvedStepIsExactForQuadraticInputs) {
  // GIVEN u(t) = a + b t + c t^2 sampled at random non-uniform times, random eps*h
  std::mt19937_64 rng(0xF0A4);
  std::uniform_real_distribution<double> uval(-2.0, 2.0);
  std::uniform_real_distribution<double> jitter(0.6, 1.4);
  for (int cs = 0; cs < 300; ++cs) {
    const StepDraw d = draw_step(rng);
    const double a = uval(rng), b = uval(rng) / d.h / 50.0, c = uval(rng) / (d.h * d.h) / 100.0;
    const auto u = [&](double t) { return a + b * t + c * t * t; };
    FohLowPass f(d.eps);
    double t_pp = 0.0, t_p = d.h * jitter(rng);
    double z = uval(rng);
    for (int k = 0; k < 30; ++k) {
      const double h = d.h * jitter(rng), hp = t_p - t_pp, t_n = t_p + h;
      f.set_step(h);
      // WHEN the curvature is taken from the last three samples and the curved step is used
      const double udd = FohLowPass::curvature(u(t_pp), u(t_p), u(t_n), hp, h);
      // THEN the divided difference recovers u'' = 2 c
      const double umax = std::abs(a) + std::abs(b) * t_n + std::abs(c) * t_n * t_n;
      ASSERT_NEAR(udd, 2.0 * c, 1e-13 * umax / (std::min(h, hp) * std::min(h, hp)));
      const double z_new = f.step_curved(u(t_p), u(t_n), 2.0 * c, z);
      // AND the step matches the analytic response to the quadratic over [t_p, t_n]
      //   (u(t_p + s) = u(t_p) + u'(t_p) s + c s^2)
      const ld ref = exact_step(z, u(t_p), b + 2.0 * c * t_p, c, d.eps, h);
      const double x = d.eps * h;
      const double tol = 1e-14 * (std::abs(z) + std::abs(u(t_p)) + std::abs(u(t_n))) +
                         1e-8 * std::min(1.0, x) * std::abs(c) * h * h;
      ASSERT_NEAR(z_new, static_cast<double>(ref), tol) << "x=" << x << " k=" << k;
      // AND without the curvature term the same step is measurably off (the test can fail)
      if (x > 1e-4 && x < 10 && std::abs(c) * h * h > 1e-3) {
        const double z_lin = f.step(u(t_p), u(t_n), z);
        ASSERT_GT(std::abs(z_lin - static_cast<double>(ref)), 100 * tol);
      }
      z = static_cast<double>(ref);
      t_pp = t_p;
      t_p = t_n;
    }
  }
}

TEST(FohLowPass, CubicStepIsExactForCubicInputs) {
  // GIVEN u(t) = a + b t + c t^2 + d t^3 sampled at random non-uniform times, random eps*h
  std::mt19937_64 rng(0xF0A5);
  std::uniform_real_distribution<double> uval(-2.0, 2.0);
  std::uniform_real_distribution<double> jitter(0.6, 1.4);
  for (int cs = 0; cs < 300; ++cs) {
    const StepDraw dr = draw_step(rng);
    const double a = uval(rng), b = uval(rng) / dr.h / 50.0;
    const double c = uval(rng) / (dr.h * dr.h) / 100.0, d = uval(rng) / std::pow(dr.h, 3) / 300.0;
    const auto u = [&](double t) { return a + t * (b + t * (c + t * d)); };
    FohLowPass f(dr.eps);
    double t_ppp = 0.0, t_pp = dr.h * jitter(rng), t_p = t_pp + dr.h * jitter(rng);
    double z = uval(rng);
    for (int k = 0; k < 30; ++k) {
      const double h = dr.h * jitter(rng), hp = t_p - t_pp, hpp = t_pp - t_ppp, t_n = t_p + h;
      f.set_step(h, hp);
      // WHEN the curvature comes from the last three samples, its change from the last four,
      //   and the cubic step is used
      const double udd = FohLowPass::curvature(u(t_pp), u(t_p), u(t_n), hp, h);
      const double udd_prev = FohLowPass::curvature(u(t_ppp), u(t_pp), u(t_p), hpp, hp);
      const double c3 = FohLowPass::third_difference(udd, udd_prev, t_n - t_ppp);
      // THEN the third divided difference recovers d
      const double umax =
          std::abs(a) + std::abs(b) * t_n + std::abs(c) * t_n * t_n + std::abs(d) * t_n * t_n * t_n;
      const double hmin = std::min({h, hp, hpp});
      ASSERT_NEAR(c3, d, 1e-12 * umax / (hmin * hmin * hmin));
      const double z_new = f.step_cubic(u(t_p), u(t_n), udd, c3, z);
      // AND the step matches the analytic response to the cubic over [t_p, t_n]
      //   (u(t_p + s) = u(t_p) + u'(t_p) s + u''(t_p)/2 s^2 + d s^3)
      const ld ref = exact_step(z, u(t_p), b + t_p * (2.0 * c + 3.0 * d * t_p), c + 3.0 * d * t_p,
                                dr.eps, h, d);
      const double x = dr.eps * h;
      const double tol = 1e-14 * (std::abs(z) + std::abs(u(t_p)) + std::abs(u(t_n))) +
                         1e-8 * std::min(1.0, x) * (std::abs(c) + std::abs(d) * t_n) * h * h;
      ASSERT_NEAR(z_new, static_cast<double>(ref), tol) << "x=" << x << " k=" << k;
      // AND without the cubic term the same step is measurably off (the test can fail)
      if (x > 1e-4 && x < 10 && std::abs(d) * h * h * h > 1e-3) {
        const double z_quad = f.step_curved(u(t_p), u(t_n), udd, z);
        ASSERT_GT(std::abs(z_quad - static_cast<double>(ref)), 100 * tol);
      }
      z = static_cast<double>(ref);
      t_ppp = t_pp;
      t_pp = t_p;
      t_p = t_n;
    }
  }
}

TEST(FohLowPass, ErrorOrderOnASmoothInputIsTwoPlainThreeCurvedFourCubic) {
  // GIVEN u = sin(w t), eps = 1, run over 10 s with steps h and h / 2
  const double w = 1.3, eps = 1.0, T = 10.0;
  const auto exact = [&](double t) {
    // z' = eps (sin(w t) - z), z(0) = 0
    const double g = eps / (eps * eps + w * w);
    return g * (eps * std::sin(w * t) - w * std::cos(w * t) + w * std::exp(-eps * t));
  };
  // order 1: first-order hold, 2: with curvature, 3: with the cubic term
  const auto run = [&](double h, int order) {
    FohLowPass f(eps);
    f.set_step(h, h);
    const int n = static_cast<int>(std::lround(T / h));
    const auto u = [&](double t) { return std::sin(w * t); };  // also before t = 0
    double z = 0.0;
    for (int k = 0; k < n; ++k) {
      const double t0 = k * h, t1 = (k + 1) * h;
      const double udd = FohLowPass::curvature(u(t0 - h), u(t0), u(t1), h, h);
      const double udd_prev = FohLowPass::curvature(u(t0 - 2 * h), u(t0 - h), u(t0), h, h);
      const double c3 = FohLowPass::third_difference(udd, udd_prev, 3 * h);
      z = order == 3   ? f.step_cubic(u(t0), u(t1), udd, c3, z)
          : order == 2 ? f.step_curved(u(t0), u(t1), udd, z)
                       : f.step(u(t0), u(t1), z);
    }
    return std::abs(z - exact(n * h));
  };
  // WHEN the step is halved
  // THEN the plain first-order-hold error falls ~4x (O(h^2)), the curved one ~8x (O(h^3))
  //   and the cubic one ~16x (O(h^4))
  const double e1 = run(0.02, 1), e2 = run(0.01, 1);
  const double c1 = run(0.02, 2), c2 = run(0.01, 2);
  const double k1 = run(0.02, 3), k2 = run(0.01, 3);
  EXPECT_NEAR(e1 / e2, 4.0, 0.4);
  EXPECT_NEAR(c1 / c2, 8.0, 1.2);
  EXPECT_NEAR(k1 / k2, 16.0, 2.4);
  EXPECT_LT(c1, 0.1 * e1);
  EXPECT_LT(k1, 0.1 * c1);
}

TEST(InputPrefilter, StartsAtSteadyStateFollowsTheCascadeAndRestartsAfterReset) {
  const double w = 0.3, h = 0.1;
  InputPrefilter f(w);
  ASSERT_TRUE(f.enabled());
  // GIVEN a constant input: the output is that input from the first sample (no transient)
  const InputPrefilter::Vec3 x0(0.2, -0.01, 0.05);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(f.step(h, x0), x0);
  // WHEN the input steps by d and is held
  const InputPrefilter::Vec3 d(1.0, -2.0, 0.5);
  InputPrefilter::Vec3 y;
  for (int k = 1; k <= 100; ++k) {
    y = f.step(h, x0 + d);
    // THEN each channel follows the sampled step response of w^2 / (p + w)^2 exactly (the
    //   input is held over each step): 1 - (1 + w t) e^{-w t} at t = k h, up to the lag of
    //   the second stage, which sees the first stage's output at the end of the step
    const double a = -std::expm1(-w * h), e = 1.0 - a;
    // Closed form of the two ZOH stages in cascade: 1 - e^k - k a e^k.
    const double expect = 1.0 - std::pow(e, k) - k * a * std::pow(e, k);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR((y(i) - x0(i)) / d(i), expect, 1e-12) << k;
  }
  // AND after reset() the next sample is passed through as the new steady state
  f.reset();
  const InputPrefilter::Vec3 x1(-1.0, 3.0, 0.0);
  EXPECT_EQ(f.step(h, x1), x1);
  // AND a bandwidth of 0 passes every sample through
  InputPrefilter off(0.0);
  EXPECT_FALSE(off.enabled());
  EXPECT_EQ(off.step(h, x0 + d), x0 + d);
}

}  // namespace
}  // namespace usvfdi
