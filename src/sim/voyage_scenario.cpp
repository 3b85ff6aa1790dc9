// The scripted voyages of `usv-fdi sim --scenario`.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "usv_fdi/sim/hulls.hpp"
#include "voyage_internal.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

Leg leg(Manoeuvre kind, double duration, double heading = 0.0, double rudder = 0.0,
        double throttle = -1.0) {
  Leg l;
  l.kind = kind;
  l.duration = duration;
  l.heading = heading;
  l.rudder = rudder;
  l.throttle = throttle;
  return l;
}

/// Course changes of +10, -10, -10, +10 deg (the heading visits base, +10, base, -10, base).
void course_changes(double p, double throttle, std::vector<Leg>* out) {
  const double steps[] = {10.0, -10.0, -10.0, 10.0};
  for (const double s : steps) {
    out->push_back(leg(Manoeuvre::kCourse, p, s * kDeg, 0.0, throttle));
    throttle = -1.0;
  }
}

/// A zigzag whose first execute is to side k (+1 starboard, -1 port: the sign of the rudder).
void zigzag(double p, double angle, double k, std::vector<Leg>* out) {
  out->push_back(leg(Manoeuvre::kHold, p));
  out->push_back(leg(Manoeuvre::kZigzag, 8.0 * p, angle * kDeg, k * (angle * kDeg)));
  out->push_back(leg(Manoeuvre::kHold, 2.0 * p));
}

/// A turning circle to side k (+1 starboard, -1 port), then one to the other side.
void turns(double p, double rudder, double k, std::vector<Leg>* out) {
  out->push_back(leg(Manoeuvre::kHold, p));
  out->push_back(leg(Manoeuvre::kTurn, 20.0 * p, k * (360.0 * kDeg), k * rudder));
  out->push_back(leg(Manoeuvre::kHold, 2.0 * p));
  out->push_back(leg(Manoeuvre::kTurn, 20.0 * p, -k * (360.0 * kDeg), -k * rudder));
  out->push_back(leg(Manoeuvre::kHold, 2.0 * p));
}

void speed_changes(double p, std::vector<Leg>* out) {
  // Deceleration to -30 %, back to nominal, acceleration to +30 %, back; course changes
  // while the speed settles.
  const double throttles[] = {0.7, 1.0, 1.3, 1.0};
  for (const double th : throttles) {
    out->push_back(leg(Manoeuvre::kSpeed, p, 0.0, 0.0, th));
    out->push_back(leg(Manoeuvre::kCourse, p, 10.0 * kDeg));
    out->push_back(leg(Manoeuvre::kCourse, p, -10.0 * kDeg));
  }
}

void slow_passage(double p, std::vector<Leg>* out) {
  out->push_back(leg(Manoeuvre::kSpeed, 2.0 * p, 0.0, 0.0, 0.5));
  course_changes(p, -1.0, out);
  out->push_back(leg(Manoeuvre::kSpeed, 2.0 * p, 0.0, 0.0, 1.0));
}
}  // namespace

const char* to_string(Manoeuvre m) {
  switch (m) {
    case Manoeuvre::kHold:
      return "hold";
    case Manoeuvre::kCourse:
      return "course";
    case Manoeuvre::kZigzag:
      return "zigzag";
    case Manoeuvre::kTurn:
      return "turn";
    case Manoeuvre::kSpeed:
      return "speed";
  }
  return "hold";
}

double turning_rudder(const Hull& hull) {
  const double full = std::min(35.0 * kDeg, hull.limits().max_rudder);
  if (hull.nonlinear()) return full;
  // A linear hull has no nonlinear damping to bound its turn: at 35 deg its steady yaw rate
  // K delta is far beyond any real ship's. Use the rudder that gives a turning circle of
  // diameter 4 L (r = U0 / 2L), a typical tactical diameter of a hard-over turn.
  const Linearisation lin = linearise(hull, hull.nominal_speed());
  const double det = lin.A.determinant();
  const double num = lin.A(1, 0) * lin.B(0) - lin.A(0, 0) * lin.B(1);
  if (!(det > 0) || num == 0.0) return full;
  const double r = hull.nominal_speed() / (2.0 * hull.limits().length);
  return std::min(full, r / std::abs(num / det));
}

double leg_period(const Hull& hull) {
  const double u0 = hull.nominal_speed(), l = hull.limits().length;
  return std::max(20.0, 6.0 * l / u0);
}

std::vector<std::string> scenario_names() {
  return {"hold", "course", "zigzag10", "zigzag20", "turn", "speed", "slow", "voyage"};
}

std::vector<Leg> scenario_legs(const std::string& name, const Hull& hull, Side first) {
  const double p = leg_period(hull);
  const double turn_rudder = turning_rudder(hull);
  const double k = side_sign(first);
  std::vector<Leg> out;
  if (name == "hold") {
    out.push_back(leg(Manoeuvre::kHold, p));
  } else if (name == "course") {
    out.push_back(leg(Manoeuvre::kHold, p));
    course_changes(p, -1.0, &out);
  } else if (name == "zigzag10" || name == "zigzag20") {
    zigzag(p, name == "zigzag10" ? 10.0 : 20.0, k, &out);
  } else if (name == "turn") {
    turns(p, turn_rudder, k, &out);
  } else if (name == "speed") {
    out.push_back(leg(Manoeuvre::kHold, p));
    speed_changes(p, &out);
  } else if (name == "slow") {
    slow_passage(p, &out);
  } else if (name == "voyage") {
    out.push_back(leg(Manoeuvre::kHold, p));
    course_changes(p, -1.0, &out);
    zigzag(p, 10.0, k, &out);
    speed_changes(p, &out);
    turns(p, turn_rudder, k, &out);
    zigzag(p, 20.0, k, &out);
    slow_passage(p, &out);
  } else {
    std::string names;
    for (const std::string& n : scenario_names()) names += (names.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown voyage scenario '" + name + "' (expected " + names + ")");
  }
  return out;
}

}  // namespace usvfdi::sim
