// The registry of the vessel zoo (docs/vessels.md has the table of sources).
#include <cmath>

#include "hull_base.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
/// A shipped linear model of the core (usv_fdi/core/vessel.hpp) as linear hulls.
// (The core's otter is not one: its differential-thrust yaw moment does not scale with
// U^2 as a rudder's; otter3dof linearised at 1 m/s reproduces it, see test_hulls.cpp.)
LinearHullData from_core(const VesselModel& v, const std::string& name, double L, double T_u) {
  LinearHullData d;
  d.name = name;
  d.source = v.source;
  d.U0 = v.u0;
  d.A0 = v.A;
  d.B0 = v.B;
  d.T_u = T_u;
  d.limits = {v.max_rudder, v.max_rudder_rate, v.rudder_time_constant, L};
  return d;
}

std::vector<ZooEntry> build_zoo() {
  std::vector<ZooEntry> z;
  z.push_back({"mariner", make_mariner(), {7.7175, 5.0, 10.0}});
  z.push_back({"container", make_container(), {7.0, 5.0, 9.0}});
  z.push_back({"esso-tanker", make_esso_tanker(), {8.23, 5.0}});
  z.push_back({"kvlcc2", make_kvlcc2(7.0, 1.179), {1.179, 0.8}});
  z.push_back({"kvlcc2-full", make_kvlcc2(320.0, 7.97), {7.97, 5.0}});
  z.push_back({"otter3dof", make_otter3dof(), {2.0, 1.0, 3.0}});
  z.push_back({"lcontainer", make_linear_hull(lcontainer_data()), {7.0, 5.0, 9.0}});
  // Clarke (1983) regression for a 50 m coaster with the main dimensions of Fossen's
  // shipClarke83 example (L 50 m, B 7 m, T 5 m, Cb 0.7).
  z.push_back({"coaster",
               make_linear_hull(clarke83_data("coaster", 50.0, 7.0, 5.0, 0.7, 5.0)),
               {5.0, 3.0, 7.0}});
  // The Mariner's main dimensions (L 160.93 m, B 23.17 m, T 8.23 m, Cb 0.6) in Clarke's
  // regression: a second linear model of the same ship.
  z.push_back(
      {"mariner-clarke83",
       make_linear_hull(clarke83_data("mariner-clarke83", 160.93, 23.17, 8.23, 0.6, 7.7175)),
       {7.7175, 5.0}});
  z.push_back({"mariner-linear",
               make_linear_hull(from_core(mariner(), "mariner-linear", 160.93, 160.93)),
               {7.7175, 5.0}});
  return z;
}
}  // namespace

const std::vector<ZooEntry>& zoo() {
  static const std::vector<ZooEntry> z = build_zoo();
  return z;
}

const ZooEntry* find_hull(const std::string& name) {
  for (const ZooEntry& e : zoo()) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

}  // namespace usvfdi::sim
