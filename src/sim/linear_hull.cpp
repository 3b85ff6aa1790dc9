#include "linear_hull.hpp"

#include <algorithm>
#include <stdexcept>

namespace usvfdi::sim {
namespace {
/// Lengths between perpendiculars of the shipped vessels (Fossen, MSS mariner.m: 160.93 m;
/// PythonVehicleSimulator otter.py: 2.0 m).
double shipped_length(const std::string& name) {
  if (name == "mariner") return 160.93;
  if (name == "otter") return 2.0;
  return 0.0;
}
}  // namespace

LinearHull::LinearHull(const VesselModel& model, double length, double surge_time_constant)
    : m_(model), length_(length), tau_u_(surge_time_constant) {
  if (!(m_.u0 > 0) || !m_.A.allFinite() || !m_.B.allFinite() || !(length_ > 0)) {
    throw std::invalid_argument("LinearHull " + m_.name +
                                ": needs u0 > 0, finite A and B and a length > 0");
  }
  if (!(tau_u_ > 0)) tau_u_ = std::max(2.0, 5.0 * length_ / m_.u0);
}

HullLimits LinearHull::limits() const {
  HullLimits l;
  l.max_rudder = m_.max_rudder;
  l.max_rudder_rate = m_.max_rudder_rate;
  l.rudder_time_constant = m_.rudder_time_constant;
  l.length = length_;
  return l;
}

HullRates LinearHull::rates(const HullState& x, const HullInput& in, const Disturbance& d) const {
  const double s = x.u / m_.u0;  // A ~ U / U0, B ~ (U / U0)^2
  const Vec2 vr(x.v, x.r);
  const Vec2 f = s * (m_.A * vr) + s * s * m_.B * in.delta;
  HullRates out;
  out.du = (in.throttle * m_.u0 - x.u) / tau_u_ + d.du;
  out.dv = f(0) + d.dv;
  out.dr = f(1) + d.dr;
  return out;
}

std::vector<std::string> linear_hull_names() {
  std::vector<std::string> names;
  for (const VesselModel& m : shipped_vessels()) names.push_back(m.name);
  return names;
}

std::shared_ptr<const Hull> make_linear_hull(const std::string& name) {
  VesselModel m;
  if (!find_vessel(name, &m)) return nullptr;
  return std::make_shared<LinearHull>(m, shipped_length(name));
}

}  // namespace usvfdi::sim
