// Hull models of the proving ground (vessel zoo): the contract between a hull's equations
// of motion and the voyage simulator that steers it. Depends on Eigen alone.
//
// Conventions (the project's, as in usv_fdi/core/types.hpp): body axes, x forward, y to
// starboard, z down; u surge [m/s], v sway [m/s] (+ to starboard), r yaw rate [rad/s]
// (+ to starboard). The rudder angle delta [rad] keeps each hull's published sign
// convention; the linearised B tells the engine which way it acts (B = [b1, b2]).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "usv_fdi/core/types.hpp"

namespace usvfdi::sim {

/// Body-fixed velocities.
struct HullState {
  double u = 0.0;  ///< surge [m/s]
  double v = 0.0;  ///< sway [m/s], + to starboard
  double r = 0.0;  ///< yaw rate [rad/s], + to starboard
};

/// Time derivative of HullState.
struct HullRates {
  double du = 0.0;  ///< [m/s^2]
  double dv = 0.0;  ///< [m/s^2]
  double dr = 0.0;  ///< [rad/s^2]
};

/// What the voyage gives the hull besides its own state.
struct HullInput {
  double delta = 0.0;     ///< actual rudder angle [rad] (after the servo), hull's sign
  double throttle = 1.0;  ///< propulsion command relative to the one that holds the nominal
                          ///< speed in straight running (1 = nominal, 0.7 = -30 %) [-]
};

/// Environmental loads as accelerations of the body (wind, current, wave drift),
/// so that one environment model serves every hull.
struct Disturbance {
  double du = 0.0;  ///< [m/s^2]
  double dv = 0.0;  ///< [m/s^2]
  double dr = 0.0;  ///< [rad/s^2]
};

/// Actuator and size facts the voyage needs.
struct HullLimits {
  double max_rudder = 0.0;            ///< saturation [rad]
  double max_rudder_rate = 0.0;       ///< rate limit [rad/s]
  double rudder_time_constant = 0.0;  ///< first-order servo lag [s]
  double length = 0.0;                ///< length between perpendiculars [m]
};

/// One hull: its equations of motion in surge, sway and yaw.
class Hull {
 public:
  virtual ~Hull() = default;
  virtual std::string name() const = 0;
  /// Where the coefficients come from (author, year, title or report), as published.
  virtual std::string source() const = 0;
  /// True when the equations are nonlinear 3-DOF (speed loss in turns, speed-dependent
  /// hydrodynamics); false for a linear sway-yaw model with a first-order surge.
  virtual bool nonlinear() const = 0;
  /// Straight-running speed at throttle 1 [m/s].
  virtual double nominal_speed() const = 0;
  virtual HullLimits limits() const = 0;
  /// x' = f(x, input) + disturbance.
  virtual HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const = 0;
};

/// The sway-yaw model a user's engine sees: x' = A x + B delta at surge speed u0, obtained
/// by linearising Hull::rates about straight running (v = r = delta = 0, u = u0).
struct Linearisation {
  double u0 = 0.0;
  Mat2 A = Mat2::Zero();
  Vec2 B = Vec2::Zero();
};

}  // namespace usvfdi::sim
