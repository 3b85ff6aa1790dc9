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
  struct Channel {
    double last_valid_t = kNaN;
    double last_value = kNaN;
    double stuck_since = kNaN;
    int stuck_samples = 0;
    double repeat_fraction = 0.0;  ///< learned fraction of samples equal to the previous
    double repeat_seen = 0;        ///< samples it was learned from (a plain mean at first)
    std::deque<double> invalids;   ///< times of invalid values
  };
  void check(int c, double t, double x, double limit, bool learn_repeat, InputHealth* input);

  double stale_timeout_, stuck_time_, stuck_probability_, stuck_learn_time_, stuck_time_max_;
  int stuck_min_samples_, invalid_count_;
  double spike_window_;
  std::array<double, 3> limits_;
  std::array<Channel, 3> ch_;
  std::array<Verdict, 3> verdict_;
  std::deque<double> timing_errors_;  ///< times of repeated / backward stamps
};

}  // namespace usvfdi
