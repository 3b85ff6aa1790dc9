// Shared helpers of the hull models (internal to usv_fdi_sim).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include "usv_fdi/sim/hull.hpp"

namespace usvfdi::sim::detail {

constexpr double kDeg = M_PI / 180.0;
constexpr double kRho = 1025.0;  ///< sea water [kg/m^3]

/// The facts every hull has besides its equations.
struct HullFacts {
  std::string name;
  std::string source;
  bool nonlinear = true;
  double nominal_speed = 0.0;
  HullLimits limits;
};

/// Implements the descriptive part of Hull from HullFacts.
class HullWithFacts : public Hull {
 public:
  explicit HullWithFacts(HullFacts facts) : facts_(std::move(facts)) {}
  std::string name() const override { return facts_.name; }
  std::string source() const override { return facts_.source; }
  bool nonlinear() const override { return facts_.nonlinear; }
  double nominal_speed() const override { return facts_.nominal_speed; }
  HullLimits limits() const override { return facts_.limits; }

 protected:
  HullFacts facts_;
};

inline HullRates add(const HullRates& a, const Disturbance& d) {
  return {a.du + d.du, a.dv + d.dv, a.dr + d.dr};
}

/// Solves the 2x2 sway-yaw inertia system [m22 m23; m32 m33] [dv dr] = [Y N].
inline void solve_sway_yaw(double m22, double m23, double m32, double m33, double Y, double N,
                           double* dv, double* dr) {
  const double det = m22 * m33 - m23 * m32;
  *dv = (m33 * Y - m23 * N) / det;
  *dr = (m22 * N - m32 * Y) / det;
}

/// The shaft speed [rps] in [lo, hi] at which a surge force (or acceleration) that rises with
/// the shaft speed, surge(n), is zero: the thrust that balances the resistance. 200 bisection
/// steps; throws "<hull>: no shaft speed" if even hi leaves surge(hi) < 0.
template <class Surge>
double balancing_shaft_speed(const char* hull, double lo, double hi, Surge surge) {
  if (surge(hi) < 0) throw std::runtime_error(std::string(hull) + ": no shaft speed");
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (surge(mid) < 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace usvfdi::sim::detail
