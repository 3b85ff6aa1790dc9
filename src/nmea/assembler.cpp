// SampleAssembler (include/usv_fdi/nmea/assembler.hpp).
#include "usv_fdi/nmea/assembler.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>

namespace usvfdi::nmea {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMinTolerance = 0.002;  ///< [s]: jitter below this is not told apart
constexpr double kMadsOfJitter = 4.5;    ///< ~3 standard deviations of Gaussian jitter
constexpr double kMaxScatter = 0.25;     ///< MAD / period beyond which a sentence is irregular
/// The share of intervals that must be whole multiples of the period (a lost sentence makes
/// one of 2 P): two senders of one sentence, or a sender that repeats it, make a pattern of
/// short and long intervals whose median is neither, and no period.
constexpr double kMinOnPeriod = 0.8;
/// Intervals outside period +- tolerance in a row that restart the learning (a new rate).
constexpr int kOffPeriodRestart = 3;

double median_of(double* x, int n) {
  std::nth_element(x, x + n / 2, x + n);
  const double hi = x[n / 2];
  if (n % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(x, x + n / 2));
}
}  // namespace

bool SampleAssembler::Arrivals::arrive(double t) {
  if (std::isnan(last)) {
    last = t;
    return true;
  }
  const double dt = t - last;
  // Another line of the same datagram, or a copy of the sentence: the same arrival.
  if (dt < kMinTolerance) return false;
  last = t;
  // A new rate: the last few intervals all off the learned period; learn again from them.
  off_period = !std::isnan(period) && std::abs(dt - period) > tolerance ? off_period + 1 : 0;
  intervals[next] = dt;
  next = (next + 1) % kKeptIntervals;
  count = std::min(count + 1, kKeptIntervals);
  if (off_period >= kOffPeriodRestart) {
    double recent[kOffPeriodRestart];
    for (int i = 0; i < kOffPeriodRestart; ++i) {
      recent[i] = intervals[(next - kOffPeriodRestart + i + kKeptIntervals) % kKeptIntervals];
    }
    std::copy(recent, recent + kOffPeriodRestart, intervals);
    count = kOffPeriodRestart;
    next = kOffPeriodRestart;
    off_period = 0;
  }
  period = kNaN;
  if (count < kMinIntervals) return true;
  double x[kKeptIntervals];
  std::copy(intervals, intervals + count, x);
  const double p = median_of(x, count);
  for (int i = 0; i < count; ++i) x[i] = std::abs(x[i] - p);
  const double mad = median_of(x, count);
  if (mad > kMaxScatter * p) return true;  // not periodic: held up to max_age_s
  const double tol = std::max(kMadsOfJitter * mad, kMinTolerance);
  int on_period = 0;
  for (int i = 0; i < count; ++i) {
    const double k = std::round(intervals[i] / p);
    on_period += k >= 1.0 && std::abs(intervals[i] - k * p) <= std::max(tol, p / 8.0);
  }
  if (on_period < kMinOnPeriod * count) return true;
  period = p;
  tolerance = tol;
  return true;
}

SampleAssembler::Feed SampleAssembler::feed_of(Slot slot) {
  switch (slot) {
    case kR:
      return kRot;
    case kDelta:
      return kRsa;
    case kUGround:
      return kVtg;
    default:
      return kVbw;  // v and the water speed
  }
}

double SampleAssembler::learned_period(const std::string& sentence) const {
  if (sentence == "ROT") return arrivals_[kRot].period;
  if (sentence == "RSA") return arrivals_[kRsa].period;
  if (sentence == "VBW") return arrivals_[kVbw].period;
  if (sentence == "VTG") return arrivals_[kVtg].period;
  return kNaN;
}

SampleAssembler::SampleAssembler(const AssemblerConfig& config) : config_(config) {
  if (!std::isfinite(config.rate_hz) || config.rate_hz <= 0.0) {
    throw std::invalid_argument("SampleAssembler: rate_hz must be finite and > 0, not " +
                                std::to_string(config.rate_hz));
  }
  if (!std::isfinite(config.max_age_s) || config.max_age_s <= 0.0) {
    throw std::invalid_argument("SampleAssembler: max_age_s must be finite and > 0, not " +
                                std::to_string(config.max_age_s));
  }
  period_ = 1.0 / config.rate_hz;
  look_ahead_ = config.hold_until_due ? 0.5 * period_ : 0.0;
}

bool SampleAssembler::accept_time(double t) {
  if (!std::isfinite(t) || t < latest_input_) {
    ++out_of_order_;
    return false;
  }
  if (!started_) {
    started_ = true;
    first_input_ = t;
    next_k_ = first_grid_index(t - look_ahead_, false);
  }
  emit_before(t - look_ahead_, false);
  latest_input_ = t;
  return true;
}

void SampleAssembler::set(Slot slot, double t, bool valid, double value) {
  if (valid && std::isfinite(value)) {
    held_[slot].value = value;
    held_[slot].time = t;
    held_[slot].used = false;
  } else {
    held_[slot].value = kNaN;  // invalid from now on; the age keeps counting
  }
}

bool SampleAssembler::add(double t, const Rot& rot) {
  if (!accept_time(t)) return false;
  if (!arrivals_[kRot].arrive(t) && config_.hold_until_due) return true;  // a copy
  set(kR, t, rot.valid(), rot.valid() ? yaw_rate_from_rot(*rot.rate_deg_per_min) : kNaN);
  return true;
}

bool SampleAssembler::add(double t, const Rsa& rsa) {
  if (!accept_time(t)) return false;
  if (!arrivals_[kRsa].arrive(t) && config_.hold_until_due) return true;  // a copy
  if (rsa.starboard_valid()) {
    set(kDelta, t, true, delta_from_rsa(*rsa.starboard_deg, config_.rudder_sign));
  } else if (rsa.port_valid()) {
    set(kDelta, t, true, delta_from_rsa(*rsa.port_deg, config_.rudder_sign));
  } else {
    set(kDelta, t, false, kNaN);
  }
  return true;
}

bool SampleAssembler::add(double t, const Vbw& vbw) {
  if (!accept_time(t)) return false;
  if (!arrivals_[kVbw].arrive(t) && config_.hold_until_due) return true;  // a copy
  const bool water = vbw.water_valid();
  set(kV, t, water && vbw.water_transverse_kn,
      water && vbw.water_transverse_kn ? speed_from_knots(*vbw.water_transverse_kn) : kNaN);
  set(kUWater, t, water && vbw.water_longitudinal_kn,
      water && vbw.water_longitudinal_kn ? speed_from_knots(*vbw.water_longitudinal_kn) : kNaN);
  return true;
}

bool SampleAssembler::add(double t, const Vtg& vtg) {
  if (!accept_time(t)) return false;
  if (!arrivals_[kVtg].arrive(t) && config_.hold_until_due) return true;  // a copy
  const bool ok = vtg.valid() && vtg.speed_kn;
  set(kUGround, t, ok, ok ? speed_from_knots(*vtg.speed_kn) : kNaN);
  return true;
}

namespace {

// Whether a sentence carries a valid value of the quantity it is read for (kUsed), or says
// that quantity is not valid (kNotValid). Mirrors what add() holds.
bool carries_value(const Rot& x) { return x.valid(); }
bool carries_value(const Rsa& x) { return x.starboard_valid() || x.port_valid(); }
bool carries_value(const Vbw& x) { return x.water_valid() && x.water_transverse_kn.has_value(); }
bool carries_value(const Vtg& x) { return x.valid() && x.speed_kn.has_value(); }

template <class T>
InputResult feed(SampleAssembler* a, double t, const Result<T>& parsed) {
  if (!parsed) return InputResult{InputUse::kRefused, parsed.rejection()};
  if (!a->add(t, parsed.value())) return InputResult{InputUse::kOutOfOrder, {}};
  return InputResult{carries_value(parsed.value()) ? InputUse::kUsed : InputUse::kNotValid, {}};
}

}  // namespace

bool SampleAssembler::is_input(const Sentence& s) {
  if (s.proprietary) return false;
  const std::string& f = s.formatter;
  return f == "ROT" || f == "RSA" || f == "VBW" || f == "VTG";
}

InputResult SampleAssembler::add_sentence(double t, const Sentence& s) {
  if (is_input(s)) {
    if (s.formatter == "ROT") return feed(this, t, parse_rot(s));
    if (s.formatter == "RSA") return feed(this, t, parse_rsa(s));
    if (s.formatter == "VBW") return feed(this, t, parse_vbw(s));
    return feed(this, t, parse_vtg(s));
  }
  return InputResult{InputUse::kNotAnInput, {}};
}

void SampleAssembler::advance(double t) {
  if (!started_ || !std::isfinite(t)) return;
  emit_before(t, true);
}

double SampleAssembler::at(Slot slot, double g, double* age) {
  Held& h = held_[slot];
  *age = kNaN;
  if (std::isnan(h.value) || !(g - h.time <= config_.max_age_s)) return kNaN;
  const Arrivals& a = arrivals_[feed_of(slot)];
  // Already in a sample, and its successor overdue (beyond the jitter, at most half the
  // look-ahead) by g's look-ahead time: the successor is lost or late, and the value is not
  // given again. (One not yet used is given, however late its successor: no repetition.)
  if (config_.hold_until_due && !std::isnan(a.period) && h.used &&
      g + look_ahead_ >= h.time + a.period + std::min(a.tolerance, 0.5 * look_ahead_)) {
    return kNaN;
  }
  h.used = true;
  *age = g - h.time;
  return h.value;
}

void SampleAssembler::emit_before(double t, bool inclusive) {
  while (true) {
    const double g = static_cast<double>(next_k_) * period_;
    if (inclusive ? g > t : g >= t) return;
    AssembledSample s;
    s.t = g;
    s.v = at(kV, g, &s.age_v);
    s.r = at(kR, g, &s.age_r);
    s.delta = at(kDelta, g, &s.age_delta);
    s.u = at(kUWater, g, &s.age_u);
    // The ground speed stands in only when there is no water speed (invalid or too old), not
    // where a water speed is withheld as a repetition: u would flip between the two.
    const Held& water = held_[kUWater];
    const bool water_held = !std::isnan(water.value) && g - water.time <= config_.max_age_s;
    if (std::isnan(s.u) && !water_held) s.u = at(kUGround, g, &s.age_u);
    const bool any =
        !std::isnan(s.v) || !std::isnan(s.r) || !std::isnan(s.delta) || !std::isnan(s.u);
    if (!any) {
      // Nothing held is fresh, and values only age until the next input at t: jump past t.
      next_k_ = first_grid_index(t, inclusive);
      return;
    }
    out_.push_back(s);
    ++next_k_;
  }
}

long long SampleAssembler::first_grid_index(double t, bool after) const {
  // The first k with k * period > t (after) or >= t, robust to the rounding of t / period.
  long long k = static_cast<long long>(std::ceil(t / period_));
  const auto ok = [&](long long j) {
    const double g = static_cast<double>(j) * period_;
    return after ? g > t : g >= t;
  };
  while (k > LLONG_MIN && ok(k - 1)) --k;
  while (!ok(k)) ++k;
  return k;
}

std::vector<AssembledSample> SampleAssembler::take() {
  std::vector<AssembledSample> out;
  out.swap(out_);
  return out;
}

std::vector<StaleInput> SampleAssembler::stale(double t) const {
  std::vector<StaleInput> out;
  if (!started_) return out;
  const auto check = [&](const char* quantity, const char* sentence, double time) {
    if (std::isnan(time)) {
      if (t - first_input_ > config_.max_age_s) {
        out.push_back(StaleInput{quantity, sentence, t - first_input_, true});
      }
    } else if (t - time > config_.max_age_s) {
      out.push_back(StaleInput{quantity, sentence, t - time, false});
    }
  };
  check("v", "VBW", held_[kV].time);
  check("r", "ROT", held_[kR].time);
  check("delta", "RSA", held_[kDelta].time);
  const double u_water = held_[kUWater].time;
  const double u_ground = held_[kUGround].time;
  double u_time = kNaN;
  if (!std::isnan(u_water)) u_time = u_water;
  if (!std::isnan(u_ground) && (std::isnan(u_time) || u_ground > u_time)) u_time = u_ground;
  check("u", "VBW/VTG", u_time);
  return out;
}

}  // namespace usvfdi::nmea
