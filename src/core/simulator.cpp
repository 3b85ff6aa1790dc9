#include "usv_fdi/core/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace usvfdi {

Simulator::Simulator(const SimConfig& cfg) : c_(cfg), rng_(cfg.seed) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("sim: " + what); };
  if (!(c_.rate_hz > 0)) bad("rate_hz must be positive");
  if (!(c_.duration > 0)) bad("duration must be positive");
  if (c_.substeps < 1) bad("substeps must be >= 1");
  if (!c_.vessel.A.allFinite() || !c_.vessel.B.allFinite() || c_.vessel.B(1) == 0.0) {
    bad("vessel model needs finite A and B with b2 != 0");
  }
  if (!(c_.vessel.max_rudder > 0) || !(c_.vessel.max_rudder_rate > 0) ||
      !(c_.vessel.rudder_time_constant > 0) || !(c_.vessel.autopilot_bandwidth > 0)) {
    bad("vessel " + c_.vessel.name + " needs rudder limits, servo lag and autopilot bandwidth");
  }
  for (const FaultInjection& f : c_.faults) {
    if (f.sensor == Sensor::kUnknown) bad("a fault must name the accelerometer or the gyro");
    if (!(f.t_end > f.t_start)) bad("a fault must end after it starts");
  }
  sigma_[0] = c_.sigma_v >= 0 ? c_.sigma_v : c_.vessel.sigma_v;
  sigma_[1] = c_.sigma_r >= 0 ? c_.sigma_r : c_.vessel.sigma_r;
  held_.assign(c_.faults.size(), std::numeric_limits<double>::quiet_NaN());
  target_ = c_.vessel.turn_angle;
  if (c_.sine_amplitude < 0) c_.sine_amplitude = c_.vessel.sine_amplitude;
  if (c_.sine_frequency < 0) c_.sine_frequency = c_.vessel.sine_frequency;
}

double Simulator::autopilot(double psi_ref) const {
  // Model-based PD: desired r' = wn^2 (psi_ref - psi) - 2 wn r.
  const VesselModel& m = c_.vessel;
  const double wn = m.autopilot_bandwidth;
  const bool meas = c_.autopilot_on_measurement;
  const double v = meas ? measured_(0) : z_(0), r = meas ? measured_(1) : z_(1);
  const double psi = meas ? measured_(2) : z_(2);
  const double want = wn * wn * (psi_ref - psi) - 2.0 * wn * r;
  const double dc = (want - m.A(1, 0) * v - m.A(1, 1) * r) / m.B(1);
  return std::clamp(dc, -m.max_rudder, m.max_rudder);
}

Simulator::State Simulator::deriv(const State& z, double delta_c) const {
  const VesselModel& m = c_.vessel;
  State d;
  d.head<2>() = m.A * z.head<2>() + m.B * z(3);
  d(2) = z(1);
  d(3) =
      std::clamp((delta_c - z(3)) / m.rudder_time_constant, -m.max_rudder_rate, m.max_rudder_rate);
  return d;
}

double Simulator::apply_faults(int channel, double t, double truth, double noisy,
                               FaultKind* active) {
  double y = noisy;
  *active = FaultKind::kUnknown;
  for (std::size_t i = 0; i < c_.faults.size(); ++i) {
    const FaultInjection& f = c_.faults[i];
    if (static_cast<int>(f.sensor) != channel) continue;
    if (t < f.t_start || t >= f.t_end) {
      held_[i] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    *active = f.kind;
    const double dt = 1.0 / c_.rate_hz;
    switch (f.kind) {
      case FaultKind::kBias:
        y += f.magnitude;
        break;
      case FaultKind::kDrift:
        y += f.magnitude * (t - f.t_start);
        break;
      case FaultKind::kNoise:
        y += f.magnitude * n01_(rng_);
        break;
      case FaultKind::kSpikes:
        if (u01_(rng_) < f.spike_rate * dt) y += (u01_(rng_) < 0.5 ? -1 : 1) * f.magnitude;
        break;
      case FaultKind::kScale:
        y += f.magnitude * truth;
        break;
      case FaultKind::kStuck:
        if (std::isnan(held_[i])) held_[i] = y;
        y = held_[i];
        break;
      case FaultKind::kStale:
        y = std::numeric_limits<double>::quiet_NaN();
        break;
      case FaultKind::kInvalid:
        y = std::numeric_limits<double>::infinity();
        break;
      case FaultKind::kUnknown:
        break;
    }
  }
  return y;
}

bool Simulator::next(SimRow* row) {
  const double h = 1.0 / c_.rate_hz;
  const double t = static_cast<double>(k_) * h;
  if (t > c_.duration + 1e-9) return false;
  if (k_ > 0) {
    // Advance the plant over [t - h, t] with the command computed at t - h.
    const VesselModel& m = c_.vessel;
    double delta_c = 0.0;
    const bool sine = c_.steering == Steering::kSine;
    if (!sine) {
      // Alternating course changes through a first-order reference filter; the autopilot
      // command is held over the sample (a digital autopilot).
      const double tp = t - h;
      const int leg = static_cast<int>(std::floor(tp / m.turn_period));
      target_ = (leg % 2 == 0) ? m.turn_angle : -m.turn_angle;
      delta_c = autopilot(psi_ref_);
      psi_ref_ += (target_ - psi_ref_) * (-std::expm1(-0.5 * m.autopilot_bandwidth * h));
    }
    const double hs = h / c_.substeps;
    // The open-loop sine is a continuous-time command (a smooth identification input).
    const auto command = [&](double tau) {
      if (!sine) return delta_c;
      return std::clamp(c_.sine_amplitude * std::sin(c_.sine_frequency * tau) +
                            0.5 * c_.sine_amplitude * std::sin(2.7 * c_.sine_frequency * tau),
                        -m.max_rudder, m.max_rudder);
    };
    for (int i = 0; i < c_.substeps; ++i) {
      const double ts = t - h + i * hs;
      const State k1 = deriv(z_, command(ts));
      const State k2 = deriv(z_ + 0.5 * hs * k1, command(ts + 0.5 * hs));
      const State k3 = deriv(z_ + 0.5 * hs * k2, command(ts + 0.5 * hs));
      const State k4 = deriv(z_ + hs * k3, command(ts + hs));
      z_ += hs / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
      if (c_.disturbance > 0) {
        z_(0) += c_.disturbance * std::sqrt(hs) * n01_(rng_);
        z_(1) += c_.disturbance * std::sqrt(hs) * n01_(rng_) *
                 (m.sigma_v > 0 ? m.sigma_r / m.sigma_v : 1.0);
      }
    }
  }
  ++k_;
  row->t = t;
  row->v_true = z_(0);
  row->r_true = z_(1);
  row->psi = z_(2);
  row->delta_true = z_(3);
  row->psi_ref = psi_ref_;
  const double nv = sigma_[0] > 0 ? sigma_[0] * n01_(rng_) : 0.0;
  const double nr = sigma_[1] > 0 ? sigma_[1] * n01_(rng_) : 0.0;
  row->v = apply_faults(kV, t, z_(0), z_(0) + nv, &row->fault_a);
  row->r = apply_faults(kR, t, z_(1), z_(1) + nr, &row->fault_g);
  row->delta = z_(3) + (c_.sigma_delta > 0 ? c_.sigma_delta * n01_(rng_) : 0.0);
  // What an autopilot on the INS knows at t: the last valid v and r, and the heading
  // integrated from the measured yaw rate (trapezoidal).
  if (std::isfinite(row->v)) measured_(0) = row->v;
  if (std::isfinite(row->r)) {
    if (k_ > 1) measured_(2) += 0.5 * h * (measured_(1) + row->r);
    measured_(1) = row->r;
  }
  return true;
}

std::vector<SimRow> simulate(const SimConfig& cfg) {
  Simulator sim(cfg);
  std::vector<SimRow> rows;
  rows.reserve(static_cast<std::size_t>(cfg.duration * cfg.rate_hz) + 2);
  SimRow row;
  while (sim.next(&row)) rows.push_back(row);
  return rows;
}

SimConfig paper_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed) {
  SimConfig c;
  c.vessel = vessel;
  c.rate_hz = rate_hz;
  c.duration = 100.0;
  c.seed = seed;
  c.steering = Steering::kSine;  // the paper does not say: a smooth rudder sine (docs/design.md)
  const double sv = vessel.sigma_v, sr = vessel.sigma_r;
  c.faults.push_back({Sensor::kGyro, FaultKind::kBias, 20.0, 40.0, 10.0 * sr, 2.0});
  c.faults.push_back({Sensor::kAccelerometer, FaultKind::kBias, 60.0, 80.0, 10.0 * sv, 2.0});
  return c;
}

}  // namespace usvfdi
