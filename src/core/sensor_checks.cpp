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
      inv_learn_time_(1.0 / p.stuck_learn_time),
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
    // After a gap longer than stale_timeout the value is no repeat of the one before it, and
    // the pair teaches nothing: the stream says nothing of what the channel did in between.
    const double gap = t - ch.last_valid_t;
    const bool after_gap = gap > stale_timeout_;
    const bool repeat = !after_gap && x == ch.last_value;
    // How often this channel repeats a value while it moves (its quantisation), learned per
    // decade of |x| while it is not taken for stuck; a run's repeats once it has ended.
    const double step = std::min(1.0, gap * inv_learn_time_);
    if (repeat) {
      if (ch.stuck_samples == 0) ch.stuck_since = ch.last_valid_t;
      ++ch.stuck_samples;
      if (learn_repeat) {
        ++ch.pending_repeats;
        ch.pending_step += step;
      }
    } else {
      if (!ch.run_stuck && ch.pending_repeats > 0) {
        const double mean_step = ch.pending_step / ch.pending_repeats;
        for (int i = 0; i < ch.pending_repeats; ++i) learn(&ch, ch.last_value, true, mean_step);
      }
      ch.pending_repeats = 0;
      ch.pending_step = 0.0;
      ch.run_stuck = false;
      ch.stuck_samples = 0;
      ch.stuck_since = kNaN;
      if (learn_repeat && !after_gap && std::isfinite(ch.last_value)) learn(&ch, x, false, step);
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
    const double f = repeat_fraction(&ch, ch.last_value);
    double needed = 0.0;
    if (std::isnan(f)) {
      needed = std::numeric_limits<double>::infinity();  // rate unknown: not by repeats
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
  ch->last_decade = decade(x, ch->last_decade);
  for (RepeatRate* rr : {&ch->repeat[ch->last_decade], &ch->pooled}) {
    rr->seen += 1.0;
    // max(1 / seen, step), dividing only while the plain mean lasts.
    const double w = rr->seen * step >= 1.0 ? step : 1.0 / rr->seen;
    rr->fraction += w * ((repeat ? 1.0 : 0.0) - rr->fraction);
  }
}

int SensorChecks::decade(double x, int hint) {
  // floor(log10 |x|) by comparison from the hint (no log per sample), clamped.
  static constexpr double kPowers[kDecades - 1] = {1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3,
                                                   1e-2, 1e-1, 1e0,  1e1,  1e2,  1e3};
  static_assert(kMinDecade == -9 && kDecades == 14, "kPowers lists 10^kMinDecade and up");
  const double a = std::abs(x);
  int i = std::min(std::max(hint, 0), kDecades - 1);
  while (i > 0 && a < kPowers[i - 1]) --i;
  while (i < kDecades - 1 && a >= kPowers[i]) ++i;
  return i;
}

double SensorChecks::repeat_fraction(Channel* ch, double x) {
  ch->last_decade = decade(x, ch->last_decade);
  const RepeatRate& rr = ch->repeat[ch->last_decade];
  if (rr.seen >= kRepeatLearned) return rr.fraction;
  const bool full_precision =
      ch->pooled.seen >= kRepeatLearned && ch->pooled.fraction <= kFullPrecision;
  return full_precision ? ch->pooled.fraction : kNaN;
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
