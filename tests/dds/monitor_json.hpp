// The one model and parser of `usv-fdi monitor --json [--status]` for every test program (dds,
// fleet, security): every field the monitor prints, plus when the test received the line. The
// older names (MonitorEvent in fleet.hpp, FaultUpdate in tests/fleet/monitor_log.hpp) are aliases
// of these.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "io/json_lite.hpp"

namespace usvfdi::test_support {

/// {"type":"fault"}: one FaultEvent update.
struct MonitorFault {
  unsigned mmsi = 0;
  std::string sensor, state, kind, message;
  double c_a = 0, c_g = 0, statistic = 0, threshold = 0, onset_time = 0, detection_time = 0;
  double stamp = 0;         ///< time of this state change (vessel's source clock) [s]
  double age_s = 0;         ///< wall seconds since the sidecar wrote it, when printed
  double heard_age_s = -1;  ///< seconds since the monitor last received anything from the vessel
  unsigned long long sequence = 0;
  bool alive = true;      ///< false: the monitor has lost the sidecar that wrote it
  double received = 0.0;  ///< when the test read the line [s on the test's clock]
};

/// {"type":"status"}: one FdiStatus (--status).
struct MonitorStatusLine {
  unsigned mmsi = 0;
  double stamp = -1;  ///< -1: no sample yet
  bool converged = false, armed = false, ins_healthy = false, rudder_healthy = false;
  unsigned long long samples = 0, dropped = 0;
  std::vector<std::string> input_flags, identification_paused, isolation_paused;
  unsigned long long rejected_timestamps = 0, invalid_values = 0, gaps = 0, reordered = 0,
                     dropped_inputs = 0;
  double heard_age_s = -1;
  std::vector<double> a;  ///< A-hat, row major
  /// The surge speed, the model's speed ratio and its reference speed (NaN: null).
  double surge_speed = 0, speed_ratio = 0, reference_speed = 0;
  double received = 0.0;
  static bool has(const std::vector<std::string>& v, const std::string& f) {
    return std::find(v.begin(), v.end(), f) != v.end();
  }
  bool has_flag(const std::string& f) const { return has(input_flags, f); }
};

/// {"type":"vessel"}: a vessel going silent or heard again.
struct MonitorVesselChange {
  unsigned mmsi = 0;
  bool silent = false;
  double heard_age_s = -1, gap_s = -1, silent_after_s = -1;
  double received = 0.0;
};

/// {"type":"conflict"}: a writer other than an instance's owner.
struct MonitorConflict {
  unsigned mmsi = 0;
  std::string sensor, verdict, why, writer, state, owner;
  unsigned long long sequence = 0, owner_sequence = 0;
  double received = 0.0;
};

/// One parsed line: `type` says which member is set ("" : not a JSON object; another type: kept
/// in `type` only, a consumer ignores types it does not know).
struct MonitorLine {
  std::string type;
  MonitorFault fault;
  MonitorStatusLine status;
  MonitorVesselChange vessel;
  MonitorConflict conflict;
};

/// Parses one stdout line of the monitor. Throws std::runtime_error on a malformed JSON line or
/// a missing field.
inline MonitorLine parse_monitor_json(const std::string& line, double received = 0.0) {
  MonitorLine out;
  if (line.empty() || line[0] != '{') return out;
  namespace js = usvfdi::testing_json;
  const js::Value v = js::Parser(line).parse_document();
  out.type = v.at("type").str;
  const auto u = [&](const char* k) { return static_cast<unsigned long long>(v.at(k).num); };
  if (out.type == "fault") {
    MonitorFault& f = out.fault;
    f.mmsi = static_cast<unsigned>(v.at("mmsi").num);
    f.sensor = v.at("sensor").str;
    f.state = v.at("state").str;
    f.kind = v.at("kind").str;
    f.message = v.at("message").str;
    f.c_a = v.at("c_a").num;
    f.c_g = v.at("c_g").num;
    f.statistic = v.at("statistic").num;
    f.threshold = v.at("threshold").num;
    f.onset_time = v.at("onset_time").num;
    f.detection_time = v.at("detection_time").num;
    f.stamp = v.at("stamp").num;
    f.age_s = v.at("age_s").num;
    f.heard_age_s = v.at("heard_age_s").num;
    f.sequence = u("sequence");
    f.alive = v.at("alive").b;
    f.received = received;
  } else if (out.type == "status") {
    MonitorStatusLine& s = out.status;
    s.mmsi = static_cast<unsigned>(v.at("mmsi").num);
    s.stamp = v.at("stamp").kind == js::Value::kNumber ? v.at("stamp").num : -1.0;
    s.converged = v.at("converged").b;
    s.armed = v.at("armed").b;
    s.ins_healthy = v.at("ins_healthy").b;
    s.rudder_healthy = v.at("rudder_healthy").b;
    s.samples = u("samples");
    s.dropped = u("dropped");
    const auto names = [&](const char* key) {
      std::vector<std::string> n;
      for (const js::Value& x : v.at(key).arr) n.push_back(x.str);
      return n;
    };
    s.input_flags = names("input_flags");
    s.identification_paused = names("identification_paused");
    s.isolation_paused = names("isolation_paused");
    s.rejected_timestamps = u("rejected_timestamps");
    s.invalid_values = u("invalid_values");
    s.gaps = u("gaps");
    s.reordered = u("reordered");
    s.dropped_inputs = u("dropped_inputs");
    s.heard_age_s = v.at("heard_age_s").num;
    for (const js::Value& x : v.at("a").arr) s.a.push_back(x.num);
    const auto maybe = [&](const char* key) {
      const js::Value& x = v.at(key);
      return x.kind == js::Value::kNumber ? x.num : std::nan("");
    };
    s.surge_speed = maybe("surge_speed");
    s.speed_ratio = maybe("speed_ratio");
    s.reference_speed = maybe("reference_speed");
    s.received = received;
  } else if (out.type == "vessel") {
    MonitorVesselChange& c = out.vessel;
    c.mmsi = static_cast<unsigned>(v.at("mmsi").num);
    c.silent = v.at("silent").b;
    c.heard_age_s = v.at("heard_age_s").num;
    if (!c.silent) c.gap_s = v.at("gap_s").num;
    c.silent_after_s = v.at("silent_after_s").num;
    c.received = received;
  } else if (out.type == "conflict") {
    MonitorConflict& c = out.conflict;
    c.mmsi = static_cast<unsigned>(v.at("mmsi").num);
    c.sensor = v.at("sensor").str;
    c.verdict = v.at("verdict").str;
    c.why = v.at("why").str;
    c.writer = v.at("writer").str;
    c.state = v.at("state").str;
    c.owner = v.at("owner").str;
    c.sequence = u("sequence");
    c.owner_sequence = u("owner_sequence");
    c.received = received;
  }
  return out;
}

}  // namespace usvfdi::test_support
