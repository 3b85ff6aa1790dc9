// Open-loop standard manoeuvres of a hull (IMO MSC.137(76) / ITTC 7.5-04-02-01): a fixed-step
// RK4 of Hull::rates with heading, position and a rate-limited first-order rudder servo.
#pragma once

#include <cstdint>
#include <string>

#include "usv_fdi/sim/hull.hpp"

namespace usvfdi::sim {

/// The side a manoeuvre turns to (first): starboard (heading increasing, r > 0) or port.
/// Starboard is every manoeuvre's default.
enum class Side : std::uint8_t { kStarboard = 0, kPort };
/// +1 for starboard, -1 for port.
inline double side_sign(Side side) { return side == Side::kPort ? -1.0 : 1.0; }
/// "starboard" or "port".
const char* to_string(Side side);
/// Reads "starboard" or "port"; false on anything else.
bool parse_side(const std::string& text, Side* side);

/// Everything the manoeuvre integrator carries.
struct ManoeuvreState {
  HullState x;         ///< body velocities
  double north = 0.0;  ///< position [m] (x0: along the approach course)
  double east = 0.0;   ///< [m]
  double psi = 0.0;    ///< heading [rad], + to starboard
  double delta = 0.0;  ///< actual rudder angle [rad]
};

/// One RK4 step of length dt [s] with rudder command delta_c (saturated at the hull's
/// limit; the servo is first-order with the hull's time constant and rate limit).
ManoeuvreState manoeuvre_step(const Hull& hull, const ManoeuvreState& s, double delta_c,
                              double throttle, double dt);

/// Rudder sign that turns the hull to starboard (r > 0) in straight running at u0: +1 or -1.
double starboard_rudder_sign(const Hull& hull, double u0);

/// The 35 deg (or any) turning circle to a side, approach speed u0 at constant throttle.
/// Distances across the approach course are measured towards the side of the turn (> 0 for
/// either side), so that a port and a starboard circle compare directly.
struct TurningCircle {
  double advance = 0.0;            ///< [m] along the approach course at 90 deg heading change
  double transfer = 0.0;           ///< [m] across it at 90 deg
  double tactical_diameter = 0.0;  ///< [m] across it at 180 deg
  double steady_speed = 0.0;       ///< speed U in the steady turn [m/s] (after 720 deg)
  double steady_yaw_rate = 0.0;    ///< [rad/s] (+ to starboard: < 0 in a port turn)
  double approach_speed = 0.0;     ///< [m/s]
};
TurningCircle turning_circle(const Hull& hull, double u0, double rudder,
                             Side side = Side::kStarboard, double dt = 0.05);

/// The rudder/heading zigzag (10/10, 20/20), first execute to `first`. Overshoots are
/// measured past the switching heading on each side (> 0 for either first side).
struct Zigzag {
  double first_overshoot = 0.0;         ///< [rad]
  double second_overshoot = 0.0;        ///< [rad]
  double time_to_second_execute = 0.0;  ///< [s] (the "initial turning time" ends earlier)
};
Zigzag zigzag(const Hull& hull, double u0, double rudder, double heading,
              Side first = Side::kStarboard, double dt = 0.05);

}  // namespace usvfdi::sim
