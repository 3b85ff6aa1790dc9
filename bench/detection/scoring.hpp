// Scoring rules of the detection benchmark (docs/benchmark.md, "Scoring"). Pure functions on
// hand-checkable inputs: the faults that were injected into one run and the alarm changes a
// detector published on it. No simulator, no engine.
//
//   detection window of a fault  W_i = [t_start, t_end + detect_grace), cut at the next
//                                onset; a raise of ANY sensor in W_i detects fault i, the
//                                first such raise gives the delay (t_raise - t_start) and
//                                the isolation (its sensor is the faulty one)
//   false alarm                  a raise outside every detection window
//   healthy time                 the run's span minus the detection windows
//   recovery                     first time >= t_end at which no sensor's condition is
//                                raised (before the next onset and the run's end); delay
//                                = that time - t_end (0 when already clear at t_end)
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "usv_fdi/core/types.hpp"

namespace usvfdi::bench {

/// A fault put into one run.
struct InjectedFault {
  Sensor sensor = Sensor::kGyro;
  FaultKind kind = FaultKind::kBias;
  double t_start = 0.0;  ///< onset [s]
  double t_end = 0.0;    ///< end, exclusive [s]
};

/// A change of one sensor's alarm condition as a detector published it.
struct Alarm {
  double t = 0.0;  ///< [s]
  Sensor sensor = Sensor::kUnknown;
  bool raised = true;  ///< true: raised; false: cleared
  FaultKind kind = FaultKind::kUnknown;
};

struct ScoreParams {
  /// A raise this long after the fault's end still detects it (the fault's removal is a
  /// step too; a detector that only sees that is late, not blind) [s].
  double detect_grace = 2.0;
};

struct FaultScore {
  InjectedFault fault;
  bool detected = false;
  bool isolated = false;  ///< the first raise in the window names the faulty sensor
  Sensor raised_sensor = Sensor::kUnknown;
  FaultKind raised_kind = FaultKind::kUnknown;
  double delay = kNaN;           ///< first raise - onset [s]
  bool recovered = false;        ///< every condition cleared after the end (detected only)
  double recovery_delay = kNaN;  ///< [s]
  bool armed_at_onset = false;   ///< detection was live at the onset (a live span holds it)
  /// Raised on the faulty sensor from its first raise in the fault to the fault's end, never
  /// cleared in between (a fault shown rectified while it lasts is, for the operator, gone).
  bool held = false;
  /// Share of the fault's duration during which its sensor was shown raised, in [0, 1].
  double shown = 0.0;
};

struct RunScore {
  std::vector<FaultScore> faults;
  std::vector<double> false_alarm_times;  ///< [s]
  std::vector<Alarm> false_alarm_events;  ///< the same raises, with their sensor and kind
  /// How long each false alarm stayed raised: to its sensor's next clear, or the run's end [s].
  std::vector<double> false_alarm_durations;
  double span = 0.0;                ///< t_last - t_first [s]
  double healthy_time = 0.0;        ///< span minus detection windows [s]
  double healthy_armed_time = 0.0;  ///< the part of it while detection was live [s]
  std::size_t false_alarms() const { return false_alarm_times.size(); }
};

/// A span during which a detector's detection was live (armed, settled, learned): [from, to).
/// A detector may un-arm (the engine does when its estimate loses convergence) and arm again,
/// so a run has zero or more, in time order and not overlapping; to = +inf: to the run's end.
struct LiveSpan {
  double from = 0.0;                                    ///< [s]
  double to = std::numeric_limits<double>::infinity();  ///< exclusive [s]
};

/// Whether t lies in one of the spans.
bool live_at(const std::vector<LiveSpan>& live, double t);

/// Scores one run on [t_first, t_last]. Faults must not overlap (sorted or not); alarms must
/// be in time order; live: when detection was live (sorted, not overlapping). Throws
/// std::invalid_argument on overlapping faults, t_end <= t_start, unordered alarms or live
/// spans that are empty, unordered or overlapping.
RunScore score_run(std::vector<InjectedFault> faults, const std::vector<Alarm>& alarms,
                   double t_first, double t_last, const std::vector<LiveSpan>& live,
                   const ScoreParams& params = {});
/// The same for a detector live from t_armed to the end (NaN: never live).
RunScore score_run(std::vector<InjectedFault> faults, const std::vector<Alarm>& alarms,
                   double t_first, double t_last, double t_armed, const ScoreParams& params = {});

/// Quantile q in [0, 1] by linear interpolation between order statistics (NaN when empty).
double quantile(std::vector<double> x, double q);

}  // namespace usvfdi::bench
