// Open-loop manoeuvre integrator (turning circle, zigzag) for any Hull.
#include "usv_fdi/sim/manoeuvre.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
/// d/dt of the manoeuvre state.
struct Deriv {
  HullRates f;
  double dnorth, deast, dpsi, ddelta;
};

double servo_rate(const HullLimits& lim, double delta, double delta_c, double dt) {
  const double c = std::clamp(delta_c, -lim.max_rudder, lim.max_rudder);
  const double T = std::max(lim.rudder_time_constant, dt);
  return std::clamp((c - delta) / T, -lim.max_rudder_rate, lim.max_rudder_rate);
}

Deriv deriv(const Hull& hull, const ManoeuvreState& s, double delta_c, double throttle, double dt) {
  HullInput in;
  in.delta = s.delta;
  in.throttle = throttle;
  Deriv d;
  d.f = hull.rates(s.x, in, {});
  d.dnorth = s.x.u * std::cos(s.psi) - s.x.v * std::sin(s.psi);
  d.deast = s.x.u * std::sin(s.psi) + s.x.v * std::cos(s.psi);
  d.dpsi = s.x.r;
  d.ddelta = servo_rate(hull.limits(), s.delta, delta_c, dt);
  return d;
}

ManoeuvreState advance(const ManoeuvreState& s, const Deriv& d, double h) {
  ManoeuvreState n = s;
  n.x.u += h * d.f.du;
  n.x.v += h * d.f.dv;
  n.x.r += h * d.f.dr;
  n.north += h * d.dnorth;
  n.east += h * d.deast;
  n.psi += h * d.dpsi;
  n.delta += h * d.ddelta;
  return n;
}

ManoeuvreState straight(double u0) {
  ManoeuvreState s;
  s.x.u = u0;
  return s;
}

void check_step(double dt) {
  if (!(dt > 0.0)) throw std::invalid_argument("manoeuvre: dt must be > 0");
}
}  // namespace

ManoeuvreState manoeuvre_step(const Hull& hull, const ManoeuvreState& s, double delta_c,
                              double throttle, double dt) {
  const Deriv k1 = deriv(hull, s, delta_c, throttle, dt);
  const Deriv k2 = deriv(hull, advance(s, k1, dt / 2), delta_c, throttle, dt);
  const Deriv k3 = deriv(hull, advance(s, k2, dt / 2), delta_c, throttle, dt);
  const Deriv k4 = deriv(hull, advance(s, k3, dt), delta_c, throttle, dt);
  Deriv sum;
  sum.f = {k1.f.du + 2 * k2.f.du + 2 * k3.f.du + k4.f.du,
           k1.f.dv + 2 * k2.f.dv + 2 * k3.f.dv + k4.f.dv,
           k1.f.dr + 2 * k2.f.dr + 2 * k3.f.dr + k4.f.dr};
  sum.dnorth = k1.dnorth + 2 * k2.dnorth + 2 * k3.dnorth + k4.dnorth;
  sum.deast = k1.deast + 2 * k2.deast + 2 * k3.deast + k4.deast;
  sum.dpsi = k1.dpsi + 2 * k2.dpsi + 2 * k3.dpsi + k4.dpsi;
  sum.ddelta = k1.ddelta + 2 * k2.ddelta + 2 * k3.ddelta + k4.ddelta;
  return advance(s, sum, dt / 6);
}

const char* to_string(Side side) { return side == Side::kPort ? "port" : "starboard"; }

bool parse_side(const std::string& text, Side* side) {
  if (text != "starboard" && text != "port") return false;
  *side = text == "port" ? Side::kPort : Side::kStarboard;
  return true;
}

double starboard_rudder_sign(const Hull& hull, double u0) {
  return linearise(hull, u0).B(1) > 0.0 ? 1.0 : -1.0;
}

TurningCircle turning_circle(const Hull& hull, double u0, double rudder, Side side, double dt) {
  check_step(dt);
  const double throttle = equilibrium_throttle(hull, u0);
  const double k = side_sign(side);  // heading and east mirrored for a port turn
  const double dc = k * starboard_rudder_sign(hull, u0) * std::abs(rudder);
  TurningCircle tc;
  tc.approach_speed = u0;
  ManoeuvreState s = straight(u0);
  const double t_max = 2000.0 * hull.limits().length / u0;  // bounds a hull that never turns
  bool at90 = false, at180 = false;
  for (double t = 0.0; t < t_max && k * s.psi < 4 * M_PI; t += dt) {
    s = manoeuvre_step(hull, s, dc, throttle, dt);
    if (!at90 && k * s.psi >= M_PI / 2) {
      tc.advance = s.north;
      tc.transfer = k * s.east;
      at90 = true;
    }
    if (!at180 && k * s.psi >= M_PI) {
      tc.tactical_diameter = k * s.east;
      at180 = true;
    }
  }
  if (!at180) throw std::runtime_error("turning_circle: '" + hull.name() + "' did not turn 180");
  tc.steady_speed = std::hypot(s.x.u, s.x.v);
  tc.steady_yaw_rate = s.x.r;
  return tc;
}

Zigzag zigzag(const Hull& hull, double u0, double rudder, double heading, Side first, double dt) {
  check_step(dt);
  const double throttle = equilibrium_throttle(hull, u0);
  const double k = side_sign(first);  // the heading mirrored when the first execute is to port
  const double sign = k * starboard_rudder_sign(hull, u0);
  ManoeuvreState s = straight(u0);
  Zigzag z;
  int executes = 0;      // rudder reversals so far
  double side = 1.0;     // +1: rudder to the first side, heading going that way
  double extreme = 0.0;  // extreme (mirrored) heading since the last execute
  const double t_max = 500.0 * hull.limits().length / u0;
  for (double t = 0.0; t < t_max && executes < 3; t += dt) {
    s = manoeuvre_step(hull, s, sign * side * std::abs(rudder), throttle, dt);
    const double psi = k * s.psi;
    if (executes >= 1) extreme = side < 0 ? std::max(extreme, psi) : std::min(extreme, psi);
    if (side * psi >= std::abs(heading)) {
      if (executes == 1) z.first_overshoot = extreme - std::abs(heading);
      if (executes == 2) z.second_overshoot = -extreme - std::abs(heading);
      if (executes == 1) z.time_to_second_execute = t;
      side = -side;
      extreme = psi;
      ++executes;
    }
  }
  if (executes < 3) throw std::runtime_error("zigzag: '" + hull.name() + "' did not complete");
  return z;
}

}  // namespace usvfdi::sim
