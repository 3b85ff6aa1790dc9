// KVLCC2 tanker: the MMG standard manoeuvring model (hull, propeller, rudder).
//
// Source of the coefficients and of the model: H. Yasukawa and Y. Yoshimura (2015),
// "Introduction of MMG standard method for ship maneuvering predictions", J. Mar. Sci.
// Technol. 20:37-52 (principal particulars of the KVLCC2 in Table 1, the hydrodynamic
// force coefficients in Table 3). Full scale Lpp = 320 m; the free-running model (and the
// HSVA tests in ../shared/realdata) is 1:45.714, Lpp = 7 m, at 1.179 m/s (Fn 0.142).
// Equations as in section 2 of the paper (origin at midship, v = v_m).
// Throttle: propeller speed n_P = throttle * n0, n0 the one that holds u0 straight ahead.
// Rudder sign (as published): delta > 0 turns the ship to starboard (r > 0).
// gamma_R and C_2 switch at beta_R = 0 and beta_P = 0 as published: the linearisation about
// straight running (central differences) takes the mean of the two one-sided slopes.
#include <memory>
#include <stdexcept>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;
using detail::kRho;

// Table 1 (full scale) and Table 3.
constexpr double kLpp = 320.0, kB = 58.0, kd = 20.8, kNabla = 312600.0, kxG = 11.2;
constexpr double kDP = 9.86, kHR = 15.80, kAR = 112.5;
constexpr double mx_ = 0.022, my_ = 0.223, Jz_ = 0.011;  // m'_x, m'_y, J'_z
constexpr double R0 = 0.022, Xvv = -0.040, Xvr = 0.002, Xrr = 0.011, Xvvvv = 0.771;
constexpr double Yv = -0.315, Yr = 0.083, Yvvv = -1.607, Yvvr = 0.379, Yvrr = -0.391;
constexpr double Yrrr = 0.008;
constexpr double Nv = -0.137, Nr = -0.049, Nvvv = -0.030, Nvvr = -0.294, Nvrr = 0.055;
constexpr double Nrrr = -0.013;
constexpr double tP = 0.220, wP0 = 0.40, k0 = 0.2931, k1 = -0.2753, k2 = -0.1385;
constexpr double C1 = 2.0, C2pos = 1.6, C2neg = 1.1, xP_ = -0.48;
constexpr double tR = 0.387, aH = 0.312, xH_ = -0.464, xR_ = -0.5, eps = 1.09, kappa = 0.50;
constexpr double lR_ = -0.710, fa = 2.747, gRneg = 0.395, gRpos = 0.640;

struct Geometry {
  double L, d, DP, AR, eta, m, IzG, xG, mx, my, Jz;
};

Geometry geometry(double lpp) {
  const double s = kLpp / lpp;  // scale factor
  Geometry g{};
  g.L = lpp;
  g.d = kd / s;
  g.DP = kDP / s;
  g.AR = kAR / (s * s);
  g.eta = kDP / kHR;
  g.m = kRho * kNabla / (s * s * s);
  g.IzG = g.m * (0.25 * lpp) * (0.25 * lpp);
  g.xG = kxG / s;
  const double q = 0.5 * kRho * g.L * g.L * g.d;
  g.mx = mx_ * q;
  g.my = my_ * q;
  g.Jz = Jz_ * q * g.L * g.L;
  return g;
}

struct Forces {
  double X, Y, N;
};

Forces hull_forces(const Geometry& g, double u, double v, double r) {
  const double U = std::max(std::hypot(u, v), 1e-6);
  const double vp = v / U, rp = r * g.L / U;
  const double XH = -R0 + Xvv * vp * vp + Xvr * vp * rp + Xrr * rp * rp + Xvvvv * vp * vp * vp * vp;
  const double YH = Yv * vp + Yr * rp + Yvvv * vp * vp * vp + Yvvr * vp * vp * rp +
                    Yvrr * vp * rp * rp + Yrrr * rp * rp * rp;
  const double NH = Nv * vp + Nr * rp + Nvvv * vp * vp * vp + Nvvr * vp * vp * rp +
                    Nvrr * vp * rp * rp + Nrrr * rp * rp * rp;
  const double q = 0.5 * kRho * g.L * g.d * U * U;
  return {q * XH, q * YH, q * g.L * NH};
}

/// Propeller thrust share of X and the rudder forces (sections 2.3-2.4 of the paper).
Forces propeller_rudder(const Geometry& g, double u, double v, double r, double delta, double n) {
  const double U = std::max(std::hypot(u, v), 1e-6);
  const double beta = std::atan2(-v, u), rp = r * g.L / U;
  const double betaP = beta - xP_ * rp;
  const double C2 = betaP > 0 ? C2pos : C2neg;
  const double wfac = (1 - wP0) * (1 + (1 - std::exp(-C1 * std::abs(betaP))) * (C2 - 1));
  const double JP = u * wfac / (n * g.DP);
  const double KT = k0 + k1 * JP + k2 * JP * JP;
  const double XP = (1 - tP) * kRho * n * n * std::pow(g.DP, 4) * KT;
  const double betaR = beta - lR_ * rp;
  const double vR = U * (betaR < 0 ? gRneg : gRpos) * betaR;
  const double race = 1 + kappa * (std::sqrt(1 + 8 * KT / (M_PI * JP * JP)) - 1);
  const double uR = eps * u * wfac * std::sqrt(g.eta * race * race + (1 - g.eta));
  const double alphaR = delta - std::atan2(vR, uR);
  const double FN = 0.5 * kRho * g.AR * (uR * uR + vR * vR) * fa * std::sin(alphaR);
  const double xR = xR_ * g.L, xH = xH_ * g.L;
  return {XP - (1 - tR) * FN * std::sin(delta), -(1 + aH) * FN * std::cos(delta),
          -(xR + aH * xH) * FN * std::cos(delta)};
}

HullRates mmg_rates(const Geometry& g, const HullState& x, double delta, double n) {
  const Forces H = hull_forces(g, x.u, x.v, x.r);
  const Forces P = propeller_rudder(g, x.u, x.v, x.r, delta, n);
  const double X = H.X + P.X, Y = H.Y + P.Y, N = H.N + P.N;
  const double du = (X + (g.m + g.my) * x.v * x.r + g.xG * g.m * x.r * x.r) / (g.m + g.mx);
  double dv = 0.0, dr = 0.0;
  detail::solve_sway_yaw(g.m + g.my, g.xG * g.m, g.xG * g.m, g.IzG + g.xG * g.xG * g.m + g.Jz,
                         Y - (g.m + g.mx) * x.u * x.r, N - g.xG * g.m * x.u * x.r, &dv, &dr);
  return {du, dv, dr};
}

class Kvlcc2 final : public detail::HullWithFacts {
 public:
  Kvlcc2(detail::HullFacts f, Geometry g, double n0)
      : HullWithFacts(std::move(f)), g_(g), n0_(n0) {}
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override {
    HullState s = x;
    s.u = std::max(x.u, 1e-3);
    return detail::add(mmg_rates(g_, s, in.delta, std::max(in.throttle * n0_, 1e-3)), d);
  }

 private:
  Geometry g_;
  double n0_;  ///< propeller speed at throttle 1 [rps]
};

double propeller_speed_for(const Geometry& g, double u0) {
  double lo = 0.01, hi = 100.0 * 7.0 / g.L;  // [rps]; self-propulsion scales with L^-1/2
  const HullState x{u0, 0.0, 0.0};
  if (mmg_rates(g, x, 0.0, hi).du < 0) throw std::runtime_error("kvlcc2: no propeller speed");
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mmg_rates(g, x, 0.0, mid).du < 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}
}  // namespace

std::shared_ptr<const Hull> make_kvlcc2(double lpp, double u0) {
  if (!(lpp > 0.0) || !(u0 > 0.0)) throw std::invalid_argument("kvlcc2: lpp and u0 must be > 0");
  const Geometry g = geometry(lpp);
  detail::HullFacts f;
  f.name = lpp < 50.0 ? "kvlcc2" : "kvlcc2-full";
  f.source =
      "Yasukawa & Yoshimura 2015, Introduction of MMG standard method for ship maneuvering "
      "predictions, J Mar Sci Technol 20:37-52, Tables 1 and 3 (KVLCC2)";
  f.nonlinear = true;
  f.nominal_speed = u0;
  // Rudder rate 2.32 deg/s at full scale (SIMMAN), Froude-scaled: x sqrt(scale).
  const double rate = 2.32 * kDeg * std::sqrt(kLpp / lpp);
  f.limits = {35.0 * kDeg, rate, 0.1, lpp};
  return std::make_shared<Kvlcc2>(f, g, propeller_speed_for(g, u0));
}

}  // namespace usvfdi::sim
