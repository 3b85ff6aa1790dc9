// Property tests of the DREM identification of A (Identifier), both the paper's two-filter
// form and the Kreisselmeier form, on noise-free data generated in closed form:
//   delta(t) = sum_j alpha_j sin(w_j t + phi_j),
//   x(t) = x_ss(t) + e^{A t} (x0 - x_ss(0)),  x_ss(t) = sum_j Im[(i w_j - A)^{-1} B alpha_j
//   e^{i(w_j t + phi_j)}]
// (the transient is propagated with expm(A h), so the data are exact to rounding).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "usv_fdi/core/identification.hpp"

namespace usvfdi {
namespace {

using cd = std::complex<double>;

/// A random Hurwitz 2x2 matrix with eigenvalue real parts in [-3, -0.1] and |a_n| >= 0.05.
Mat2 random_stable_A(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (;;) {
    Mat2 A;
    A << u(rng), u(rng), u(rng), u(rng);
    if (A.cwiseAbs().minCoeff() < 0.05) continue;
    const Eigen::Vector2cd ev = A.eigenvalues();
    if (ev.real().maxCoeff() < -0.1 && ev.real().minCoeff() > -3.0) return A;
  }
}

struct Data {
  Mat2 A;
  Vec2 B;
  std::vector<Sample> samples;
};

/// Noise-free samples at rate_hz over [0, T] of x' = A x + B delta (closed form).
Data make_data(std::mt19937_64& rng, const Mat2& A, double eps_scale, double rate_hz, double T) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> lw(std::log(0.2), std::log(1.5));
  Data d;
  d.A = A;
  do {
    d.B << u(rng), u(rng);
  } while (d.B.cwiseAbs().minCoeff() < 0.1);
  const int nsin = 3;
  double alpha[nsin], w[nsin], phi[nsin];
  Eigen::Vector2cd g[nsin];
  for (int j = 0; j < nsin; ++j) {
    alpha[j] = 0.2 * (0.5 + 0.5 * std::abs(u(rng)));
    w[j] = eps_scale * std::exp(lw(rng));
    phi[j] = M_PI * u(rng);
    const Eigen::Matrix2cd M = cd(0.0, w[j]) * Eigen::Matrix2cd::Identity() - A.cast<cd>();
    g[j] = M.partialPivLu().solve(d.B.cast<cd>()) * alpha[j];
  }
  const auto xss = [&](double t) {
    Vec2 x = Vec2::Zero();
    for (int j = 0; j < nsin; ++j) x += (g[j] * std::exp(cd(0.0, w[j] * t + phi[j]))).imag();
    return x;
  };
  const auto delta = [&](double t) {
    double s = 0.0;
    for (int j = 0; j < nsin; ++j) s += alpha[j] * std::sin(w[j] * t + phi[j]);
    return s;
  };
  const double h = 1.0 / rate_hz;
  const Mat2 Phi = (A * h).exp();
  Vec2 e = Vec2(0.3 * u(rng), 0.3 * u(rng)) - xss(0.0);  // transient part
  const int n = static_cast<int>(std::lround(T * rate_hz));
  d.samples.reserve(n + 1);
  for (int k = 0; k <= n; ++k) {
    const double t = k * h;
    const Vec2 x = xss(t) + e;
    d.samples.push_back(Sample{t, x(0), x(1), delta(t)});
    e = Phi * e;
  }
  return d;
}

IdentificationParams params_for(IdentMethod method, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> le(std::log(0.5), std::log(2.0));
  IdentificationParams p;
  p.method = method;
  p.eps1 = std::exp(le(rng));
  p.eps2 = 2.0 * p.eps1;
  p.lambda = 0.05;
  // Long enough for the e^{-eps t} transient of the zero-initialised filters to vanish
  // to rounding (the DREM identity is exact only after it).
  p.warmup_time = 35.0 / p.eps1;
  return p;
}

/// Tolerance of h = psi a relative to |a| times the regressor scale. The paper's
/// R = [q; q_bar] has columns of very different size when v and r differ in scale, which
/// its column-norm product underrates; the Kreisselmeier Phi is symmetric and well scaled.
double identity_tolerance(IdentMethod m) { return m == IdentMethod::kPaper ? 1e-3 : 1e-4; }

const char* name(IdentMethod m) { return m == IdentMethod::kPaper ? "paper" : "kreisselmeier"; }

class DremProperty : public ::testing::TestWithParam<IdentMethod> {};

TEST_P(DremProperty, MixedRegressorIdentityAndLinearRegressionHoldOnExactData) {
  std::mt19937_64 rng(GetParam() == IdentMethod::kPaper ? 101 : 102);
  double worst_identity = 0.0, worst_regression = 0.0;
  for (int c = 0; c < 30; ++c) {
    // GIVEN a random stable A, random B, a random smooth input, noise-free exact data
    const Mat2 A = random_stable_A(rng);
    IdentificationParams p = params_for(GetParam(), rng);
    const Data d = make_data(rng, A, p.eps1, 50.0, p.warmup_time + 30.0);
    Identifier id(p, d.B);
    const Vec4 a = to_params(A);
    int checked = 0;
    double q_max = 0.0, reg_err = 0.0, id_err = 0.0;
    double t_reg = 0.0, t_id = 0.0;
    for (const Sample& s : d.samples) {
      // WHEN every sample is fed
      ASSERT_TRUE(id.update(s, false));
      if (id.estimate().warming_up) continue;
      // THEN after warm-up m = A q (relative to |A| max|q|: the error is a discretisation
      //   error of the signal, not of |q(t)|, which may pass near zero)
      q_max = std::max(q_max, id.q().norm());
      const double e_reg = (id.m() - A * id.q()).norm() / A.norm();
      if (e_reg > reg_err) reg_err = e_reg, t_reg = s.t;
      // AND h_n = psi a_n, relative to |psi| |a| / excitation = |a| times the scale of the
      //   extended regressor (its column-norm product), which does not vanish where psi does
      const double exc = id.estimate().excitation;
      if (!(exc > 0)) continue;
      const double e_id = (id.h() - id.psi() * a).norm() * exc / (std::abs(id.psi()) * a.norm());
      if (e_id > id_err) id_err = e_id, t_id = s.t;
      ++checked;
    }
    EXPECT_LT(reg_err / q_max, 2e-5) << name(GetParam()) << " case " << c << " t=" << t_reg;
    EXPECT_LT(id_err, identity_tolerance(GetParam()))
        << name(GetParam()) << " case " << c << " t=" << t_id;
    worst_regression = std::max(worst_regression, reg_err / q_max);
    worst_identity = std::max(worst_identity, id_err);
    ASSERT_GT(checked, 500) << "the regressor was never excited; the test checks nothing";
    // AND the estimate has converged to A
    const Mat2 Ahat = id.estimate().A;
    EXPECT_LT((Ahat - A).norm() / A.norm(), 1e-4) << name(GetParam()) << " case " << c;
  }
  std::cout << "[ INFO     ] worst relative errors: m = A q " << worst_regression << ", h = psi a "
            << worst_identity << "\n";
}

TEST_P(DremProperty, EachEstimateConvergesMonotonically) {
  std::mt19937_64 rng(GetParam() == IdentMethod::kPaper ? 201 : 202);
  for (int c = 0; c < 30; ++c) {
    // GIVEN noise-free data and an initial estimate far from A
    const Mat2 A = random_stable_A(rng);
    IdentificationParams p = params_for(GetParam(), rng);
    p.a0 = Vec4(3.0, -3.0, 3.0, 3.0);
    const Data d = make_data(rng, A, p.eps1, 50.0, p.warmup_time + 25.0);
    Identifier id(p, d.B);
    const Vec4 a = to_params(A);
    Vec4 err_prev = (p.a0 - a).cwiseAbs();
    // Allowed growth per sample: the sampled identity h = psi a holds to ~1e-7 relative
    // (O(h^3) of the first-order hold with curvature) and each step can move a^_n at most by
    // that much toward a wrong target. The paper's R = [q; q_bar] is ill conditioned near
    // the zero crossings of psi (DESIGN.md section 2, finding 2), which amplifies it ~1e3x.
    const double slack = (GetParam() == IdentMethod::kPaper ? 2e-3 : 1e-6) * a.norm();
    for (const Sample& s : d.samples) {
      // WHEN each sample is fed
      ASSERT_TRUE(id.update(s, false));
      // THEN no |a^_n - a_n| ever grows (beyond the identity's discretisation error), and
      //   it falls monotonically from its initial value ~5 |a| to the 1e-4 |a| checked below
      const Vec4 err = (to_params(id.estimate().A) - a).cwiseAbs();
      for (int n = 0; n < 4; ++n) {
        ASSERT_LE(err(n), err_prev(n) + slack)
            << name(GetParam()) << " case " << c << " a" << n + 1 << " t=" << s.t;
      }
      err_prev = err;
    }
    // AND it actually converged (a frozen estimator would pass the check above)
    EXPECT_LT(err_prev.maxCoeff(), 1e-4 * a.norm()) << name(GetParam()) << " case " << c;
  }
}

TEST_P(DremProperty, HugeGainStaysStable) {
  std::mt19937_64 rng(GetParam() == IdentMethod::kPaper ? 301 : 302);
  const double tol = identity_tolerance(GetParam());
  int total_good = 0;
  for (int c = 0; c < 20; ++c) {
    for (bool normalised : {true, false}) {
      // GIVEN a gain so large that gamma psi^2 dt >> 1 (an explicit Euler step would diverge)
      const Mat2 A = random_stable_A(rng);
      IdentificationParams p = params_for(GetParam(), rng);
      p.normalised = normalised;
      p.gamma = normalised ? 1e9 : 1e14;
      const Data d = make_data(rng, A, p.eps1, 50.0, p.warmup_time + 20.0);
      Identifier id(p, d.B);
      int good = 0;
      for (const Sample& s : d.samples) {
        // WHEN the data are fed
        ASSERT_TRUE(id.update(s, false));
        // THEN the estimate stays finite and, wherever the regressor is well conditioned,
        //   equals h / psi = A (the exact scalar update jumps straight to its target)
        ASSERT_TRUE(id.estimate().A.allFinite());
        if (id.estimate().warming_up || !(id.estimate().excitation > 0)) continue;
        if (id.estimate().time_constant > 1e-4) continue;  // gain not yet "huge"
        //   (the same scale-relative tolerance as the identity test: tol / excitation)
        ASSERT_LT((id.estimate().A - A).norm() / A.norm(), tol / id.estimate().excitation)
            << name(GetParam()) << " case " << c << " normalised=" << normalised << " t=" << s.t;
        ++good;
      }
      total_good += good;
    }
  }
  EXPECT_GT(total_good, 20 * 500);  // most cases were checked over most of their length
}

TEST_P(DremProperty, FreezeChangesNothingAndFrozenSamplesAreIgnored) {
  std::mt19937_64 rng(GetParam() == IdentMethod::kPaper ? 401 : 402);
  std::uniform_real_distribution<double> garbage(-50.0, 50.0);
  for (int c = 0; c < 20; ++c) {
    // GIVEN an identifier part-way through converging on noise-free data
    const Mat2 A = random_stable_A(rng);
    IdentificationParams p = params_for(GetParam(), rng);
    p.a0 = Vec4(1.0, 1.0, 1.0, 1.0);
    const Data d = make_data(rng, A, p.eps1, 50.0, 2.0 * p.warmup_time + 40.0);
    Identifier frozen(p, d.B), skipping(p, d.B);
    const double t_f0 = p.warmup_time + 2.0, t_f1 = t_f0 + 3.0;  // longer than max_gap
    Estimate at_freeze;
    double err_at_freeze = 0.0;
    bool saw_freeze = false;
    for (const Sample& s : d.samples) {
      const bool in_freeze = s.t >= t_f0 && s.t < t_f1;
      if (!in_freeze) {
        ASSERT_TRUE(frozen.update(s, false));
        ASSERT_TRUE(skipping.update(s, false));
        // THEN (after the freeze) the frozen identifier is bit-identical to one that never
        //   saw the frozen samples at all
        ASSERT_EQ(frozen.estimate().A, skipping.estimate().A) << "t=" << s.t;
        ASSERT_EQ(frozen.estimate().updates, skipping.estimate().updates);
        ASSERT_EQ(frozen.psi(), skipping.psi());
        continue;
      }
      if (!saw_freeze) {
        saw_freeze = true;
        at_freeze = frozen.estimate();
        err_at_freeze = (at_freeze.A - A).norm();
        ASSERT_GT(err_at_freeze, 1e-3) << "freeze must begin before convergence";
      }
      // WHEN samples full of garbage (a sensor fault) arrive with freeze = true
      Sample bad = s;
      bad.v += garbage(rng);
      bad.r += garbage(rng);
      ASSERT_TRUE(frozen.update(bad, true));
      // THEN nothing in the estimate changes
      ASSERT_EQ(frozen.estimate().A, at_freeze.A);
      ASSERT_EQ(frozen.estimate().updates, at_freeze.updates);
      ASSERT_EQ(frozen.estimate().converged, at_freeze.converged);
      ASSERT_TRUE(frozen.estimate().frozen);
      ASSERT_EQ(frozen.estimate().t, s.t);
    }
    ASSERT_TRUE(saw_freeze);
    // AND after the freeze the estimate kept converging to A
    const double err_end = (frozen.estimate().A - A).norm();
    EXPECT_LT(err_end, 1e-4 * A.norm()) << name(GetParam()) << " case " << c;
    EXPECT_LT(err_end, 1e-2 * err_at_freeze);
    EXPECT_FALSE(frozen.estimate().frozen);
  }
}

/// Every observable piece of an identifier's state, for "changes nothing" checks.
void expect_same_state(const Identifier& x, const Identifier& y) {
  ASSERT_EQ(x.estimate().A, y.estimate().A);
  ASSERT_EQ(x.estimate().updates, y.estimate().updates);
  ASSERT_EQ(x.estimate().warming_up, y.estimate().warming_up);
  ASSERT_EQ(x.estimate().frozen, y.estimate().frozen);
  ASSERT_EQ(x.estimate().converged, y.estimate().converged);
  ASSERT_EQ(x.estimate().excitation, y.estimate().excitation);
  ASSERT_TRUE(x.estimate().t == y.estimate().t ||
              (std::isnan(x.estimate().t) && std::isnan(y.estimate().t)));
  ASSERT_EQ(x.psi(), y.psi());
  ASSERT_EQ(x.h(), y.h());
  ASSERT_EQ(x.q(), y.q());
  ASSERT_EQ(x.m(), y.m());
}

TEST_P(DremProperty, RejectedInputsReturnFalseAndChangeNothing) {
  std::mt19937_64 rng(GetParam() == IdentMethod::kPaper ? 501 : 502);
  std::uniform_int_distribution<int> field(0, 3), kind(0, 4);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double bad_values[] = {kNaN, std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity()};
  for (int c = 0; c < 10; ++c) {
    // GIVEN two identical identifiers on the same noise-free data
    const Mat2 A = random_stable_A(rng);
    IdentificationParams p = params_for(GetParam(), rng);
    const Data d = make_data(rng, A, p.eps1, 50.0, p.warmup_time + 10.0);
    Identifier clean(p, d.B), dirty(p, d.B);
    int rejected = 0;
    for (std::size_t k = 0; k < d.samples.size(); ++k) {
      const Sample& s = d.samples[k];
      // WHEN the dirty one is also fed, at random, a sample with a non-finite value or a
      //   time that does not increase (equal to or before the last accepted sample), with
      //   or without a freeze request
      if (k > 0 && u01(rng) < 0.2) {
        Sample bad = s;
        const int kd = kind(rng);
        if (kd <= 2) {
          double* f[] = {&bad.t, &bad.v, &bad.r, &bad.delta};
          *f[field(rng)] = bad_values[kd];
        } else if (kd == 3) {
          bad.t = d.samples[k - 1].t;
        } else {
          bad.t = d.samples[k - 1].t - 0.5 * u01(rng);
        }
        const bool freeze = u01(rng) < 0.3;
        // THEN it is refused and nothing observable changes
        ASSERT_FALSE(dirty.update(bad, freeze)) << "kind " << kd << " k=" << k;
        expect_same_state(clean, dirty);
        ++rejected;
      }
      ASSERT_TRUE(clean.update(s, false));
      ASSERT_TRUE(dirty.update(s, false));
      // AND the future is unaffected (bit-identical)
      expect_same_state(clean, dirty);
    }
    EXPECT_GT(rejected, 100);
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, DremProperty,
                         ::testing::Values(IdentMethod::kPaper, IdentMethod::kKreisselmeier),
                         [](const ::testing::TestParamInfo<IdentMethod>& i) {
                           return std::string(name(i.param));
                         });

// Disabled: fails on the current core. Identifier::update compares s.t with prev_.t, the
// last *unfrozen* sample, so after a freeze a sample older than the last frozen one is
// accepted and estimate().t goes back (identification.cpp, `have_prev_ && !(s.t > prev_.t)`).
// Enable once update() compares with the last accepted time.
TEST(Identifier, DISABLED_TimeMustIncreaseAcrossFrozenSamplesToo) {
  // GIVEN an identifier that accepted samples up to t = 1.0 and then frozen samples up to 2.0
  IdentificationParams p;
  Identifier id(p, Vec2(0.1, -1.0));
  double t = 0.0;
  for (; t <= 1.0 + 1e-9; t += 0.02) ASSERT_TRUE(id.update(Sample{t, 0.1, 0.01, 0.05}, false));
  for (; t <= 2.0 + 1e-9; t += 0.02) ASSERT_TRUE(id.update(Sample{t, 0.1, 0.01, 0.05}, true));
  const double t_last = id.estimate().t;
  // WHEN a sample older than the last frozen one arrives
  // THEN it is refused (time does not increase) and the estimate time does not go back
  EXPECT_FALSE(id.update(Sample{1.5, 0.1, 0.01, 0.05}, true));
  EXPECT_FALSE(id.update(Sample{1.5, 0.1, 0.01, 0.05}, false));
  EXPECT_EQ(id.estimate().t, t_last);
}

TEST(IdentificationParams, ValidateNamesTheOffendingField) {
  const auto message = [](IdentificationParams p) {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  IdentificationParams p;
  EXPECT_EQ(message(p), "");
  p.eps1 = 0.0;
  EXPECT_NE(message(p).find("eps1"), std::string::npos);
  p = IdentificationParams{};
  p.method = IdentMethod::kPaper;
  p.eps2 = p.eps1;
  EXPECT_NE(message(p).find("eps2"), std::string::npos);
  p = IdentificationParams{};
  p.gamma = kNaN;
  EXPECT_NE(message(p).find("gamma"), std::string::npos);
  p = IdentificationParams{};
  p.min_excitation = 1.5;
  EXPECT_NE(message(p).find("min_excitation"), std::string::npos);
  EXPECT_THROW(Identifier(IdentificationParams{}, Vec2(kNaN, 1.0)), std::invalid_argument);
}

}  // namespace
}  // namespace usvfdi
