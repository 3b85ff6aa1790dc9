// Property tests of the dedicated observers (docs/design.md section 3): pole placement, exact
// discretisation, the discrete Lyapunov solver, and the structured-residual directions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "usv_fdi/core/observer.hpp"

namespace usvfdi {
namespace {

using cd = std::complex<double>;
using Mat22 = Eigen::Matrix<double, 2, 2>;

Mat2 random_matrix(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Mat2 M;
  M << u(rng), u(rng), u(rng), u(rng);
  return M;
}

/// Hurwitz, eigenvalue real parts in [-2, -0.1], every |a_n| >= 0.05.
Mat2 random_stable_A(std::mt19937_64& rng) {
  for (;;) {
    const Mat2 A = random_matrix(rng, 2.0);
    if (A.cwiseAbs().minCoeff() < 0.05) continue;
    const Eigen::Vector2cd ev = A.eigenvalues();
    if (ev.real().maxCoeff() < -0.1 && ev.real().minCoeff() > -2.0) return A;
  }
}

/// Two real negative poles in [lo, hi] (lo < hi < 0); sometimes a double pole.
Vec2 random_poles(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi), u01(0.0, 1.0);
  const double p1 = u(rng);
  return Vec2(p1, u01(rng) < 0.2 ? p1 : u(rng));
}

TEST(PlacePoles, PutsTheObserverPolesWhereAsked) {
  std::mt19937_64 rng(0x0B51);
  std::uniform_real_distribution<double> lsig(std::log(1e-4), std::log(1.0));
  for (int c = 0; c < 2000; ++c) {
    // GIVEN a random A (stable or not) whose coupling entry for the channel is nonzero
    //   (a2 for channel kV, a3 for kR), random negative poles and random noise scales
    const int channel = c % 2 == 0 ? kV : kR;
    Mat2 A = random_matrix(rng, 3.0);
    const double coupling = channel == kV ? A(0, 1) : A(1, 0);
    if (std::abs(coupling) < 0.05) continue;
    const Vec2 p = random_poles(rng, -4.0, -0.1);
    const double sv = std::exp(lsig(rng)), sr = std::exp(lsig(rng));
    // WHEN the gain is placed
    const ObserverDesign d = place_poles(A, channel, p(0), p(1), sv, sr, 1e-12);
    ASSERT_TRUE(d.ok) << d.reason;
    EXPECT_TRUE(d.reason.empty());
    // THEN F = A - k e_c^T
    Mat2 F = A;
    F.col(channel) -= d.k;
    ASSERT_LT((d.F - F).norm(), 1e-12 * (A.norm() + d.k.norm()));
    // AND the characteristic polynomial of F is (s - p1)(s - p2)
    const double scale = std::abs(p(0)) + std::abs(p(1)) + A.norm();
    ASSERT_NEAR(d.F.trace(), p(0) + p(1), 1e-11 * scale) << "case " << c;
    ASSERT_NEAR(d.F.determinant(), p(0) * p(1), 1e-11 * scale * scale) << "case " << c;
    // AND (for well separated poles) its eigenvalues are p1, p2
    if (std::abs(p(0) - p(1)) > 0.05) {
      Eigen::Vector2cd ev = d.F.eigenvalues();
      std::vector<double> re = {ev(0).real(), ev(1).real()}, want = {p(0), p(1)};
      std::sort(re.begin(), re.end());
      std::sort(want.begin(), want.end());
      EXPECT_NEAR(re[0], want[0], 1e-8 * scale);
      EXPECT_NEAR(re[1], want[1], 1e-8 * scale);
      EXPECT_LT(std::abs(ev(0).imag()) + std::abs(ev(1).imag()), 1e-8 * scale);
    }
    // AND the observability index is the whitened coupling over sqrt(p1 p2)
    const double index = channel == kV ? std::abs(A(0, 1)) * sr / sv : std::abs(A(1, 0)) * sv / sr;
    EXPECT_NEAR(d.observability, index / std::sqrt(p(0) * p(1)), 1e-12 * d.observability);
  }
}

TEST(PlacePoles, RefusesNearUnobservablePairsAndBadPoles) {
  std::mt19937_64 rng(0x0B52);
  std::uniform_real_distribution<double> tiny(-1e-9, 1e-9);
  for (int c = 0; c < 500; ++c) {
    // GIVEN a random A whose a3 (resp. a2) is practically zero
    Mat2 A = random_matrix(rng, 2.0);
    const Vec2 p = random_poles(rng, -2.0, -0.2);
    Mat2 A3 = A, A2 = A;
    A3(1, 0) = tiny(rng);
    A2(0, 1) = tiny(rng);
    // WHEN the gyro-driven observer (kR) is designed on the first and the accelerometer-
    //   driven one (kV) on the second
    const ObserverDesign g = place_poles(A3, kR, p(0), p(1), 1.0, 1.0, 1e-6);
    const ObserverDesign v = place_poles(A2, kV, p(0), p(1), 1.0, 1.0, 1e-6);
    // THEN both are refused, with a reason naming the vanishing coupling
    EXPECT_FALSE(g.ok);
    EXPECT_NE(g.reason.find("a3"), std::string::npos) << g.reason;
    EXPECT_FALSE(v.ok);
    EXPECT_NE(v.reason.find("a2"), std::string::npos) << v.reason;
    // AND the other channel, which does not need that coupling, is still designed
    if (std::abs(A(0, 1)) > 0.05) {
      EXPECT_TRUE(place_poles(A3, kV, p(0), p(1), 1, 1, 1e-6).ok);
    }
    if (std::abs(A(1, 0)) > 0.05) {
      EXPECT_TRUE(place_poles(A2, kR, p(0), p(1), 1, 1, 1e-6).ok);
    }
  }
  // AND the threshold is the documented index: accepted at it, refused just below it
  Mat2 A;
  A << -1.0, 0.5, 0.2, -1.0;
  const double idx = 0.2 / std::sqrt(0.5 * 0.8);
  EXPECT_TRUE(place_poles(A, kR, -0.5, -0.8, 1.0, 1.0, idx * (1 - 1e-12)).ok);
  EXPECT_FALSE(place_poles(A, kR, -0.5, -0.8, 1.0, 1.0, idx * (1 + 1e-12)).ok);
  // AND non-negative or non-finite poles and a non-finite A are refused
  EXPECT_FALSE(place_poles(A, kV, 0.0, -1.0, 1, 1, 1e-6).ok);
  EXPECT_FALSE(place_poles(A, kV, -1.0, 0.3, 1, 1, 1e-6).ok);
  EXPECT_FALSE(place_poles(A, kV, -1.0, kNaN, 1, 1, 1e-6).ok);
  EXPECT_FALSE(place_poles(A, kV, -1.0, -std::numeric_limits<double>::infinity(), 1, 1, 1e-6).ok);
  Mat2 An = A;
  An(1, 1) = kNaN;
  const ObserverDesign dn = place_poles(An, kV, -1.0, -2.0, 1, 1, 1e-6);
  EXPECT_FALSE(dn.ok);
  EXPECT_FALSE(dn.reason.empty());
}

/// RK4 of Phi' = M Phi, Gamma' = Phi N over [0, h] (Phi(0) = I, Gamma(0) = 0).
void rk4_zoh(const Mat2& M, const Mat22& N, double h, int n, Mat2* Phi, Mat22* Gam) {
  Mat2 P = Mat2::Identity();
  Mat22 G = Mat22::Zero();
  const double s = h / n;
  for (int i = 0; i < n; ++i) {
    const Mat2 k1 = M * P, k2 = M * (P + 0.5 * s * k1), k3 = M * (P + 0.5 * s * k2),
               k4 = M * (P + s * k3);
    const Mat22 g1 = P * N, g2 = (P + 0.5 * s * k1) * N, g3 = (P + 0.5 * s * k2) * N,
                g4 = (P + s * k3) * N;
    P += s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    G += s / 6.0 * (g1 + 2 * g2 + 2 * g3 + g4);
  }
  *Phi = P;
  *Gam = G;
}

TEST(ZohDiscretise, MatchesNumericalIntegrationAndComposes) {
  std::mt19937_64 rng(0x0B53);
  std::uniform_real_distribution<double> lh(std::log(1e-3), std::log(2.0));
  for (int c = 0; c < 300; ++c) {
    // GIVEN a random M (any stability), N and step h
    const Mat2 M = random_matrix(rng, 2.0);
    const Mat22 N = random_matrix(rng, 3.0);
    const double h = std::exp(lh(rng));
    // WHEN it is discretised
    Mat2 Md, Phi;
    Mat22 Nd, Gam;
    zoh_discretise(M, N, h, &Md, &Nd);
    // THEN it matches RK4 on a fine grid: exp(M h) and int_0^h exp(M s) ds N
    rk4_zoh(M, N, h, 2000, &Phi, &Gam);
    EXPECT_LT((Md - Phi).norm(), 1e-10 * Phi.norm()) << "h=" << h;
    EXPECT_LT((Nd - Gam).norm(), 1e-10 * (Gam.norm() + h * N.norm())) << "h=" << h;
    // AND two steps compose: Md(h1 + h2) = Md(h2) Md(h1), Nd(h1 + h2) = Nd(h1) + Md(h1) Nd(h2)
    Mat2 M1, M2, M12;
    Mat22 N1, N2, N12;
    const double h1 = 0.3 * h, h2 = 0.7 * h;
    zoh_discretise(M, N, h1, &M1, &N1);
    zoh_discretise(M, N, h2, &M2, &N2);
    zoh_discretise(M, N, h1 + h2, &M12, &N12);
    EXPECT_LT((M12 - M2 * M1).norm(), 1e-12 * M12.norm());
    EXPECT_LT((N12 - (N1 + M1 * N2)).norm(), 1e-12 * (N12.norm() + h * N.norm()));
  }
}

TEST(DiscreteLyapunov, MatchesBruteForceSummation) {
  std::mt19937_64 rng(0x0B54);
  std::uniform_real_distribution<double> rad(0.0, 0.995), u(-1.0, 1.0);
  for (int c = 0; c < 300; ++c) {
    // GIVEN a random (often non-normal) Schur-stable Ad with spectral radius up to 0.995
    Mat2 Ad = random_matrix(rng, 3.0);
    const double rho0 = Ad.eigenvalues().cwiseAbs().maxCoeff();
    if (!(rho0 > 1e-6)) continue;
    Ad *= rad(rng) / rho0;
    const Vec2 g(u(rng), u(rng));
    // WHEN the stationary covariance is solved
    Mat2 P;
    ASSERT_TRUE(discrete_lyapunov(Ad, g, &P)) << Ad;
    // THEN it equals sum_j Ad^j g g^T Ad^jT summed term by term
    Mat2 S = Mat2::Zero();
    Vec2 x = g;
    for (int j = 0; j < 200000; ++j) {
      S += x * x.transpose();
      x = Ad * x;
      if (x.squaredNorm() < 1e-22 * S.norm()) break;
    }
    EXPECT_LT((P - S).norm(), 1e-9 * S.norm()) << "rho=" << Ad.eigenvalues().cwiseAbs().maxCoeff();
    // AND it solves P = Ad P Ad^T + g g^T and is symmetric positive semi-definite
    EXPECT_LT((P - Ad * P * Ad.transpose() - g * g.transpose()).norm(), 1e-9 * P.norm());
    EXPECT_LT(std::abs(P(0, 1) - P(1, 0)), 1e-12 * P.norm());
    EXPECT_GE(P.trace(), 0.0);
    EXPECT_GE(P.determinant(), -1e-9 * P.squaredNorm());
  }
}

TEST(DiscreteLyapunov, RefusesUnstableAndMarginalMatrices) {
  std::mt19937_64 rng(0x0B55);
  std::uniform_real_distribution<double> rad(1.0, 3.0);
  for (int c = 0; c < 300; ++c) {
    // GIVEN Ad with spectral radius >= 1
    Mat2 Ad = random_matrix(rng, 2.0);
    const double rho0 = Ad.eigenvalues().cwiseAbs().maxCoeff();
    if (!(rho0 > 1e-6)) continue;
    Ad *= (c == 0 ? 1.0 : rad(rng)) / rho0;
    // WHEN / THEN the solver refuses (no finite stationary covariance exists)
    Mat2 P;
    EXPECT_FALSE(discrete_lyapunov(Ad, Vec2(1.0, 0.5), &P)) << Ad;
  }
  // AND a pure rotation (|eig| = 1) is refused
  Mat2 R;
  R << std::cos(0.3), -std::sin(0.3), std::sin(0.3), std::cos(0.3);
  Mat2 P;
  EXPECT_FALSE(discrete_lyapunov(R, Vec2(1.0, 0.0), &P));
}

/// RK4 on a fine grid of x' = A x + B u(s), u linear from u0 to u1 over [0, h].
Vec2 rk4_linear_input(const Mat2& A, const Vec2& B, const Vec2& x0, double u0, double u1, double h,
                      int n) {
  const auto f = [&](double s, const Vec2& x) -> Vec2 {
    return A * x + B * (u0 + (u1 - u0) * s / h);
  };
  const double ds = h / n;
  Vec2 x = x0;
  for (int i = 0; i < n; ++i) {
    const double s = i * ds;
    const Vec2 k1 = f(s, x), k2 = f(s + 0.5 * ds, x + 0.5 * ds * k1);
    const Vec2 k3 = f(s + 0.5 * ds, x + 0.5 * ds * k2), k4 = f(s + ds, x + ds * k3);
    x += ds / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return x;
}

TEST(FohDiscretise, MatchesNumericalIntegrationWithALinearInput) {
  std::mt19937_64 rng(0x0B58);
  std::uniform_real_distribution<double> u(-1.0, 1.0), lh(std::log(1e-3), std::log(2.0));
  for (int c = 0; c < 300; ++c) {
    // GIVEN a random A (any stability), B, state, input ramp and step
    const Mat2 A = random_matrix(rng, 2.0);
    const Vec2 B(u(rng), u(rng)), x0(u(rng), u(rng));
    const double h = std::exp(lh(rng)), u0 = u(rng), u1 = u(rng);
    // WHEN it is discretised with a first-order hold
    Mat2 Phi;
    Vec2 Ga, Gb;
    foh_discretise(A, B, h, &Phi, &Ga, &Gb);
    // THEN one step is the exact response to the ramp from u0 to u1
    const Vec2 want = rk4_linear_input(A, B, x0, u0, u1, h, 2000);
    const Vec2 got = Phi * x0 + Ga * u0 + Gb * u1;
    EXPECT_LT((got - want).norm(), 1e-10 * (1.0 + want.norm())) << "h=" << h;
    // AND a held input (u0 = u1) gives the zero-order hold
    Mat2 Md;
    Mat22 Nd, N;
    N << B, Vec2::Zero();
    zoh_discretise(A, N, h, &Md, &Nd);
    EXPECT_LT((Phi - Md).norm(), 1e-12 * (1.0 + Md.norm()));
    EXPECT_LT((Ga + Gb - Nd.col(0)).norm(), 1e-12 * (1.0 + Nd.col(0).norm()));
  }
}

TEST(DedicatedObserver, StepIsTheExactSampledModelPlusAPlacedCorrection) {
  std::mt19937_64 rng(0x0B56);
  std::uniform_real_distribution<double> u(-1.0, 1.0), lh(std::log(1e-3), std::log(0.5));
  for (int c = 0; c < 200; ++c) {
    // GIVEN a designed observer at a random state, a random rudder ramp, measurement, step
    const int channel = c % 2 == 0 ? kV : kR;
    const Mat2 A = random_stable_A(rng);
    const Vec2 B(u(rng), u(rng));
    const Vec2 p = random_poles(rng, -3.0, -0.2);
    const ObserverDesign d = place_poles(A, channel, p(0), p(1), 1.0, 1.0, 1e-9);
    ASSERT_TRUE(d.ok);
    DedicatedObserver obs;
    obs.set_channel(channel);
    obs.set_design(d, B);
    ASSERT_TRUE(obs.ready());
    const Vec2 x0(u(rng), u(rng));
    obs.reset(x0);
    const double h = std::exp(lh(rng)), d0 = u(rng), d1 = u(rng), yc = u(rng);
    // WHEN it steps without the measurement (open loop) and with it (closed loop)
    obs.step(h, d0, d1, yc, false);
    const Vec2 open = obs.x();
    obs.reset(x0);
    obs.step(h, d0, d1, yc, true);
    const Vec2 closed = obs.x();
    // THEN open loop = the exact response of x' = A x + B delta to the rudder ramp (the
    //   measurement is not used at all)
    const Vec2 want_open = rk4_linear_input(A, B, x0, d0, d1, h, 1000);
    EXPECT_LT((open - want_open).norm(), 1e-10 * (1 + want_open.norm()));
    // AND closed loop adds L (y_c - x0_c), with L placing the error poles at exp(p_i h)
    const Vec2 L = obs.Gy();
    EXPECT_LT((closed - (open + L * (yc - x0(channel)))).norm(), 1e-12 * (1 + closed.norm()));
    Eigen::Vector2d z = obs.Ad().eigenvalues().real();
    std::sort(z.data(), z.data() + 2);
    Eigen::Vector2d want_z(std::exp(p(0) * h), std::exp(p(1) * h));
    std::sort(want_z.data(), want_z.data() + 2);
    EXPECT_LT((z - want_z).cwiseAbs().maxCoeff(), 1e-6) << "p=" << p.transpose() << " h=" << h;
    EXPECT_LT(obs.Ad().eigenvalues().imag().cwiseAbs().maxCoeff(), 1e-4);
    // AND only the driving channel enters: L's correction uses y_c alone
    EXPECT_LT((obs.Ad() - (obs.Phi() - L * Eigen::RowVector2d::Unit(channel))).norm(), 1e-15);
    // AND a redesign keeps the state (bumpless), and the next step of the same length uses
    //   the new design
    const ObserverDesign d2 = place_poles(A, channel, -1.0, -1.5, 1, 1, 1e-9);
    obs.reset(open);
    obs.set_design(d2, B);
    EXPECT_EQ(obs.x(), open);
    obs.step(h, d0, d1, yc, true);
    Eigen::Vector2d z2 = obs.Ad().eigenvalues().real();
    std::sort(z2.data(), z2.data() + 2);
    EXPECT_NEAR(z2(0), std::exp(-1.5 * h), 1e-6);
    EXPECT_NEAR(z2(1), std::exp(-1.0 * h), 1e-6);
    const Vec2 want2 =
        rk4_linear_input(A, B, open, d0, d1, h, 1000) + obs.Gy() * (yc - open(channel));
    EXPECT_LT((obs.x() - want2).norm(), 1e-10 * (1 + want2.norm()));
    obs.reset(open);
    // AND a refused design makes it not ready, and a non-ready observer does not move
    obs.set_design(ObserverDesign{}, B);
    EXPECT_FALSE(obs.ready());
    obs.step(h, d0, d1, yc, true);
    EXPECT_EQ(obs.x(), open);
  }
}

// ---- Structured residuals ----------------------------------------------------------------

/// Noise-free data x' = A x + B delta, delta a sum of sinusoids, in closed form.
struct Plant {
  std::vector<double> t, delta;
  std::vector<Vec2> x;
};
Plant make_plant(std::mt19937_64& rng, const Mat2& A, const Vec2& B, double h, double T) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), lw(std::log(0.1), std::log(2.0));
  const int nsin = 3;
  double alpha[nsin], w[nsin], phi[nsin];
  Eigen::Vector2cd g[nsin];
  for (int j = 0; j < nsin; ++j) {
    alpha[j] = 0.2 * u(rng);
    w[j] = std::exp(lw(rng));
    phi[j] = M_PI * u(rng);
    const Eigen::Matrix2cd M = cd(0.0, w[j]) * Eigen::Matrix2cd::Identity() - A.cast<cd>();
    g[j] = M.partialPivLu().solve(B.cast<cd>()) * alpha[j];
  }
  Plant p;
  const Mat2 Phi = (A * h).exp();
  Vec2 e(0.2 * u(rng), 0.2 * u(rng));
  const int n = static_cast<int>(std::lround(T / h));
  for (int k = 0; k <= n; ++k) {
    const double t = k * h;
    Vec2 x = e;
    double d = 0.0;
    for (int j = 0; j < nsin; ++j) {
      x += (g[j] * std::exp(cd(0.0, w[j] * t + phi[j]))).imag();
      d += alpha[j] * std::sin(w[j] * t + phi[j]);
    }
    p.t.push_back(t);
    p.delta.push_back(d);
    p.x.push_back(x);
    e = Phi * e;
  }
  return p;
}

/// Residuals y_k - x^(k|k-1) of one observer run over measured outputs y (as the isolator
/// runs it: the rudder linear between samples, the driving measurement of t_{k-1}).
std::vector<Vec2> residuals(const ObserverDesign& d, int channel, const Vec2& B, const Plant& p,
                            const std::vector<Vec2>& y) {
  DedicatedObserver obs;
  obs.set_channel(channel);
  obs.set_design(d, B);
  obs.reset(y[0]);
  std::vector<Vec2> r(y.size(), Vec2::Zero());
  for (std::size_t k = 1; k < y.size(); ++k) {
    obs.step(p.t[k] - p.t[k - 1], p.delta[k - 1], p.delta[k], y[k - 1](channel), true);
    r[k] = y[k] - obs.x();
  }
  return r;
}

TEST(StructuredResidual, EachSensorFaultStaysOnItsOwnDirection) {
  std::mt19937_64 rng(0x0B57);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  const double h = 0.02, T = 60.0, t0 = 20.0;
  double worst_healthy = 0.0;
  for (int c = 0; c < 60; ++c) {
    // GIVEN random stable A, B, observer poles, noise-free data, and both observers
    //   (V driven by the accelerometer channel y1, G by the gyro y2)
    const Mat2 A = random_stable_A(rng);
    const Vec2 B(u(rng), u(rng));
    const Vec2 pv = random_poles(rng, -3.0, -0.8), pg = random_poles(rng, -3.0, -0.8);
    const ObserverDesign dv = place_poles(A, kV, pv(0), pv(1), 1, 1, 1e-9);
    const ObserverDesign dg = place_poles(A, kR, pg(0), pg(1), 1, 1, 1e-9);
    ASSERT_TRUE(dv.ok && dg.ok);
    const Plant p = make_plant(rng, A, B, h, T);
    // AND a fault on one sensor from t0: a bias or a ramp
    const int faulty = c % 2 == 0 ? kV : kR;  // kV: accelerometer, kR: gyro
    const bool ramp = (c / 2) % 2 == 1;
    const double mag = (0.05 + u01(rng)) * (u(rng) < 0 ? -1 : 1);
    std::vector<double> f(p.t.size(), 0.0);
    std::vector<Vec2> y_ok = p.x, y_bad = p.x;
    for (std::size_t k = 0; k < p.t.size(); ++k) {
      if (p.t[k] >= t0) f[k] = ramp ? mag * (p.t[k] - t0) : mag;
      y_bad[k](faulty) += f[k];
    }
    const double fmax = std::max(std::abs(f.back()), std::abs(mag));
    // WHEN both observers run on the healthy and on the faulty data
    const std::vector<Vec2> rv_ok = residuals(dv, kV, B, p, y_ok),
                            rv_bad = residuals(dv, kV, B, p, y_bad);
    const std::vector<Vec2> rg_ok = residuals(dg, kR, B, p, y_ok),
                            rg_bad = residuals(dg, kR, B, p, y_bad);
    // THEN the observer driven by the healthy sensor is untouched by the fault: its full
    //   residual changes by exactly f l_faulty (r^G = l_a f_a, r^V = l_g f_g)
    const std::vector<Vec2>& other_ok = faulty == kV ? rg_ok : rv_ok;
    const std::vector<Vec2>& other_bad = faulty == kV ? rg_bad : rv_bad;
    // AND the observer driven by the faulty sensor follows the error system
    //   e+ = (Phi - L e_c^T) e + L f_k, its residual changing by f - e_c
    const ObserverDesign& dd = faulty == kV ? dv : dg;
    DedicatedObserver probe;
    probe.set_channel(faulty);
    probe.set_design(dd, B);
    probe.step(h, 0.0, 0.0, 0.0, true);  // discretises for h
    const Mat2 E = probe.Ad();
    const Vec2 G = probe.Gy();
    const std::vector<Vec2>& own_ok = faulty == kV ? rv_ok : rg_ok;
    const std::vector<Vec2>& own_bad = faulty == kV ? rv_bad : rg_bad;
    Vec2 e = Vec2::Zero();
    const int healthy = 1 - faulty;
    for (std::size_t k = 1; k < p.t.size(); ++k) {
      e = E * e + G * f[k - 1];
      const Vec2 d_other = other_bad[k] - other_ok[k];
      ASSERT_NEAR(d_other(faulty), f[k], 1e-9 * fmax) << "case " << c << " k=" << k;
      ASSERT_NEAR(d_other(healthy), 0.0, 1e-9 * fmax) << "case " << c << " k=" << k;
      const Vec2 d_own = own_bad[k] - own_ok[k];
      ASSERT_NEAR(d_own(faulty), f[k] - e(faulty), 1e-9 * fmax) << "case " << c << " k=" << k;
      // AND the structured residual s = [r1^V, r2^G] moves along l_faulty only:
      //   C_faulty = 1, C_healthy = 0 whenever it moved at all
      const Vec2 ds(rv_bad[k](kV) - rv_ok[k](kV), rg_bad[k](kR) - rg_ok[k](kR));
      ASSERT_LE(std::abs(ds(healthy)), 1e-12 * fmax) << "case " << c << " k=" << k;
      if (f[k] != 0.0) {
        ASSERT_GT(std::abs(ds(faulty)), 0.0);
      }
    }
    // AND for a bias, the dedicated residual settles at f det(I - Phi) / det(I - Phi + L c)
    //   (1 - c (zI - E)^-1 L = det(zI - Phi) / det(zI - E) at z = 1), which is the
    //   continuous det(A) / (p1 p2) to O(h)
    if (!ramp) {
      const Vec2& pp = faulty == kV ? pv : pg;
      const Mat2 I = Mat2::Identity();
      const double dc = (I - probe.Phi()).determinant() / (I - E).determinant();
      const double settled = own_bad.back()(faulty) - own_ok.back()(faulty);
      EXPECT_NEAR(settled, mag * dc, 1e-6 * std::abs(mag)) << "case " << c;
      const double dc_cont = A.determinant() / (pp(0) * pp(1));
      EXPECT_NEAR(dc, dc_cont, 0.05 * std::abs(dc_cont) + 1e-3) << "case " << c;
    }
    // AND on healthy data both observers track the vessel exactly but for the rudder's
    //   deviation from a straight line over a step (O(h^2) of the first-order hold)
    double xmax = 0.0, rmax = 0.0;
    for (std::size_t k = 0; k < p.t.size(); ++k) {
      xmax = std::max(xmax, p.x[k].cwiseAbs().maxCoeff());
      if (p.t[k] < 10.0) continue;
      rmax = std::max({rmax, rv_ok[k].cwiseAbs().maxCoeff(), rg_ok[k].cwiseAbs().maxCoeff()});
    }
    worst_healthy = std::max(worst_healthy, rmax / xmax);
    EXPECT_LT(rmax, 1e-3 * xmax) << "case " << c;
  }
  std::cout << "[ INFO     ] worst healthy residual / max|x|: " << worst_healthy << "\n";
}

}  // namespace
}  // namespace usvfdi

namespace usvfdi {
namespace {

TEST(ObserverStepBand, AStepLengthThatMovesEverySampleMatchesTheExactDiscretisation) {
  // The vessel's own time at a changing speed: a step that differs a little on every sample
  // is taken with first-order corrected matrices; the state must follow the exactly
  // re-discretised observer to far below any noise (second order in the step difference).
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat2 A = random_stable_A(rng);
    const Vec2 B(0.2, -1.5);
    for (int channel : {kV, kR}) {
      const ObserverDesign d = place_poles(A, channel, -0.5, -0.7, 0.01, 0.001, 0.0);
      if (!d.ok) continue;
      DedicatedObserver exact, banded;
      for (DedicatedObserver* o : {&exact, &banded}) {
        o->set_channel(channel);
        o->set_design(d, B);
        o->reset(Vec2(0.1, -0.02));
      }
      banded.set_step_band(0.005);
      double max_diff = 0.0, max_x = 0.0;
      for (int k = 0; k < 2000; ++k) {
        const double h = 0.1 * (1.0 + 0.3 * std::sin(0.001 * k));  // 0.7 .. 1.3 x
        const double dp = 0.1 * std::sin(0.05 * k), dn = 0.1 * std::sin(0.05 * (k + 1));
        const double y = 0.05 * std::cos(0.03 * k);
        exact.step(h, dp, dn, y, true);
        banded.step(h, dp, dn, y, true);
        max_diff = std::max(max_diff, (exact.x() - banded.x()).cwiseAbs().maxCoeff());
        max_x = std::max(max_x, exact.x().cwiseAbs().maxCoeff());
      }
      EXPECT_LT(max_diff, 1e-5 * max_x) << "trial " << trial << " channel " << channel;
    }
  }
}

}  // namespace
}  // namespace usvfdi
