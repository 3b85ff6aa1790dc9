#include "usv_fdi/dds_service/status_uplink.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace usvfdi::dds_service {

namespace {

/// Same value: equal, or both NaN.
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

/// |x - ref| relative to |ref| (at least `floor`); 0 unless both are finite (a value that
/// becomes or stops being finite is a discrete change).
double relative(double x, double ref, double floor) {
  if (!std::isfinite(x) || !std::isfinite(ref)) return 0.0;
  return std::abs(x - ref) / std::max(std::abs(ref), floor);
}

/// A problem counter is news when it starts counting; its growth goes with the next heartbeat
/// (a steady loss must not make every status urgent: its flag says it goes on).
bool started(unsigned long long sent, unsigned long long now) { return sent == 0 && now > 0; }

/// The message without its numbers ("12 samples lost" and "13 samples lost" say the same).
std::string without_digits(const std::string& m) {
  std::string out;
  for (char c : m) {
    if (std::isdigit(static_cast<unsigned char>(c)) == 0) {
      out += c;
    } else if (out.empty() || out.back() != '#') {
      out += '#';
    }
  }
  return out;
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
  if (started(a.dropped(), b.dropped())) return changed("dropped");
  if (started(a.rejected_timestamps(), b.rejected_timestamps())) {
    return changed("rejected_timestamps");
  }
  if (started(a.invalid_values(), b.invalid_values())) return changed("invalid_values");
  if (started(a.gaps(), b.gaps())) return changed("gaps");
  if (started(a.reordered(), b.reordered())) return changed("reordered");
  if (started(a.dropped_inputs(), b.dropped_inputs())) return changed("dropped_inputs");
  if (started(a.lost_ins(), b.lost_ins()) || started(a.lost_rudder(), b.lost_rudder())) {
    return changed("lost");
  }
  if (started(a.acks_refused(), b.acks_refused()) || started(a.acks_dropped(), b.acks_dropped())) {
    return changed("acks");
  }
  if (a.other_event_writers() != b.other_event_writers()) return changed("other_event_writers");
  // A counter that went back: a new run, or a counter reset; news.
  if (b.dropped() < a.dropped() || b.rejected_timestamps() < a.rejected_timestamps() ||
      b.invalid_values() < a.invalid_values() || b.gaps() < a.gaps() ||
      b.reordered() < a.reordered() || b.dropped_inputs() < a.dropped_inputs() ||
      b.lost_ins() < a.lost_ins() || b.lost_rudder() < a.lost_rudder() ||
      b.acks_refused() < a.acks_refused() || b.acks_dropped() < a.acks_dropped()) {
    return changed("a counter went back");
  }
  if (!same(a.reference_speed(), b.reference_speed())) return changed("reference_speed");
  if (a.model_mismatch() != b.model_mismatch()) return changed("model_mismatch");
  // A residual that goes above its leave threshold (a suspicion) or back below is news; its
  // level in between is not.
  for (int c = 0; c < 2; ++c) {
    const auto above = [c](const fdi::FdiStatus& s) {
      return s.j_leave()[c] > 0.0 && s.j_peak()[c] > s.j_leave()[c];
    };
    if (above(a) != above(b)) return changed("residual above its leave threshold");
  }
  // A value that appears, goes away (NaN) or becomes infinite is news, not a deviation.
  const auto flip = [](double x, double y) { return std::isfinite(x) != std::isfinite(y); };
  for (int i = 0; i < 4; ++i) {
    if (flip(a.a()[i], b.a()[i])) return changed("a");
  }
  if (flip(a.excitation(), b.excitation()) || flip(a.sigma_v(), b.sigma_v()) ||
      flip(a.sigma_r(), b.sigma_r()) || flip(a.surge_speed(), b.surge_speed()) ||
      flip(a.speed_ratio(), b.speed_ratio())) {
    return changed("a value became or stopped being finite");
  }
  if (without_digits(a.message().to_string()) != without_digits(b.message().to_string())) {
    return changed("message");
  }
  return false;
}

double StatusUplink::deviation(const fdi::FdiStatus& s0, const fdi::FdiStatus& s) const {
  // A-hat: the Frobenius norm of the change relative to the sent matrix's.
  double num = 0.0, den = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double x = s.a()[i], x0 = s0.a()[i];
    if (!std::isfinite(x) || !std::isfinite(x0)) continue;
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
    // The heartbeat goes at the evaluation nearest its time: at most half an evaluation
    // interval early, so that statuses are at most heartbeat + half an interval apart.
    const double half_interval = have_offer_ ? 0.5 * std::max(0.0, now - last_offer_) : 0.0;
    if (!(e2 <= sigma2 + eta_ / o_.theta)) {
      why = UplinkReason::kContinuous;
    } else if (now - last_at_ + half_interval >= o_.heartbeat) {
      why = UplinkReason::kHeartbeat;
    }
  }
  have_offer_ = true;
  last_offer_ = now;
  if (why != UplinkReason::kNone) {
    last_ = s;
    last_at_ = now;
    have_ = true;
    e2 = 0.0;
  }
  const double eta = o_.decay * eta_ + sigma2 - e2;
  eta_ = eta > 0.0 ? eta : 0.0;  // also when e2 was not a number
  ++sent_[static_cast<int>(why)];
  return why;
}

}  // namespace usvfdi::dds_service
