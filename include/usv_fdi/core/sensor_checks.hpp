// The sensor-level checks of the isolation stage: for each input channel (v, r and the
// rudder angle) whether it is stale (no valid value for stale_timeout), stuck (its value
// repeated for longer than its quantisation makes probable) or invalid (non-finite or
// absurd values, invalid_count of them within spike_window); and the timing errors (stamps
// that repeat, go backwards or jump), which count against no channel. They need no model.
// docs/design.md section 8.3.
#pragma once

#include <array>
#include <deque>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

struct IsolationParams;
struct InputHealth;

/// The input channels the checks look at (the first two are kV and kR).
enum InputChannel : int { kInputV = 0, kInputR = 1, kInputDelta = 2 };

class SensorChecks {
 public:
  /// What one channel's checks found on the latest sample.
  struct Verdict {
    bool stale = false;
    bool stuck = false;
    bool invalid = false;
    double value = kNaN;       ///< the sample's value
    double since_valid = 0.0;  ///< time since the last valid value [s]
  };

  explicit SensorChecks(const IsolationParams& p);

  /// One sample. learn_repeat[c]: channel c (v, r) may learn how often it repeats a value
  /// (not while it is taken for stuck; the rudder always learns). Counts invalid values in
  /// *input.
  void update(const Sample& s, const std::array<bool, 2>& learn_repeat, InputHealth* input);
  const Verdict& verdict(int channel) const { return verdict_[channel]; }
  /// How many times in a row channel c has repeated its value.
  int repeats(int channel) const { return ch_[channel].stuck_samples; }

  /// A sample whose stamp did not fit, at the last good time t: true when invalid_count of
  /// them fell within spike_window.
  bool timing_error(double t);
  /// Whether no timing error is left within spike_window before t.
  bool timing_clear(double t);

 private:
  /// How often a channel repeats its value, learned per decade of |x|: a channel printed to
  /// a number of significant digits has a quantum that grows tenfold at each power of ten
  /// (v to 3 digits: 0.001 below 1 m/s, 0.01 above), so it repeats itself far more often in
  /// a decade above the ones it has moved in.
  struct RepeatRate {
    double fraction = 0.0;  ///< learned fraction of samples equal to the previous
    double seen = 0;        ///< samples it was learned from (a plain mean at first)
  };
  /// Decades 10^kMinDecade .. 10^(kMinDecade + kDecades - 2) (clamped), the first bin below.
  static constexpr int kMinDecade = -9;
  static constexpr int kDecades = 14;
  /// A decade's rate is used once it was learned from this many samples.
  static constexpr double kRepeatLearned = 50;
  /// A channel that repeats less often than this over all decades is taken as printed at full
  /// precision: a decade it has not moved in is judged by that rate.
  static constexpr double kFullPrecision = 1e-3;
  /// The bin of |x|: 0 below 10^kMinDecade, i for 10^(kMinDecade + i - 1) <= |x| <
  /// 10^(kMinDecade + i), the last bin unbounded. Searched from hint (the channel's last bin:
  /// a signal seldom leaves its decade between samples).
  static int decade(double x, int hint);
  struct Channel {
    double last_valid_t = kNaN;
    double last_value = kNaN;
    double stuck_since = kNaN;
    int stuck_samples = 0;
    std::array<RepeatRate, kDecades> repeat{};  ///< per decade of |x|
    RepeatRate pooled;                          ///< over all decades
    int last_decade = 0;                        ///< decade() of the last value looked up
    /// The current run's repeats, learned when it ends (a run is judged by the rates from
    /// before it) and only if it was never taken for stuck.
    int pending_repeats = 0;
    double pending_step = 0.0;  ///< their summed weights (sample interval / stuck_learn_time)
    bool run_stuck = false;
    std::deque<double> invalids;  ///< times of invalid values
  };
  /// The repeat fraction to judge a run at x by: its decade's once learned; before that, the
  /// rate over all decades of a channel learned to be at full precision, and NaN otherwise (a
  /// quantised channel's rate in a decade it has not moved in is unknown, and so is any rate
  /// before kRepeatLearned samples: only stuck_time_max then holds).
  static double repeat_fraction(Channel* ch, double x);
  void check(int c, double t, double x, double limit, bool learn_repeat, InputHealth* input);
  /// One learned sample (repeat or not) at x, of weight step, into its decade and the pool.
  static void learn(Channel* ch, double x, bool repeat, double step);

  double stale_timeout_, stuck_time_, stuck_probability_;
  double inv_learn_time_;  ///< 1 / stuck_learn_time (a product per sample, not a quotient)
  double stuck_time_max_;
  int stuck_min_samples_, invalid_count_;
  double spike_window_;
  std::array<double, 3> limits_;
  std::array<Channel, 3> ch_;
  std::array<Verdict, 3> verdict_;
  std::deque<double> timing_errors_;  ///< times of repeated / backward stamps
};

}  // namespace usvfdi
