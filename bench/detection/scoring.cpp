#include "scoring.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

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

}  // namespace

RunScore score_run(std::vector<InjectedFault> faults, const std::vector<Alarm>& alarms,
                   double t_first, double t_last, double t_armed, const ScoreParams& params) {
  std::sort(faults.begin(), faults.end(),
            [](const InjectedFault& a, const InjectedFault& b) { return a.t_start < b.t_start; });
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

  // Detection windows, each cut at the next onset.
  const std::size_t n = faults.size();
  std::vector<double> win_end(n);
  for (std::size_t i = 0; i < n; ++i) {
    win_end[i] = faults[i].t_end + params.detect_grace;
    if (i + 1 < n) win_end[i] = std::min(win_end[i], faults[i + 1].t_start);
  }
  auto window_of = [&](double t) -> int {
    for (std::size_t i = 0; i < n; ++i) {
      if (t >= faults[i].t_start && t < win_end[i]) return static_cast<int>(i);
    }
    return -1;
  };

  RunScore out;
  out.span = t_last - t_first;
  double windows = 0.0, windows_armed = 0.0;
  const bool armed = std::isfinite(t_armed);
  const double arm_from = armed ? std::max(t_armed, t_first) : t_last;
  for (std::size_t i = 0; i < n; ++i) {
    windows += overlap(faults[i].t_start, win_end[i], t_first, t_last);
    windows_armed += overlap(faults[i].t_start, win_end[i], arm_from, t_last);
  }
  out.healthy_time = out.span - windows;
  out.healthy_armed_time = armed ? (t_last - arm_from) - windows_armed : 0.0;

  out.faults.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.faults[i].fault = faults[i];
    out.faults[i].armed_at_onset = armed && t_armed <= faults[i].t_start;
  }
  for (const Alarm& a : alarms) {
    if (!a.raised || a.t < t_first || a.t > t_last) continue;
    const int w = window_of(a.t);
    if (w < 0) {
      out.false_alarm_times.push_back(a.t);
      out.false_alarm_events.push_back(a);
      continue;
    }
    FaultScore& fs = out.faults[static_cast<std::size_t>(w)];
    if (fs.detected) continue;
    fs.detected = true;
    fs.delay = a.t - fs.fault.t_start;
    fs.raised_sensor = a.sensor;
    fs.raised_kind = a.kind;
    fs.isolated = a.sensor == fs.fault.sensor;
  }

  // Recovery: replay the conditions.
  for (std::size_t i = 0; i < n; ++i) {
    FaultScore& fs = out.faults[i];
    if (!fs.detected) continue;
    const double limit = i + 1 < n ? faults[i + 1].t_start : t_last;
    std::array<bool, 3> raised{false, false, false};
    auto clear = [&] { return !raised[0] && !raised[1] && !raised[2]; };
    std::size_t k = 0;
    for (; k < alarms.size() && alarms[k].t <= fs.fault.t_end; ++k) {
      raised[static_cast<int>(alarms[k].sensor)] = alarms[k].raised;
    }
    if (clear()) {
      fs.recovered = true;
      fs.recovery_delay = 0.0;
      continue;
    }
    for (; k < alarms.size() && alarms[k].t <= limit; ++k) {
      raised[static_cast<int>(alarms[k].sensor)] = alarms[k].raised;
      if (clear()) {
        fs.recovered = true;
        fs.recovery_delay = alarms[k].t - fs.fault.t_end;
        break;
      }
    }
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
