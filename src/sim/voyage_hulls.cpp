// The hulls a voyage can drive: the vessel zoo, and the core's shipped linear vessels that the
// zoo does not hold under their names (the otter) as linear hulls.
#include <algorithm>

#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::sim {
namespace {
/// Lengths of the shipped vessels (Fossen: MSS mariner.m 160.93 m, otter.py 2.0 m).
double shipped_length(const std::string& name) { return name == "mariner" ? 160.93 : 2.0; }

std::shared_ptr<const Hull> shipped_linear(const VesselModel& v) {
  LinearHullData d;
  d.name = v.name;
  d.source = v.source;
  d.U0 = v.u0;
  d.A0 = v.A;
  d.B0 = v.B;
  const double L = shipped_length(v.name);
  d.T_u = std::max(2.0, 5.0 * L / v.u0);  // a first-order surge of 5 ship lengths' time
  d.limits = {v.max_rudder, v.max_rudder_rate, v.rudder_time_constant, L};
  return make_linear_hull(d);
}
}  // namespace

std::vector<std::string> voyage_hull_names() {
  std::vector<std::string> names;
  for (const ZooEntry& e : zoo()) names.push_back(e.name);
  for (const VesselModel& v : shipped_vessels()) {
    if (std::find(names.begin(), names.end(), v.name) == names.end()) names.push_back(v.name);
  }
  return names;
}

std::shared_ptr<const Hull> voyage_hull(const std::string& name) {
  if (const ZooEntry* e = find_hull(name)) return e->hull;
  VesselModel v;
  if (find_vessel(name, &v)) return shipped_linear(v);
  return nullptr;
}

}  // namespace usvfdi::sim
