#include "scoring.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace usvfdi::bench {

namespace {

std::string describe(const InjectedFault& f) {
  return std::string(to_string(f.sensor)) + " " + to_string(f.kind) + " [" +
         std::to_string(f.t_start) + ", " + std::to_string(f.t_end) + ")";
}

/// Length of [a, b) inside [lo, hi].
double overlap(double a, double b, double lo, double hi) {
  return std::max(0.0, std::min(b, hi) - std::max(a, lo));
}

/// Throws std::invalid_argument on a fault that ends before it starts, overlapping faults
/// (sorted by onset), alarms out of time order or a run that ends before it begins.
void check_run(const std::vector<InjectedFault>& faults, const std::vector<Alarm>& alarms,
               double t_first, double t_last) {
  for (std::size_t i = 0; i < faults.size(); ++i) {
    if (!(faults[i].t_end > faults[i].t_start)) {
      throw std::invalid_argument("fault " + describe(faults[i]) + ": t_end must exceed t_start");
    }
    if (i > 0 && faults[i].t_start < faults[i - 1].t_end) {
      throw std::invalid_argument("faults " + describe(faults[i - 1]) + " and " +
                                  describe(faults[i]) + " overlap");
    }
  }
  for (std::size_t k = 1; k < alarms.size(); ++k) {
    if (alarms[k].t < alarms[k - 1].t) {
      throw std::invalid_argument("alarm " + std::to_string(k) + " at t = " +
                                  std::to_string(alarms[k].t) + " is earlier than the one before");
    }
  }
  if (!(t_last >= t_first)) throw std::invalid_argument("run ends before it begins");
}

/// The detection windows of the faults (sorted by onset), each cut at the next onset.
class DetectionWindows {
 public:
  DetectionWindows(const std::vector<InjectedFault>& faults, double grace) : faults_(faults) {
    const std::size_t n = faults.size();
    end_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      end_[i] = faults[i].t_end + grace;
      if (i + 1 < n) end_[i] = std::min(end_[i], faults[i + 1].t_start);
    }
  }
  double end(std::size_t i) const { return end_[i]; }
  /// The window that holds t, -1 for none.
  int of(double t) const {
    for (std::size_t i = 0; i < faults_.size(); ++i) {
      if (t >= faults_[i].t_start && t < end_[i]) return static_cast<int>(i);
    }
    return -1;
  }

 private:
  const std::vector<InjectedFault>& faults_;
  std::vector<double> end_;
};

/// The run's span and its healthy time (outside the windows), in all and while live.
void set_healthy_time(const std::vector<InjectedFault>& faults, const DetectionWindows& windows,
                      double t_first, double t_last, const std::vector<LiveSpan>& live,
                      RunScore* out) {
  out->span = t_last - t_first;
  double in_windows = 0.0;
  for (std::size_t i = 0; i < faults.size(); ++i) {
    in_windows += overlap(faults[i].t_start, windows.end(i), t_first, t_last);
  }
  out->healthy_time = out->span - in_windows;
  double live_healthy = 0.0;
  for (const LiveSpan& l : live) {
    const double from = std::max(l.from, t_first), to = std::min(l.to, t_last);
    if (!(to > from)) continue;
    live_healthy += to - from;
    for (std::size_t i = 0; i < faults.size(); ++i) {
      live_healthy -= overlap(faults[i].t_start, windows.end(i), from, to);
    }
  }
  out->healthy_armed_time = live_healthy;
}

void check_live(const std::vector<LiveSpan>& live) {
  for (std::size_t k = 0; k < live.size(); ++k) {
    if (!(live[k].to > live[k].from)) {
      throw std::invalid_argument("live span " + std::to_string(k) + " is empty");
    }
    if (k > 0 && live[k].from < live[k - 1].to) {
      throw std::invalid_argument("live span " + std::to_string(k) +
                                  " starts before the one before it ends");
    }
  }
}

/// Each raise within the run: the first in a fault's window detects it (delay, isolation);
/// one outside every window is a false alarm.
void score_raises(const std::vector<Alarm>& alarms, const DetectionWindows& windows, double t_first,
                  double t_last, RunScore* out) {
  for (std::size_t k = 0; k < alarms.size(); ++k) {
    const Alarm& a = alarms[k];
    if (!a.raised || a.t < t_first || a.t > t_last) continue;
    const int w = windows.of(a.t);
    if (w < 0) {
      out->false_alarm_times.push_back(a.t);
      out->false_alarm_events.push_back(a);
      // Alarms are in time order: its clear, if any, comes after it.
      const auto clear = std::find_if(
          alarms.begin() + static_cast<std::ptrdiff_t>(k) + 1, alarms.end(),
          [&](const Alarm& b) { return b.t > a.t && b.sensor == a.sensor && !b.raised; });
      const double until = clear == alarms.end() ? t_last : std::min(clear->t, t_last);
      out->false_alarm_durations.push_back(until - a.t);
      continue;
    }
    FaultScore& fs = out->faults[static_cast<std::size_t>(w)];
    if (fs.detected) continue;
    fs.detected = true;
    fs.delay = a.t - fs.fault.t_start;
    fs.raised_sensor = a.sensor;
    fs.raised_kind = a.kind;
    fs.isolated = a.sensor == fs.fault.sensor;
  }
}

/// Recovery of a detected fault: the alarm conditions replayed up to its end, then until
/// every one is clear, at the latest by limit.
void score_recovery(const std::vector<Alarm>& alarms, double limit, FaultScore* fs) {
  std::array<bool, 3> raised{false, false, false};
  auto clear = [&] { return !raised[0] && !raised[1] && !raised[2]; };
  std::size_t k = 0;
  for (; k < alarms.size() && alarms[k].t <= fs->fault.t_end; ++k) {
    raised[static_cast<int>(alarms[k].sensor)] = alarms[k].raised;
  }
  if (clear()) {
    fs->recovered = true;
    fs->recovery_delay = 0.0;
    return;
  }
  for (; k < alarms.size() && alarms[k].t <= limit; ++k) {
    raised[static_cast<int>(alarms[k].sensor)] = alarms[k].raised;
    if (clear()) {
      fs->recovered = true;
      fs->recovery_delay = alarms[k].t - fs->fault.t_end;
      return;
    }
  }
}

/// How long the faulty sensor was shown raised during the fault, and whether it stayed raised
/// from its first raise in the fault to the fault's end.
void score_shown(const std::vector<Alarm>& alarms, FaultScore* fs) {
  const InjectedFault& f = fs->fault;
  bool raised = false, first_seen = false, dropped = false;
  double since = f.t_start, shown = 0.0;
  for (const Alarm& a : alarms) {
    if (a.sensor != f.sensor) continue;
    if (a.t >= f.t_end) break;
    if (a.t > f.t_start) {
      if (raised) shown += a.t - since;
      since = a.t;
    }
    if (a.raised && !raised && a.t >= f.t_start) first_seen = true;
    if (!a.raised && raised && first_seen) dropped = true;
    raised = a.raised;
  }
  if (raised) shown += f.t_end - std::max(since, f.t_start);
  fs->shown = shown / (f.t_end - f.t_start);
  fs->held = fs->isolated && first_seen && raised && !dropped;
}

}  // namespace

bool live_at(const std::vector<LiveSpan>& live, double t) {
  return std::any_of(live.begin(), live.end(),
                     [t](const LiveSpan& l) { return l.from <= t && t < l.to; });
}

RunScore score_run(std::vector<InjectedFault> faults, const std::vector<Alarm>& alarms,
                   double t_first, double t_last, double t_armed, const ScoreParams& params) {
  std::vector<LiveSpan> live;
  if (std::isfinite(t_armed)) live.push_back(LiveSpan{t_armed});
  return score_run(std::move(faults), alarms, t_first, t_last, live, params);
}

RunScore score_run(std::vector<InjectedFault> faults, const std::vector<Alarm>& alarms,
                   double t_first, double t_last, const std::vector<LiveSpan>& live,
                   const ScoreParams& params) {
  std::sort(faults.begin(), faults.end(),
            [](const InjectedFault& a, const InjectedFault& b) { return a.t_start < b.t_start; });
  check_run(faults, alarms, t_first, t_last);
  check_live(live);
  const DetectionWindows windows(faults, params.detect_grace);

  RunScore out;
  set_healthy_time(faults, windows, t_first, t_last, live, &out);
  const std::size_t n = faults.size();
  out.faults.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.faults[i].fault = faults[i];
    out.faults[i].armed_at_onset = live_at(live, faults[i].t_start);
  }
  score_raises(alarms, windows, t_first, t_last, &out);
  for (std::size_t i = 0; i < n; ++i) {
    score_shown(alarms, &out.faults[i]);
    if (!out.faults[i].detected) continue;
    score_recovery(alarms, i + 1 < n ? faults[i + 1].t_start : t_last, &out.faults[i]);
  }
  return out;
}

double quantile(std::vector<double> x, double q) {
  x.erase(std::remove_if(x.begin(), x.end(), [](double v) { return std::isnan(v); }), x.end());
  if (x.empty()) return kNaN;
  std::sort(x.begin(), x.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(x.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, x.size() - 1);
  return x[lo] + (pos - static_cast<double>(lo)) * (x[hi] - x[lo]);
}

}  // namespace usvfdi::bench
