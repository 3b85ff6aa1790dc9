// JSON Lines output of a replay: one JSON object per line, each with a "type" field.
//
//   {"type":"event",<the fault event's fields, fault_event_fields()>}
//   {"type":"estimate","t":..,"a":[a1,a2,a3,a4],"converged":bool,"excitation":..,"armed":bool}
//   {"type":"signal","t":..,"armed":bool,"mismatch":bool,"j":[a,g],"threshold":[a,g],
//    "c_a":..,"c_g":..}   (replay --signals S only)
//   {"type":"summary","samples":n,"rejected":n,"events":n,
//    "raised":{"accelerometer":n,"gyro":n,"unknown":n},"final_a":[..],"converged":bool,
//    "frozen_samples":n,"unconvergences":n,"duration_s":..,"complete":bool[,"error":".."]}
//
// Numbers are written with %.9g; NaN and infinities as null. Hand-written (no JSON library).
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "usv_fdi/core/engine.hpp"

namespace usvfdi::io {

/// A JSON string literal (with the quotes): escapes '"', '\\' and control characters;
/// bytes that are not valid UTF-8 become U+FFFD.
std::string json_string(const std::string& s);
/// A JSON number with %.9g, or null when x is not finite.
std::string json_number(double x);
/// A JSON number with `digits` significant digits (%.*g), or null when x is not finite.
std::string json_number(double x, int digits);

/// A fault event's fields as JSON members, without the braces, in this order:
///   "sensor":"accelerometer"|"gyro"|"unknown",
///   "state":"normal"|"raised"|"active_acknowledged"|"cleared"|"acknowledged",
///   "kind":"bias"|.., "sequence":n, "incarnation":n, "c_a":.., "c_g":.., "statistic":..,
///   "threshold":.., "onset_time":.., "detection_time":.., "stamp":.. (the event's own time,
///   FaultEvent::t), "a":[a1,a2,a3,a4], "message":".."
/// The one serialisation of a FaultEvent: the replay's event records, the sidecar's state
/// journal and `usv-fdi monitor --json` all write it (numbers with `digits` significant
/// digits: 9, or 17 where the value must survive a round trip).
std::string fault_event_fields(const FaultEvent& e, int digits = 9);

/// A JSON array of strings from a comma-separated list of names ("a,b" -> ["a","b"]; "" -> []),
/// the elements separated by `separator`.
std::string json_string_array(const std::string& names, const char* separator = ",");

/// What a replay did (the summary record).
struct RunSummary {
  std::uint64_t samples = 0;   ///< rows read
  std::uint64_t rejected = 0;  ///< rows the engine rejected (time missing or not increasing)
  std::uint64_t rejected_no_time = 0;    ///< of them: time missing or not finite
  std::uint64_t model_mismatches = 0;    ///< verdicts of model mismatch (never latched)
  std::uint64_t duplicates = 0;          ///< rows that repeat the previous one exactly (dropped)
  std::size_t first_duplicate_line = 0;  ///< the first of them (not in the JSON record)
  // The first rejected row (not in the JSON record; for the command's message).
  std::size_t first_rejected_line = 0;           ///< its line in the input (0: none rejected)
  double first_rejected_t = kNaN;                ///< its time [s]
  double first_rejected_after = kNaN;            ///< the latest time accepted before it [s]
  std::uint64_t events = 0;                      ///< event records written
  std::array<std::uint64_t, 3> raised{0, 0, 0};  ///< raised events per Sensor
  Vec4 final_a = Vec4::Zero();
  bool converged = false;
  std::uint64_t frozen_samples = 0;
  std::uint64_t unconvergences = 0;  ///< times a converged estimate lost convergence
  double duration_s = 0.0;           ///< last minus first sample time [s, data time]
  bool complete = true;              ///< false: the input ended in an error
  // For the command's messages, not in the JSON record:
  std::vector<std::string> warnings;  ///< PlausibilityCheck's findings on the input
  std::string not_converged;          ///< convergence_report() at the end ("" if converged)
  std::string error;                  ///< that error (only when !complete)
};

class JsonlWriter {
 public:
  explicit JsonlWriter(std::ostream& out) : out_(out) {}
  void event(const FaultEvent& e);
  /// t: data time of the record [s] (the estimate itself may lag by the identification delay).
  void estimate(double t, const Estimate& est, bool armed);
  /// The fault signals at data time t: the windowed statistic J_N per channel [accelerometer,
  /// gyro] and its enter thresholds, the isolation confidences C_a and C_g (6 significant
  /// digits: these records are for plots).
  void signal(double t, const IsolatorStatus& iso);
  /// A model-mismatch verdict began (active, with its reason) or ended.
  void mismatch(double t, bool active, const std::string& reason);
  void summary(const RunSummary& s);
  void flush();

 private:
  std::ostream& out_;
};

}  // namespace usvfdi::io
