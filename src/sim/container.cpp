// High-speed container ship (L = 175 m, the S-175 hull): nonlinear manoeuvring model with
// propeller and rudder.
//
// Source of the coefficients: K. Son and K. Nomoto (1982), "On the coupled motion of
// steering and rolling of a high-speed container ship", Naval Architecture and Ocean
// Engineering 20:73-83 (from J. Soc. Naval Arch. Japan 150, 1981); the table as given in
// Fossen's handbook (2011) and the MSS toolbox (container.m). The published model is 4-DOF
// (surge, sway, roll, yaw); here roll is frozen (phi = p = 0), which leaves the surge, sway
// and yaw equations with their roll terms dropped and the sway-yaw inertia coupling
// my * alpha_y kept. The shaft dynamics are omitted: the shaft speed is n = throttle * n0,
// with n0 [rpm] the one that holds the nominal 7 m/s in straight running.
// Rudder sign (as published): delta > 0 turns the ship to starboard (r > 0).
#include <memory>
#include <stdexcept>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;

constexpr double L = 175.0, D = 6.533, AR = 33.0376, Lambda = 1.8219;
constexpr double m = 0.00792, mx = 0.000238, my = 0.007049, alphay = 0.05;
constexpr double Iz = 0.000456, Jz = 0.000419;
constexpr double t = 0.175;
constexpr double Xuu = -0.0004226, Xvr = -0.00311, Xrr = 0.00020, Xvv = -0.00386;
constexpr double Yv = -0.0116, Yr = 0.00242, Yvvv = -0.109, Yrrr = 0.00177;
constexpr double Yvvr = 0.0214, Yvrr = -0.0405;
constexpr double Nv = -0.0038545, Nr = -0.00222, Nvvv = 0.001492, Nrrr = -0.00229;
constexpr double Nvvr = -0.0424, Nvrr = 0.00156;
constexpr double kk = 0.631, epsilon = 0.921, xR = -0.5, wp = 0.184, tau = 1.09;
constexpr double xp = -0.526, cpv = 0.0, cpr = 0.0, ga = 0.088, cRr = -0.156;
constexpr double cRrrr = -0.275, cRrrv = 1.96, cRX = 0.71, aH = 0.237, xH = -0.48;
constexpr double kU0 = 7.0;

/// Nondimensional forces (prime system: L, U) at shaft speed n [rps].
struct Forces {
  double X, Y, N;
};

Forces forces(double u, double v, double r, double delta, double n, double U) {
  const double vR = ga * v + cRr * r + cRrrr * r * r * r + cRrrv * r * r * v;
  const double uP = u * ((1 - wp) + tau * ((v + xp * r) * (v + xp * r) + cpv * v + cpr * r));
  const double J = uP * U / (n * D);
  const double KT = 0.527 - 0.455 * J;
  const double uR = uP * epsilon * std::sqrt(1 + 8 * kk * KT / (M_PI * J * J));
  const double alphaR = delta + std::atan(vR / uR);
  const double FN =
      -(6.13 * Lambda / (Lambda + 2.25)) * (AR / (L * L)) * (uR * uR + vR * vR) * std::sin(alphaR);
  const double T = 2 * D * D * D * D / (U * U * L * L) * KT * n * std::abs(n);
  const double X = Xuu * u * u + (1 - t) * T + Xvr * v * r + Xvv * v * v + Xrr * r * r +
                   cRX * FN * std::sin(delta) + (m + my) * v * r;
  const double Y = Yv * v + Yr * r + Yvvv * v * v * v + Yrrr * r * r * r + Yvvr * v * v * r +
                   Yvrr * v * r * r + (1 + aH) * FN * std::cos(delta) - (m + mx) * u * r;
  const double N = Nv * v + Nr * r + Nvvv * v * v * v + Nrrr * r * r * r + Nvvr * v * v * r +
                   Nvrr * v * r * r + (xR + aH * xH) * FN * std::cos(delta);
  return {X, Y, N};
}

class Container final : public detail::HullWithFacts {
 public:
  Container(detail::HullFacts f, double n0_rps) : HullWithFacts(std::move(f)), n0_(n0_rps) {}
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override {
    const double U = std::max(std::hypot(x.u, x.v), 1e-3);
    const Forces F = forces(x.u / U, x.v / U, x.r * L / U, in.delta, in.throttle * n0_, U);
    double dv = 0.0, dr = 0.0;
    const double m42 = my * alphay;
    detail::solve_sway_yaw(m + my, m42, m42, Iz + Jz, F.Y, F.N, &dv, &dr);
    const double s = U * U / L;
    return detail::add({F.X * s / (m + mx), dv * s, dr * s / L}, d);
  }

 private:
  double n0_;  ///< shaft speed at throttle 1 [rps]
};

/// Shaft speed [rps] whose thrust balances the resistance at U (bisection on X(n) = 0).
double shaft_speed_for(double U) {
  return detail::balancing_shaft_speed("container", 0.05, 10.0,
                                       [U](double n) { return forces(1, 0, 0, 0, n, U).X; });
}
}  // namespace

std::shared_ptr<const Hull> make_container() {
  detail::HullFacts f;
  f.name = "container";
  f.source =
      "Son & Nomoto 1982, On the coupled motion of steering and rolling of a high-speed "
      "container ship, Naval Arch. Ocean Eng. 20:73-83 (J.S.N.A. Japan 150, 1981); table as "
      "in Fossen's handbook 2011; roll frozen";
  f.nonlinear = true;
  f.nominal_speed = kU0;
  // 35 deg rudder for the standard manoeuvres, 5 deg/s rate as in the source's simulation.
  f.limits = {35.0 * kDeg, 5.0 * kDeg, 1.0, L};
  return std::make_shared<Container>(f, shaft_speed_for(kU0));
}

}  // namespace usvfdi::sim
