// The voyage simulator: hull + rudder servo integrated with RK4, a PID heading autopilot on
// the measured heading and yaw rate, scripted legs, environment, sensors and faults.
#include "usv_fdi/sim/voyage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <string>

#include "usv_fdi/sim/hulls.hpp"
#include "voyage_internal.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kPi = 3.14159265358979323846;
using State = Eigen::Matrix<double, 5, 1>;  // u, v, r, psi (low-frequency), delta (actual)
enum : int { kU = 0, kSv = 1, kSr = 2, kPsi = 3, kDelta = 4 };

double sign_of(double x) { return x < 0 ? -1.0 : 1.0; }

void check_config(const Hull& hull, const VoyageConfig& c) {
  const auto bad = [&](const std::string& what) {
    throw std::invalid_argument("voyage (" + hull.name() + "): " + what);
  };
  const HullLimits l = hull.limits();
  if (!(c.rate_hz > 0)) bad("rate_hz must be positive");
  if (!(c.duration > 0)) bad("duration must be positive");
  if (c.substeps < 1) bad("substeps must be >= 1");
  if (!(hull.nominal_speed() > 0)) bad("the hull's nominal speed must be positive");
  if (!(l.max_rudder > 0) || !(l.max_rudder_rate > 0) || !(l.rudder_time_constant > 0) ||
      !(l.length > 0)) {
    bad("the hull needs rudder limits, a servo time constant and a length");
  }
  for (const FaultInjection& f : c.faults) {
    if (f.sensor == Sensor::kUnknown) bad("a fault must name the accelerometer or the gyro");
    if (!(f.t_end > f.t_start)) bad("a fault must end after it starts");
  }
  for (const Leg& g : c.legs) {
    if (!(g.duration > 0)) bad("every leg needs a positive duration");
  }
  if (c.sensors.drop < 0 || c.sensors.drop >= 1 || c.sensors.duplicate < 0 ||
      c.sensors.duplicate >= 1) {
    bad("drop and duplicate are probabilities in [0, 1)");
  }
}

/// PID gains from the first-order Nomoto approximation T r' + r = K delta of the
/// linearisation (K = num / det(A), T = T1 + T2 - T3 with T1 + T2 = -tr(A) / det(A) and
/// T3 = b2 / num, num = a3 b1 - a1 b2): Kp = T wn^2 / K, Kd = (2 zeta wn T - 1) / K, written
/// with T / K = -tr / num - b2 det / num^2 so that det(A) = 0 (a marginally stable hull) and
/// det(A) < 0 (course-unstable: T < 0) need no special case.
struct Gains {
  double kp = 0.0, kd = 0.0, ki = 0.0, wn = 0.0;
};

Gains autopilot_gains(const Linearisation& lin, const AutopilotConfig& a, const Hull& hull) {
  Gains g;
  g.wn = a.bandwidth > 0 ? a.bandwidth : 1.2 * hull.nominal_speed() / hull.limits().length;
  const Mat2& A = lin.A;
  const double b1 = lin.B(0), b2 = lin.B(1);
  const double num = A(1, 0) * b1 - A(0, 0) * b2;
  if (num == 0.0) {
    throw std::invalid_argument("voyage (" + hull.name() + "): the rudder makes no steady turn");
  }
  const double t_over_k = -A.trace() / num - b2 * A.determinant() / (num * num);
  const double inv_k = A.determinant() / num;
  g.kp = g.wn * g.wn * t_over_k;
  g.kd = 2.0 * a.damping * g.wn * t_over_k - inv_k;
  g.ki = a.integral * g.wn * g.kp;
  return g;
}

Linearisation linearise_nominal(const Hull& hull) {
  try {
    return linearise(hull, hull.nominal_speed());
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument("voyage (" + hull.name() + "): " + e.what());
  }
}
}  // namespace

struct Voyage::Impl {
  Impl(std::shared_ptr<const Hull> h, const VoyageConfig& cfg);
  State deriv(const State& z, const HullInput& in) const;
  void advance();
  void measure(VoyageRow* row);
  void update_heading(const VoyageRow& row);
  void start_leg(std::size_t i);
  void schedule(double t);
  double command(double t);
  double autopilot();
  bool produce(VoyageRow* row);

  std::shared_ptr<const Hull> hull;
  VoyageConfig c;
  HullLimits lim;
  Linearisation lin;
  Gains gains;
  double h = 0.1;
  detail::Environment env;
  detail::Channel ch_v, ch_r, ch_d;
  detail::Stream s_compass, s_link;
  detail::Faults faults;
  State z = State::Zero();
  std::uint64_t k = 0;
  // autopilot and script
  double psi_hat = 0.0, r_last = 0.0, psi_ref = 0.0, target = 0.0, integral = 0.0;
  double throttle = 1.0, delta_c = 0.0, rudder_sign = 1.0;
  std::size_t leg = 0;
  double leg_start = 0.0, leg_base = 0.0, zig_side = 1.0;
  bool leg_done = false, steering_open = false;
  VoyageRow pending;
  bool has_pending = false;
};

Voyage::Impl::Impl(std::shared_ptr<const Hull> hl, const VoyageConfig& cfg)
    : hull(std::move(hl)),
      c(cfg),
      lim(hull->limits()),
      lin(linearise_nominal(*hull)),
      gains(autopilot_gains(lin, cfg.autopilot, *hull)),
      h(1.0 / cfg.rate_hz),
      env(cfg.environment, lin, lim.length, 1.0 / cfg.rate_hz, cfg.seed),
      ch_v(cfg.sensors.v, 1.0 / cfg.rate_hz, cfg.seed, 10),
      ch_r(cfg.sensors.r, 1.0 / cfg.rate_hz, cfg.seed, 11),
      ch_d(cfg.sensors.delta, 1.0 / cfg.rate_hz, cfg.seed, 12),
      s_compass(cfg.seed, 13),
      s_link(cfg.seed, 30),
      faults(cfg.faults, 1.0 / cfg.rate_hz, cfg.seed) {
  z(kU) = hull->nominal_speed();
  rudder_sign = sign_of(lin.B(1));  // a positive heading change needs this rudder sign
  if (c.autopilot.dither_period <= 0) c.autopilot.dither_period = 0.5 * leg_period(*hull);
  psi_hat = env.psi_wave();
  if (!c.legs.empty()) start_leg(0);
}

State Voyage::Impl::deriv(const State& s, const HullInput& in_c) const {
  HullState x;
  x.u = s(kU);
  x.v = s(kSv);
  x.r = s(kSr);
  HullInput in = in_c;
  in.delta = s(kDelta);
  const HullRates f = hull->rates(x, in, env.disturbance());
  State d;
  d << f.du, f.dv, f.dr, s(kSr),
      std::clamp((in_c.delta - s(kDelta)) / lim.rudder_time_constant, -lim.max_rudder_rate,
                 lim.max_rudder_rate);
  return d;
}

void Voyage::Impl::advance() {
  HullInput in;
  in.delta = delta_c;
  in.throttle = throttle;
  const double hs = h / c.substeps;
  for (int i = 0; i < c.substeps; ++i) {
    const State k1 = deriv(z, in);
    const State k2 = deriv(z + 0.5 * hs * k1, in);
    const State k3 = deriv(z + 0.5 * hs * k2, in);
    const State k4 = deriv(z + hs * k3, in);
    z += hs / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  env.step(z(kPsi));
}

void Voyage::Impl::start_leg(std::size_t i) {
  leg = i;
  const Leg& g = c.legs[i];
  leg_start = static_cast<double>(k) * h;
  leg_done = false;
  if (g.throttle >= 0) throttle = g.throttle;
  steering_open = g.kind == Manoeuvre::kZigzag || g.kind == Manoeuvre::kTurn;
  leg_base = steering_open ? psi_hat : target;
  zig_side = sign_of(g.rudder);
  if (steering_open) integral = 0.0;  // the autopilot is disengaged: it starts afresh after
  if (g.kind == Manoeuvre::kCourse) target += g.heading;
}

void Voyage::Impl::schedule(double t) {
  if (c.legs.empty()) return;
  const Leg& g = c.legs[leg];
  if (!leg_done && t - leg_start < g.duration - 1e-9) return;
  if (g.kind == Manoeuvre::kTurn) target = leg_base + g.heading;
  if (steering_open) psi_ref = psi_hat;  // the autopilot takes over from where she is
  start_leg((leg + 1) % c.legs.size());
}

double Voyage::Impl::autopilot() {
  const double s = std::clamp(z(kU) / lin.u0, 0.3, 2.0);  // gains scheduled on the speed log
  const double e = psi_ref - psi_hat;
  const double g = 1.0 / (s * s);
  double d = g * (gains.kp * e - gains.kd * r_last + gains.ki * integral);
  const double cap = 0.3 * lim.max_rudder;  // anti-windup: the integral holds at most 30 %
  if (std::abs(d) < lim.max_rudder && gains.ki != 0.0) {
    integral =
        std::clamp(integral + e * h, -cap / std::abs(g * gains.ki), cap / std::abs(g * gains.ki));
  }
  return d;
}

double Voyage::Impl::command(double t) {
  const double dither = c.autopilot.dither > 0
                            ? c.autopilot.dither * std::sin(2 * kPi * t / c.autopilot.dither_period)
                            : 0.0;
  double d = 0.0;
  const Leg* g = c.legs.empty() ? nullptr : &c.legs[leg];
  if (g != nullptr && g->kind == Manoeuvre::kZigzag) {
    const double dev = psi_hat - leg_base;
    if (dev * zig_side >= std::abs(g->heading)) zig_side = -zig_side;
    d = rudder_sign * zig_side * std::abs(g->rudder);
  } else if (g != nullptr && g->kind == Manoeuvre::kTurn) {
    const double dir = sign_of(g->heading);
    leg_done = (psi_hat - leg_base) * dir >= std::abs(g->heading);
    d = rudder_sign * dir * std::abs(g->rudder);
  } else {
    d = autopilot();
    psi_ref += (target - psi_ref) * (-std::expm1(-0.5 * gains.wn * h));
  }
  return std::clamp(d + dither, -lim.max_rudder, lim.max_rudder);
}

void Voyage::Impl::measure(VoyageRow* row) {
  const double t = static_cast<double>(k) * h;
  *row = VoyageRow{};
  row->t_true = t;
  row->u_true = z(kU);
  row->v_lf = z(kSv);
  row->r_lf = z(kSr);
  row->v_wave = env.v_wave();
  row->r_wave = env.r_wave();
  row->v_current = env.v_current();
  row->v_true = row->v_lf + row->v_wave + row->v_current;
  row->r_true = row->r_lf + row->r_wave;
  row->psi = z(kPsi) + env.psi_wave();
  row->delta_true = z(kDelta);
  const double v = ch_v.measure(row->v_true), r = ch_r.measure(row->r_true);
  row->v = c.sensors.v.quantiser.apply(
      faults.apply(Sensor::kAccelerometer, t, row->v_true, v, &row->fault_a));
  row->r =
      c.sensors.r.quantiser.apply(faults.apply(Sensor::kGyro, t, row->r_true, r, &row->fault_g));
  row->delta = c.sensors.delta.quantiser.apply(ch_d.measure(row->delta_true));
  row->gyro_bias = ch_r.bias();
  const Disturbance d = env.disturbance();
  row->dist_v = d.dv;
  row->dist_r = d.dr;
}

void Voyage::Impl::update_heading(const VoyageRow& row) {
  // The autopilot's heading: the measured yaw rate integrated, pulled towards the compass.
  const double compass =
      row.psi + (c.sensors.compass_sigma > 0 ? c.sensors.compass_sigma * s_compass.normal() : 0.0);
  const bool r_ok = std::isfinite(row.r);
  if (k == 0 || !(c.sensors.compass_tau > 0)) {
    psi_hat = compass;
  } else {
    psi_hat += h * (r_ok ? row.r : r_last);
    psi_hat += (compass - psi_hat) * (-std::expm1(-h / c.sensors.compass_tau));
  }
  if (r_ok) r_last = row.r;
}

bool Voyage::Impl::produce(VoyageRow* row) {
  const double t = static_cast<double>(k) * h;
  if (t > c.duration + 1e-9) return false;
  measure(row);
  update_heading(*row);
  schedule(t);
  delta_c = command(t);
  row->psi_meas = psi_hat;
  row->psi_ref = psi_ref;
  row->delta_cmd = delta_c;
  row->throttle = throttle;
  row->manoeuvre = c.legs.empty() ? Manoeuvre::kHold : c.legs[leg].kind;
  const double jmax = 0.45 * h;
  row->t = t + (c.sensors.jitter > 0 ? std::clamp(c.sensors.jitter * s_link.normal(), -jmax, jmax)
                                     : 0.0);
  advance();
  ++k;
  return true;
}

Voyage::Voyage(std::shared_ptr<const Hull> hull, const VoyageConfig& cfg) {
  if (!hull) throw std::invalid_argument("voyage: no hull");
  check_config(*hull, cfg);
  p_ = std::make_unique<Impl>(std::move(hull), cfg);
}

Voyage::~Voyage() = default;

const Linearisation& Voyage::linearisation() const { return p_->lin; }

bool Voyage::next(VoyageRow* row) {
  if (p_->has_pending) {
    *row = p_->pending;
    p_->has_pending = false;
    return true;
  }
  const SensorConfig& s = p_->c.sensors;
  while (p_->produce(row)) {
    if (s.drop > 0 && p_->s_link.uniform() < s.drop) continue;
    if (s.duplicate > 0 && p_->s_link.uniform() < s.duplicate) {
      p_->pending = *row;
      p_->pending.duplicate = true;
      p_->has_pending = true;
    }
    return true;
  }
  return false;
}

std::vector<VoyageRow> run_voyage(std::shared_ptr<const Hull> hull, const VoyageConfig& cfg) {
  Voyage voyage(std::move(hull), cfg);
  std::vector<VoyageRow> rows;
  rows.reserve(static_cast<std::size_t>(cfg.duration * cfg.rate_hz) + 2);
  VoyageRow row;
  while (voyage.next(&row)) rows.push_back(row);
  return rows;
}

VoyageCsvWriter::VoyageCsvWriter(std::ostream& out, const SensorConfig& sensors) : out_(out) {
  digits_[0] = sensors.v.quantiser.digits;
  digits_[1] = sensors.r.quantiser.digits;
  digits_[2] = sensors.delta.quantiser.digits;
  out_ << "t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g,u,t_true,v_lf,r_lf,"
          "v_wave,r_wave,v_current,psi_meas,delta_cmd,throttle,gyro_bias,dist_v,dist_r,manoeuvre,"
          "duplicate\n";
}

void VoyageCsvWriter::write(const VoyageRow& w) {
  char m[3][40];
  const double meas[3] = {w.v, w.r, w.delta};
  for (int i = 0; i < 3; ++i) {
    const int d = std::isfinite(meas[i]) && digits_[i] > 0 ? digits_[i] : 17;
    std::snprintf(m[i], sizeof m[i], "%.*g", d, meas[i]);
  }
  char buf[1024];
  const auto kind = [](FaultKind k) { return k == FaultKind::kUnknown ? "" : to_string(k); };
  std::snprintf(buf, sizeof buf,
                "%.17g,%s,%s,%s,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%s,%.17g,%.17g,%.17g,%.17g,"
                "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%d\n",
                w.t, m[0], m[1], m[2], w.v_true, w.r_true, w.delta_true, w.psi, w.psi_ref,
                kind(w.fault_a), kind(w.fault_g), w.u_true, w.t_true, w.v_lf, w.r_lf, w.v_wave,
                w.r_wave, w.v_current, w.psi_meas, w.delta_cmd, w.throttle, w.gyro_bias, w.dist_v,
                w.dist_r, to_string(w.manoeuvre), w.duplicate ? 1 : 0);
  out_ << buf;
}

}  // namespace usvfdi::sim
