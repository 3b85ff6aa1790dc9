#include "usv_fdi/core/sensor_checks.hpp"

#include <algorithm>
#include <cmath>

#include "usv_fdi/core/isolation.hpp"

namespace usvfdi {
namespace {

void prune(std::deque<double>* q, double t_min) {
  while (!q->empty() && q->front() < t_min) q->pop_front();
}

}  // namespace

SensorChecks::SensorChecks(const IsolationParams& p)
    : stale_timeout_(p.stale_timeout),
      stuck_time_(p.stuck_time),
      stuck_probability_(p.stuck_probability),
      stuck_learn_time_(p.stuck_learn_time),
      stuck_time_max_(p.stuck_time_max),
      stuck_min_samples_(p.stuck_min_samples),
      invalid_count_(p.invalid_count),
      spike_window_(p.spike_window),
      limits_{p.max_abs_v, p.max_abs_r, p.max_abs_delta} {}

void SensorChecks::update(const Sample& s, const std::array<bool, 2>& learn_repeat,
                          InputHealth* input) {
  const double values[3] = {s.v, s.r, s.delta};
  for (int c = 0; c < 3; ++c) {
    check(c, s.t, values[c], limits_[c], c == kInputDelta || learn_repeat[c], input);
  }
}

void SensorChecks::check(int c, double t, double x, double limit, bool learn_repeat,
                         InputHealth* input) {
  Channel& ch = ch_[c];
  if (std::isnan(ch.last_valid_t)) ch.last_valid_t = t;
  const bool missing = std::isnan(x);
  const bool absurd = !missing && !(std::abs(x) <= limit);  // Inf or out of range
  if (absurd) {
    ++input->invalid_values;
    ch.invalids.push_back(t);
  }
  prune(&ch.invalids, t - spike_window_);
  if (!missing && !absurd) {
    const bool repeat = x == ch.last_value;
    if (repeat) {
      if (ch.stuck_samples == 0) ch.stuck_since = ch.last_valid_t;
      ++ch.stuck_samples;
    } else {
      ch.stuck_samples = 0;
      ch.stuck_since = kNaN;
    }
    // How often this channel repeats a value while it moves (its quantisation), learned
    // while it is not taken for stuck.
    if (learn_repeat && std::isfinite(ch.last_value)) {
      // The mean of the first samples, then an exponential average over stuck_learn_time.
      ch.repeat_seen += 1.0;
      const double w =
          std::max(1.0 / ch.repeat_seen, std::min(1.0, (t - ch.last_valid_t) / stuck_learn_time_));
      ch.repeat_fraction += w * ((repeat ? 1.0 : 0.0) - ch.repeat_fraction);
    }
    ch.last_value = x;
    ch.last_valid_t = t;
  }
  Verdict& v = verdict_[c];
  v.value = x;
  v.since_valid = t - ch.last_valid_t;
  v.stale = v.since_valid > stale_timeout_;
  const double held = t - ch.stuck_since;  // NaN while the value moves
  v.stuck = false;
  if (ch.stuck_samples + 1 >= stuck_min_samples_ && held >= stuck_time_) {
    // Repeats needed: a run this long is improbable for the channel as learned.
    const double f = std::min(ch.repeat_fraction, 1.0 - 1e-12);
    const double needed = f > 0.0 ? std::log(stuck_probability_) / std::log(f) : 0.0;
    v.stuck = ch.stuck_samples >= needed || held >= stuck_time_max_;
  }
  v.invalid = static_cast<int>(ch.invalids.size()) >= invalid_count_;
}

bool SensorChecks::timing_error(double t) {
  // At the last good time (the clock stands still while stamps are bad: only the latest
  // invalid_count are needed, memory stays bounded).
  timing_errors_.push_back(t);
  prune(&timing_errors_, t - spike_window_);
  while (static_cast<int>(timing_errors_.size()) > invalid_count_) timing_errors_.pop_front();
  return static_cast<int>(timing_errors_.size()) >= invalid_count_;
}

bool SensorChecks::timing_clear(double t) {
  prune(&timing_errors_, t - spike_window_);
  return timing_errors_.empty();
}

}  // namespace usvfdi
