// Otter USV (Maritime Robotics; L = 2 m, B = 1.08 m, 55 kg + 25 kg payload): nonlinear
// surge-sway-yaw model, M nu' + C_RB(nu) nu + C_A(nu) nu + D nu + d(nu) = tau.
//
// Source of the parameters: T. I. Fossen (2021), "Handbook of Marine Craft Hydrodynamics
// and Motion Control", 2nd ed., Wiley (the Otter example, sections 6-7 and 13), with the
// parameter values of the Otter in PythonVehicleSimulator (otter.py): masses, centre of
// gravity with payload, radius of gyration R66 = 0.25 L, added masses Xudot = -0.1 m,
// Yvdot = -1.5 m, Nrdot = -1.7 Iz, time constants T_sway = T_yaw = 1 s, max speed 6 knots
// at 24.4 kgf bollard pull (gives Xu), quadratic yaw damping 10 |Nr| |r| r, and cross-flow
// drag of one pontoon (B = 0.25 m) by strip theory with Hoerner's 2-D drag coefficient.
// Horizontal plane only: roll, pitch and heave are frozen at zero.
// Yaw control: the differential-thrust yaw moment is expressed as an equivalent rudder
// angle, N = -63.9 N m x delta / 40 deg, as the core's linear otter model (vessel.cpp).
// Throttle: the common thrust is T = throttle^2 * T0 (propeller speed ~ throttle), T0 the
// one that holds the nominal 2 m/s. Rudder sign: delta > 0 turns the boat to port (r < 0).
#include <memory>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;
using detail::kRho;

constexpr double g0 = 9.81, L = 2.0, Bp = 0.25, Cb_pont = 0.4;
constexpr double m_hull = 55.0, m_p = 25.0, m = m_hull + m_p;
constexpr double xg_hull = 0.2, xg_p = 0.05;                // [m], CG of hull and payload
constexpr double xg = (m_hull * xg_hull + m_p * xg_p) / m;  // 0.153 m
constexpr double Umax = 6 * 0.5144;                         // [m/s]
constexpr double kN_max = 63.9, kDeltaMax = 40.0 * kDeg;
constexpr double kU0 = 2.0;

struct Params {
  double Iz;             ///< yaw inertia about CG [kg m^2] (as in otter.py, payload included)
  double a11, a22, a66;  ///< added masses -Xudot, -Yvdot, -Nrdot
  double Xu, Yv, Nr;     ///< linear damping (negative)
  double T;              ///< draft [m]
  double Cd;             ///< Hoerner 2-D cross-flow drag coefficient of a pontoon
};

/// Hoerner's curve near B/2T = 0.5-0.8 (Hoerner 1965, Fluid-Dynamic Drag; as digitised
/// in Fossen 2021): linear interpolation between (0.5585, 1.0836), (0.6464, 0.9986),
/// (0.8336, 0.8796).
double hoerner(double b_over_2t) {
  const double x[] = {0.5585, 0.6464, 0.8336}, y[] = {1.0836, 0.9986, 0.8796};
  const int i = b_over_2t < x[1] ? 0 : 1;
  return y[i] + (b_over_2t - x[i]) * (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
}

Params params() {
  Params p{};
  const double R66 = 0.25 * L;
  p.Iz = m_hull * R66 * R66 + m_hull * xg * xg + m_p * xg_p * xg_p;
  p.a11 = 0.1 * m_hull;
  p.a22 = 1.5 * m_hull;
  p.a66 = 1.7 * p.Iz;
  p.Xu = -24.4 * g0 / Umax;
  p.Yv = -(m + p.a22) / 1.0;                   // T_sway = 1 s
  p.Nr = -(p.Iz + m * xg * xg + p.a66) / 1.0;  // T_yaw = 1 s
  p.T = m / kRho / (2 * Cb_pont * Bp * L);
  p.Cd = hoerner(Bp / (2 * p.T));
  return p;
}

/// Cross-flow drag of one pontoon, midpoint rule over 40 strips: [Y, N].
void cross_flow(const Params& p, double v, double r, double* Y, double* N) {
  constexpr int kStrips = 40;
  const double dx = L / kStrips;
  *Y = 0.0;
  *N = 0.0;
  for (int i = 0; i < kStrips; ++i) {
    const double x = -0.5 * L + (i + 0.5) * dx;
    const double w = v + x * r;
    const double f = -0.5 * kRho * p.T * p.Cd * std::abs(w) * w * dx;
    *Y += f;
    *N += x * f;
  }
}

class Otter3dof final : public detail::HullWithFacts {
 public:
  Otter3dof(detail::HullFacts f, Params p) : HullWithFacts(std::move(f)), p_(p) {
    T0_ = -p_.Xu * kU0;
  }
  HullRates rates(const HullState& s, const HullInput& in, const Disturbance& d) const override {
    const double u = s.u, v = s.v, r = s.r;
    double Ycf = 0.0, Ncf = 0.0;
    cross_flow(p_, v, r, &Ycf, &Ncf);
    const double tauX = in.throttle * in.throttle * T0_;
    const double tauN = -kN_max * in.delta / kDeltaMax;
    // -C_RB(nu) nu - C_A(nu) nu about the origin (CG at x = xg), then damping.
    const double X = tauX + p_.Xu * u + (m + p_.a22) * v * r + m * xg * r * r;
    const double Y = p_.Yv * v - (m + p_.a11) * u * r + Ycf;
    const double N = tauN + p_.Nr * r - 10.0 * (-p_.Nr) * std::abs(r) * r -
                     (p_.a22 - p_.a11) * u * v - m * xg * u * r + Ncf;
    double dv = 0.0, dr = 0.0;
    detail::solve_sway_yaw(m + p_.a22, m * xg, m * xg, p_.Iz + m * xg * xg + p_.a66, Y, N, &dv,
                           &dr);
    return detail::add({X / (m + p_.a11), dv, dr}, d);
  }

 private:
  Params p_;
  double T0_ = 0.0;  ///< thrust at throttle 1 [N]
};
}  // namespace

std::shared_ptr<const Hull> make_otter3dof() {
  detail::HullFacts f;
  f.name = "otter3dof";
  f.source =
      "Fossen 2021, Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed. (Otter "
      "USV), parameters of PythonVehicleSimulator otter.py; surge-sway-yaw only";
  f.nonlinear = true;
  f.nominal_speed = kU0;
  f.limits = {kDeltaMax, 10.0 * kDeg, 0.3, L};
  return std::make_shared<Otter3dof>(f, params());
}

}  // namespace usvfdi::sim
