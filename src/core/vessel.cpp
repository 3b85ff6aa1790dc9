#include "usv_fdi/core/vessel.hpp"

#include <cmath>

namespace usvfdi {
namespace {
constexpr double kDeg = M_PI / 180.0;

VesselModel make_mariner() {
  VesselModel m;
  m.name = "mariner";
  m.source = "Fossen, MSS VESSELS/models/mariner.m, linearised at U0 = 7.7175 m/s";
  m.u0 = 7.7175;
  m.A << -0.036930, -2.58499, -1.01142e-3, -0.100362;
  m.B << 0.063044, -3.74282e-3;
  m.max_rudder = 40.0 * kDeg;
  m.max_rudder_rate = 5.0 * kDeg;
  m.rudder_time_constant = 1.0;
  m.autopilot_bandwidth = 0.06;
  m.turn_angle = 20.0 * kDeg;
  m.turn_period = 120.0;
  m.sine_amplitude = 10.0 * kDeg;
  m.sine_frequency = 0.05;
  m.sigma_v = 5e-3;
  m.sigma_r = 5e-4;
  return m;
}

VesselModel make_otter() {
  VesselModel m;
  m.name = "otter";
  m.source =
      "Fossen, PythonVehicleSimulator otter.py (m = 55 + 25 kg payload), sway-yaw block "
      "linearised at u0 = 1 m/s; yaw moment of the two thrusters as an equivalent rudder "
      "(63.9 N m at 40 deg)";
  m.u0 = 1.0;
  m.A << -0.883024, -0.438614, -1.55172, -1.16124;
  m.B << 0.165394, -2.19400;
  m.max_rudder = 40.0 * kDeg;
  // The thrusters answer in 0.1 s, but the equivalent rudder of a differential-thrust
  // yaw moment is rate-limited here (10 deg/s, 0.3 s lag) like a real steering servo.
  m.max_rudder_rate = 10.0 * kDeg;
  m.rudder_time_constant = 0.3;
  m.autopilot_bandwidth = 0.6;
  m.turn_angle = 20.0 * kDeg;
  m.turn_period = 20.0;
  m.sine_amplitude = 2.0 * kDeg;
  m.sine_frequency = 0.4;
  m.sigma_v = 5e-3;
  m.sigma_r = 5e-4;
  return m;
}
}  // namespace

const VesselModel& mariner() {
  static const VesselModel m = make_mariner();
  return m;
}

const VesselModel& otter() {
  static const VesselModel m = make_otter();
  return m;
}

std::vector<VesselModel> shipped_vessels() { return {mariner(), otter()}; }

bool find_vessel(const std::string& name, VesselModel* out) {
  for (const VesselModel& m : shipped_vessels()) {
    if (m.name == name) {
      *out = m;
      return true;
    }
  }
  return false;
}

}  // namespace usvfdi
