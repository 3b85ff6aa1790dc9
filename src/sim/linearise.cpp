// Linearisation of a hull about straight running (docs/vessels.md, "How B is computed").
#include <cmath>
#include <stdexcept>
#include <string>

#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
double surge_rate(const Hull& hull, double u0, double throttle) {
  HullInput in;
  in.throttle = throttle;
  return hull.rates({u0, 0.0, 0.0}, in, {}).du;
}

Vec2 sway_yaw_rates(const Hull& hull, const HullState& x, double delta, double throttle) {
  HullInput in;
  in.delta = delta;
  in.throttle = throttle;
  const HullRates f = hull.rates(x, in, {});
  return {f.dv, f.dr};
}
}  // namespace

double equilibrium_throttle(const Hull& hull, double u0) {
  // du increases with the throttle: bisection on [0.05, 4].
  double lo = 0.05, hi = 4.0;
  if (!(surge_rate(hull, u0, lo) < 0.0) || !(surge_rate(hull, u0, hi) > 0.0)) {
    throw std::runtime_error("hull '" + hull.name() + "': no throttle in [0.05, 4] holds u0 = " +
                             std::to_string(u0) + " m/s");
  }
  for (int i = 0; i < 100 && hi - lo > 1e-14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (surge_rate(hull, u0, mid) < 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Linearisation linearise(const Hull& hull, double u0, double h) {
  if (!(u0 > 0.0) || !(h > 0.0)) throw std::invalid_argument("linearise: u0 and h must be > 0");
  const double throttle = equilibrium_throttle(hull, u0);
  const double L = hull.limits().length;
  // Steps scaled to the state: dv ~ h u0, dr ~ h u0 / L, ddelta ~ h rad.
  const double hv = h * u0, hr = h * u0 / L, hd = h;
  const HullState x0{u0, 0.0, 0.0};
  Linearisation lin;
  lin.u0 = u0;
  lin.A.col(0) = (sway_yaw_rates(hull, {u0, hv, 0.0}, 0.0, throttle) -
                  sway_yaw_rates(hull, {u0, -hv, 0.0}, 0.0, throttle)) /
                 (2 * hv);
  lin.A.col(1) = (sway_yaw_rates(hull, {u0, 0.0, hr}, 0.0, throttle) -
                  sway_yaw_rates(hull, {u0, 0.0, -hr}, 0.0, throttle)) /
                 (2 * hr);
  lin.B =
      (sway_yaw_rates(hull, x0, hd, throttle) - sway_yaw_rates(hull, x0, -hd, throttle)) / (2 * hd);
  return lin;
}

}  // namespace usvfdi::sim
