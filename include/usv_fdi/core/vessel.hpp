// Shipped vessel models (linear Nomoto-type sway-yaw models at a constant surge speed).
#pragma once

#include <string>
#include <vector>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

struct VesselModel {
  std::string name;
  std::string source;     ///< where the coefficients come from
  double u0 = 0.0;        ///< surge speed of the linearisation [m/s]
  Mat2 A = Mat2::Zero();  ///< x' = A x + B delta [1/s, ...]
  Vec2 B = Vec2::Zero();
  double max_rudder = 0.0;            ///< rudder saturation [rad]
  double max_rudder_rate = 0.0;       ///< rudder rate limit [rad/s]
  double rudder_time_constant = 0.0;  ///< first-order servo [s]
  double autopilot_bandwidth = 0.0;   ///< natural frequency of the heading loop [rad/s]
  double turn_angle = 0.0;            ///< heading change of the scripted course [rad]
  double turn_period = 0.0;           ///< time between course changes [s]
  double sine_amplitude = 0.0;        ///< open-loop identification input amplitude [rad]
  double sine_frequency = 0.0;        ///< open-loop identification input frequency [rad/s]
  double sigma_v = 0.0;               ///< realistic sway-velocity noise [m/s]
  double sigma_r = 0.0;               ///< realistic yaw-rate noise [rad/s]
};

/// Mariner class vessel at 7.7 m/s (Fossen, MSS mariner.m, linearised).
const VesselModel& mariner();
/// Otter 2 m USV at 1 m/s (Fossen, PythonVehicleSimulator otter.py, linearised; the
/// differential-thrust yaw moment expressed as an equivalent rudder angle).
const VesselModel& otter();
/// Every shipped model.
std::vector<VesselModel> shipped_vessels();
/// Finds a shipped model by name; returns false when there is none.
bool find_vessel(const std::string& name, VesselModel* out);

}  // namespace usvfdi
