// A sim::Hull over a shipped linear VesselModel (core): the sway-yaw model x' = A x + B delta
// of the vessel at its u0, with A scaled by U/U0 and B by (U/U0)^2 (nondimensional
// derivatives held constant, as in Nomoto's model), and a first-order surge response to the
// throttle. Stands in for the vessel zoo's models of the shipped vessels.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/sim/hull.hpp"
#include "usv_fdi/sim/voyage.hpp"  // linear_hull_names, make_linear_hull

namespace usvfdi::sim {

class LinearHull : public Hull {
 public:
  /// `length` [m] sets the time scale of the voyages; `surge_time_constant` [s] the surge
  /// response (<= 0: 5 L / U0, at least 2 s). Throws std::invalid_argument on a bad model.
  LinearHull(const VesselModel& model, double length, double surge_time_constant = 0.0);
  std::string name() const override { return m_.name; }
  std::string source() const override { return m_.source; }
  bool nonlinear() const override { return false; }
  double nominal_speed() const override { return m_.u0; }
  HullLimits limits() const override;
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override;
  const VesselModel& model() const { return m_; }

 private:
  VesselModel m_;
  double length_;
  double tau_u_;
};

}  // namespace usvfdi::sim
