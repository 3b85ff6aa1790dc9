// Mariner class vessel (L = 160.93 m): nonlinear 3-DOF manoeuvring model.
//
// Source of the coefficients: M. S. Chislett and J. Strom-Tejsen (1965), "Planar motion
// mechanism tests and full-scale steering and manoeuvring predictions for a Mariner class
// vessel", Hydro- and Aerodynamics Laboratory, Lyngby, Report Hy-5; as tabulated in
// T. I. Fossen, "Handbook of Marine Craft Hydrodynamics and Motion Control" (Wiley 2011/
// 2021) and in the MSS toolbox (mariner.m). Nondimensional (prime system, L and U), surge
// as the perturbation u' = (u - U0)/U about the approach speed U0.
//
// Throttle: the published model is written about an approach speed U0 with the propeller
// at the rpm that holds it; a throttle t sets the approach speed U0 = t * 7.7175 m/s (the
// model's own optional U0), so the surge equilibrium is u = t * 7.7175 m/s.
// Rudder sign (as published): delta > 0 turns the ship to port (r < 0).
#include <memory>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;

// Nondimensional coefficients (x 1e-5 in the source's table).
constexpr double e5 = 1e-5;
constexpr double m = 798 * e5, Iz = 39.2 * e5, xG = -0.023;
constexpr double Xudot = -42 * e5, Yvdot = -748 * e5, Nvdot = 4.646 * e5;
constexpr double Yrdot = -9.354 * e5, Nrdot = -43.8 * e5;
constexpr double Xu = -184 * e5, Xuu = -110 * e5, Xuuu = -215 * e5, Xvv = -899 * e5;
constexpr double Xrr = 18 * e5, Xdd = -95 * e5, Xudd = -190 * e5, Xrv = 798 * e5;
constexpr double Xvd = 93 * e5, Xuvd = 93 * e5;
constexpr double Yv = -1160 * e5, Yr = -499 * e5, Yvvv = -8078 * e5, Yvvr = 15356 * e5;
constexpr double Yvu = -1160 * e5, Yru = -499 * e5, Yd = 278 * e5, Yddd = -90 * e5;
constexpr double Yud = 556 * e5, Yuud = 278 * e5, Yvdd = -4 * e5, Yvvd = 1190 * e5;
constexpr double Y0 = -4 * e5, Y0u = -8 * e5, Y0uu = -4 * e5;
constexpr double Nv = -264 * e5, Nr = -166 * e5, Nvvv = 1636 * e5, Nvvr = -5483 * e5;
constexpr double Nvu = -264 * e5, Nru = -166 * e5, Nd = -139 * e5, Nddd = 45 * e5;
constexpr double Nud = -278 * e5, Nuud = -139 * e5, Nvdd = 13 * e5, Nvvd = -489 * e5;
constexpr double N0 = 3 * e5, N0u = 6 * e5, N0uu = 3 * e5;
constexpr double L = 160.93;
constexpr double kU0 = 7.7175;  // 15 knots

// Y0, N0 (the propeller's asymmetry) are a small constant bias as published.
class Mariner final : public detail::HullWithFacts {
 public:
  using HullWithFacts::HullWithFacts;
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override {
    const double U = std::hypot(x.u, x.v);
    const double u = (x.u - in.throttle * kU0) / U, v = x.v / U, r = x.r * L / U;
    const double dl = in.delta;
    const double X = Xu * u + Xuu * u * u + Xuuu * u * u * u + Xvv * v * v + Xrr * r * r +
                     Xrv * r * v + Xdd * dl * dl + Xudd * u * dl * dl + Xvd * v * dl +
                     Xuvd * u * v * dl;
    const double Y = Yv * v + Yr * r + Yvvv * v * v * v + Yvvr * v * v * r + Yvu * v * u +
                     Yru * r * u + Yd * dl + Yddd * dl * dl * dl + Yud * u * dl +
                     Yuud * u * u * dl + Yvdd * v * dl * dl + Yvvd * v * v * dl +
                     (Y0 + Y0u * u + Y0uu * u * u);
    const double N = Nv * v + Nr * r + Nvvv * v * v * v + Nvvr * v * v * r + Nvu * v * u +
                     Nru * r * u + Nd * dl + Nddd * dl * dl * dl + Nud * u * dl +
                     Nuud * u * u * dl + Nvdd * v * dl * dl + Nvvd * v * v * dl +
                     (N0 + N0u * u + N0uu * u * u);
    double dv = 0.0, dr = 0.0;
    detail::solve_sway_yaw(m - Yvdot, m * xG - Yrdot, m * xG - Nvdot, Iz - Nrdot, Y, N, &dv, &dr);
    const double s = U * U / L;
    return detail::add({X * s / (m - Xudot), dv * s, dr * s / L}, d);
  }
};
}  // namespace

std::shared_ptr<const Hull> make_mariner() {
  detail::HullFacts f;
  f.name = "mariner";
  f.source =
      "Chislett & Strom-Tejsen 1965, Hy-5, Lyngby (PMM coefficients), as tabulated in "
      "Fossen, Handbook of Marine Craft Hydrodynamics and Motion Control, 2011";
  f.nonlinear = true;
  f.nominal_speed = kU0;
  f.limits = {40.0 * kDeg, 5.0 * kDeg, 1.0, L};
  return std::make_shared<Mariner>(f);
}

}  // namespace usvfdi::sim
