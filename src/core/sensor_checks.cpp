#include "usv_fdi/core/sensor_checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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
    // How often this channel repeats a value while it moves (its quantisation), learned per
    // decade of |x| while it is not taken for stuck; a run's repeats once it has ended.
    const double step = std::min(1.0, (t - ch.last_valid_t) / stuck_learn_time_);
    if (repeat) {
      if (ch.stuck_samples == 0) ch.stuck_since = ch.last_valid_t;
      ++ch.stuck_samples;
      if (learn_repeat) {
        ++ch.pending_repeats;
        ch.pending_step += step;
      }
    } else {
      if (!ch.run_stuck) {
        for (int i = 0; i < ch.pending_repeats; ++i) {
          learn(&ch, ch.last_value, true, ch.pending_step / ch.pending_repeats);
        }
      }
      ch.pending_repeats = 0;
      ch.pending_step = 0.0;
      ch.run_stuck = false;
      ch.stuck_samples = 0;
      ch.stuck_since = kNaN;
      if (learn_repeat && std::isfinite(ch.last_value)) learn(&ch, x, false, step);
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
    // Repeats needed: a run this long is improbable for the channel as learned at this value.
    const double f = repeat_fraction(ch, ch.last_value);
    double needed = std::numeric_limits<double>::infinity();  // rate unknown: not by repeats
    if (f <= 0.0) {
      needed = 0.0;
    } else if (f > 0.0) {
      needed = std::log(stuck_probability_) / std::log(std::min(f, 1.0 - 1e-12));
    }
    v.stuck = ch.stuck_samples >= needed || held >= stuck_time_max_;
    ch.run_stuck = ch.run_stuck || v.stuck;
  }
  v.invalid = static_cast<int>(ch.invalids.size()) >= invalid_count_;
}

void SensorChecks::learn(Channel* ch, double x, bool repeat, double step) {
  // The mean of the first samples, then an exponential average over stuck_learn_time.
  for (RepeatRate* rr : {&ch->repeat[decade(x)], &ch->pooled}) {
    rr->seen += 1.0;
    rr->fraction += std::max(1.0 / rr->seen, step) * ((repeat ? 1.0 : 0.0) - rr->fraction);
  }
}

int SensorChecks::decade(double x) {
  // floor(log10 |x|) by comparison (no log per sample), clamped; bin 0 below 10^kMinDecade.
  static const std::array<double, kDecades - 1> kPowers = [] {
    std::array<double, kDecades - 1> p{};
    for (int i = 0; i < kDecades - 1; ++i) p[i] = std::pow(10.0, kMinDecade + i);
    return p;
  }();
  const double a = std::abs(x);
  int i = 0;
  while (i < kDecades - 1 && a >= kPowers[i]) ++i;
  return i;
}

double SensorChecks::repeat_fraction(const Channel& ch, double x) {
  const RepeatRate& rr = ch.repeat[decade(x)];
  if (rr.seen >= kRepeatLearned) return rr.fraction;
  const bool full_precision =
      ch.pooled.seen >= kRepeatLearned && ch.pooled.fraction <= kFullPrecision;
  return full_precision ? ch.pooled.fraction : kNaN;
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
