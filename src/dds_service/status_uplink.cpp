#include "usv_fdi/dds_service/status_uplink.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace usvfdi::dds_service {

namespace {

/// Same value: equal, or both NaN.
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

/// |x - ref| relative to |ref| (at least `floor`); 0 when both are NaN.
double relative(double x, double ref, double floor) {
  if (std::isnan(x) || std::isnan(ref)) return 0.0;  // a NaN change is a discrete one
  return std::abs(x - ref) / std::max(std::abs(ref), floor);
}

}  // namespace

const char* to_string(UplinkReason r) {
  switch (r) {
    case UplinkReason::kNone:
      return "none";
    case UplinkReason::kFirst:
      return "first";
    case UplinkReason::kPeriodic:
      return "periodic";
    case UplinkReason::kDiscrete:
      return "discrete";
    case UplinkReason::kContinuous:
      return "continuous";
    case UplinkReason::kHeartbeat:
      return "heartbeat";
  }
  return "?";
}

StatusUplink::StatusUplink(const UplinkOptions& o) : o_(o) {
  if (!(o.heartbeat > 0.0)) throw std::invalid_argument("status heartbeat must be > 0 s");
  if (!(o.tolerance > 0.0)) throw std::invalid_argument("status tolerance must be > 0");
  if (!(o.theta > 0.0)) throw std::invalid_argument("status theta must be > 0");
  if (!(o.decay >= 0.0 && o.decay < 1.0)) {
    throw std::invalid_argument("status decay must be in [0, 1)");
  }
  if (!(o.excitation_weight >= 0.0)) {
    throw std::invalid_argument("status excitation weight must be >= 0");
  }
}

double StatusUplink::bound() const {
  return o_.tolerance * std::sqrt(1.0 + 1.0 / (o_.theta * (1.0 - o_.decay)));
}

std::uint64_t StatusUplink::sent_total() const {
  std::uint64_t n = 0;
  for (int i = 1; i < 6; ++i) n += sent_[i];
  return n;
}

bool StatusUplink::discrete_change(const fdi::FdiStatus& a, const fdi::FdiStatus& b,
                                   std::string* what) {
  const auto changed = [what](const char* name) {
    if (what != nullptr) *what = name;
    return true;
  };
  if (a.mmsi() != b.mmsi()) return changed("mmsi");
  if (a.converged() != b.converged()) return changed("converged");
  if (a.armed() != b.armed()) return changed("armed");
  if (a.ins_healthy() != b.ins_healthy()) return changed("ins_healthy");
  if (a.rudder_healthy() != b.rudder_healthy()) return changed("rudder_healthy");
  if (a.input_flags() != b.input_flags()) return changed("input_flags");
  if (a.identification_paused() != b.identification_paused()) {
    return changed("identification_paused");
  }
  if (a.isolation_paused() != b.isolation_paused()) return changed("isolation_paused");
  if (a.incarnation() != b.incarnation()) return changed("incarnation");
  if (a.poles_v() != b.poles_v() || a.poles_g() != b.poles_g()) return changed("poles");
  if (a.dropped() != b.dropped()) return changed("dropped");
  if (a.rejected_timestamps() != b.rejected_timestamps()) return changed("rejected_timestamps");
  if (a.invalid_values() != b.invalid_values()) return changed("invalid_values");
  if (a.gaps() != b.gaps()) return changed("gaps");
  if (a.reordered() != b.reordered()) return changed("reordered");
  if (a.dropped_inputs() != b.dropped_inputs()) return changed("dropped_inputs");
  if (a.lost_ins() != b.lost_ins() || a.lost_rudder() != b.lost_rudder()) return changed("lost");
  if (a.acks_refused() != b.acks_refused() || a.acks_dropped() != b.acks_dropped()) {
    return changed("acks");
  }
  if (a.other_event_writers() != b.other_event_writers()) return changed("other_event_writers");
  if (!same(a.reference_speed(), b.reference_speed())) return changed("reference_speed");
  // A value that appears or goes away (NaN) is news, not a deviation.
  const auto nan_flip = [](double x, double y) { return std::isnan(x) != std::isnan(y); };
  for (int i = 0; i < 4; ++i) {
    if (nan_flip(a.a()[i], b.a()[i])) return changed("a");
  }
  if (nan_flip(a.excitation(), b.excitation()) || nan_flip(a.sigma_v(), b.sigma_v()) ||
      nan_flip(a.sigma_r(), b.sigma_r()) || nan_flip(a.surge_speed(), b.surge_speed()) ||
      nan_flip(a.speed_ratio(), b.speed_ratio())) {
    return changed("a value became or stopped being NaN");
  }
  if (a.message() != b.message()) return changed("message");
  return false;
}

double StatusUplink::deviation(const fdi::FdiStatus& s0, const fdi::FdiStatus& s) const {
  // A-hat: the Frobenius norm of the change relative to the sent matrix's.
  double num = 0.0, den = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double x = s.a()[i], x0 = s0.a()[i];
    if (std::isnan(x) || std::isnan(x0)) continue;
    num += (x - x0) * (x - x0);
    den += x0 * x0;
  }
  const double e_a = den > 0.0 ? std::sqrt(num / den) : (num > 0.0 ? 1e9 : 0.0);
  const double e_x = o_.excitation_weight * relative(s.excitation(), s0.excitation(), 1e-12);
  const double e_sv = relative(s.sigma_v(), s0.sigma_v(), 1e-12);
  const double e_sr = relative(s.sigma_r(), s0.sigma_r(), 1e-12);
  // A speed change relative to the speed sent, at least 0.5 m/s (a vessel at rest).
  const double e_u = relative(s.surge_speed(), s0.surge_speed(), 0.5);
  const double e_k = relative(s.speed_ratio(), s0.speed_ratio(), 0.05);
  return std::sqrt(e_a * e_a + e_x * e_x + e_sv * e_sv + e_sr * e_sr + e_u * e_u + e_k * e_k);
}

UplinkReason StatusUplink::offer(const fdi::FdiStatus& s, double now) {
  ++offered_;
  UplinkReason why = UplinkReason::kNone;
  const double sigma2 = o_.tolerance * o_.tolerance;
  double e2 = 0.0;
  if (!o_.event) {
    why = UplinkReason::kPeriodic;
  } else if (!have_) {
    why = UplinkReason::kFirst;
  } else if (discrete_change(last_, s, &last_change_)) {
    why = UplinkReason::kDiscrete;
  } else {
    const double e = deviation(last_, s);
    e2 = e * e;
    if (e2 > sigma2 + eta_ / o_.theta) {
      why = UplinkReason::kContinuous;
    } else if (now - last_at_ >= o_.heartbeat) {
      why = UplinkReason::kHeartbeat;
    }
  }
  if (why != UplinkReason::kNone) {
    last_ = s;
    last_at_ = now;
    have_ = true;
    e2 = 0.0;
  }
  eta_ = std::max(0.0, o_.decay * eta_ + sigma2 - e2);
  ++sent_[static_cast<int>(why)];
  return why;
}

}  // namespace usvfdi::dds_service
