// What the fleet and service-security tests read back from the real executables: the JSON Lines
// of `usv-fdi monitor --json [--status]` (every field the tests check, plus when the test
// received the line) and the fault-event lines of the sidecar's log (`usv-fdi run`), which are
// the ground truth the shore's view is compared with.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "monitor_json.hpp"
#include "process.hpp"

namespace usvfdi::fleet::test {

/// The monitor's JSON Lines, as the one model of the test-support library (monitor_json.hpp).
using FaultUpdate = usvfdi::test_support::MonitorFault;
using StatusUpdate = usvfdi::test_support::MonitorStatusLine;
using VesselChange = usvfdi::test_support::MonitorVesselChange;
using ConflictReport = usvfdi::test_support::MonitorConflict;

/// Everything a monitor printed, in order.
struct MonitorLog {
  std::vector<FaultUpdate> faults;
  std::vector<StatusUpdate> statuses;
  std::vector<VesselChange> vessels;
  std::vector<ConflictReport> conflicts;
  std::vector<std::string> other;  ///< lines that are not JSON objects (there should be none)

  /// Parses one stdout line; throws std::runtime_error on a malformed JSON line.
  void add(const std::string& line, double received) {
    if (line.empty() || line[0] != '{') {
      if (!line.empty()) other.push_back(line);
      return;
    }
    const usvfdi::test_support::MonitorLine l =
        usvfdi::test_support::parse_monitor_json(line, received);
    if (l.type == "fault") {
      faults.push_back(l.fault);
    } else if (l.type == "status") {
      statuses.push_back(l.status);
    } else if (l.type == "vessel") {
      vessels.push_back(l.vessel);
    } else if (l.type == "conflict") {
      conflicts.push_back(l.conflict);
    } else {
      other.push_back(line);
    }
  }

  /// The updates of one fault instance, in the order printed.
  std::vector<FaultUpdate> of(unsigned mmsi, const std::string& sensor) const {
    std::vector<FaultUpdate> out;
    for (const auto& f : faults) {
      if (f.mmsi == mmsi && f.sensor == sensor) out.push_back(f);
    }
    return out;
  }
  bool has(unsigned mmsi, const std::string& sensor, const std::string& state) const {
    for (const auto& f : faults) {
      if (f.mmsi == mmsi && f.sensor == sensor && f.state == state && f.alive) return true;
    }
    return false;
  }
  /// The last status of a vessel, or nullptr.
  const StatusUpdate* last_status(unsigned mmsi) const {
    for (auto it = statuses.rbegin(); it != statuses.rend(); ++it) {
      if (it->mmsi == mmsi) return &*it;
    }
    return nullptr;
  }

  std::string dump() const {
    std::string s;
    char buf[320];
    for (const auto& f : faults) {
      std::snprintf(buf, sizeof buf,
                    "  [%7.3f s] %u %-13s #%llu %-19s %-6s t=%7.2f det=%7.2f C_a=%.2f C_g=%.2f "
                    "age=%.2f%s\n",
                    f.received, f.mmsi, f.sensor.c_str(), f.sequence, f.state.c_str(),
                    f.kind.c_str(), f.stamp, f.detection_time, f.c_a, f.c_g, f.age_s,
                    f.alive ? "" : " (sidecar gone)");
      s += buf;
    }
    for (const auto& o : other) s += "  other: " + o + "\n";
    return s;
  }
};

/// Reads the monitor's lines into `log` until `done(*log)` holds (true) or `timeout` elapses or
/// the monitor's stdout ends (false). `t0` is the test's clock origin for `received`.
template <class Done>
bool read_monitor_until(dds::test::ChildProcess& monitor, MonitorLog* log,
                        std::chrono::milliseconds timeout, std::chrono::steady_clock::time_point t0,
                        Done done) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  while (!done(*log)) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return false;
    const auto line = monitor.read_line(left);
    if (!line) return false;
    log->add(*line, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return true;
}

/// A fault event as the sidecar logged it ("fault event MMSI m sensor #n state kind=k C_a=x
/// C_g=y t=z s: message"): what it published, in order.
struct SidecarEvent {
  unsigned mmsi = 0;
  std::string sensor, state, kind;
  unsigned long long sequence = 0;
  double c_a = 0, c_g = 0, t = 0;
};

inline std::vector<SidecarEvent> sidecar_events(const std::string& log) {
  std::vector<SidecarEvent> out;
  const std::string marker = "fault event MMSI ";
  for (std::size_t at = log.find(marker); at != std::string::npos; at = log.find(marker, at + 1)) {
    SidecarEvent e;
    char sensor[32] = {}, state[32] = {}, kind[32] = {};
    if (std::sscanf(log.c_str() + at,
                    "fault event MMSI %u %31s #%llu %31s kind=%31s C_a=%lf C_g=%lf t=%lf", &e.mmsi,
                    sensor, &e.sequence, state, kind, &e.c_a, &e.c_g, &e.t) == 8) {
      e.sensor = sensor;
      e.state = state;
      e.kind = kind;
      out.push_back(e);
    }
  }
  return out;
}

/// The integer right before `suffix` in `text` ("(5001 samples, ..."), or -1.
inline long long number_before(const std::string& text, const std::string& suffix) {
  const auto at = text.find(suffix);
  if (at == std::string::npos) return -1;
  auto begin = at;
  while (begin > 0 && text[begin - 1] >= '0' && text[begin - 1] <= '9') --begin;
  if (begin == at) return -1;
  return std::stoll(text.substr(begin, at - begin));
}

}  // namespace usvfdi::fleet::test
