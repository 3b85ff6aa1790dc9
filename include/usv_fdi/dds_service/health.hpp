// The sidecar's health file (container HEALTHCHECK, docker/README.md "Health check").
//
// `usv-fdi run --health-file PATH` rewrites PATH (write <PATH>.tmp, rename) every status
// period with one JSON object:
//   {"version": 1, "time": <unix s>, "pid": .., "mmsi": .., "state": "starting"|"running"|
//    "failed"|"stopped", "reason": "..", "period": <s>, "stall_limit": <s>,
//    "isolation_thread_age": <s>, "ident_thread_age": <s>, "publisher_thread_age": <s>,
//    "ins_age": <s or null>, "rudder_age": <s or null>, "samples": .., "converged": ..,
//    "armed": .., "input_flags": [..], "identification_paused": [..], "isolation_paused": [..],
//    "dropped": .., "fault_event_readers": .., "state_file": "..", "state_error": ".."}
// The thread ages are the seconds since each pipeline thread last went round its loop (an idle
// thread goes round every 50-100 ms): a wedged thread's age grows and the state becomes
// "failed" once it passes stall_limit. Input problems (a silent INS or rudder, bad samples),
// missing readers and raised faults are reported but never make the sidecar unhealthy: a
// restart would not fix them, and the sidecar reports them itself (status, fault events).
// `usv-fdi health` judges the file: check_health_file().
#pragma once

#include <cstdint>
#include <string>

#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::dds_service {

struct HealthReport {
  double time = 0.0;  ///< [s since the Unix epoch]
  long pid = 0;
  std::uint32_t mmsi = 0;
  std::string state = "starting";  ///< starting, running, failed, stopped
  std::string reason;
  double period = 1.0;       ///< how often the file is rewritten [s]
  double stall_limit = 5.0;  ///< a thread that has not gone round its loop for this long [s]
  pipeline::PipelineLiveness live;
  std::uint64_t samples = 0;
  bool converged = false, armed = false;
  std::uint32_t input_flags = 0;
  std::uint32_t identification_paused = 0, isolation_paused = 0;
  std::uint64_t dropped = 0;
  int fault_event_readers = 0;
  std::string state_file;   ///< the journal ("" if state is not persisted)
  std::string state_error;  ///< why the journal could not be written ("" if fine)
};

/// Marks the report "failed" (with the reason) when a pipeline thread has not advanced for
/// more than stall_limit seconds; leaves it alone otherwise.
void judge_threads(HealthReport* r);

std::string health_json(const HealthReport& r);

/// Replaces `path` with the report (<path>.tmp + rename). Returns false with *error.
bool write_health_file(const std::string& path, const HealthReport& r, std::string* error);

struct HealthVerdict {
  bool healthy = false;
  std::string line;  ///< one line: "healthy: ..." or "unhealthy: <reason>"
};

/// Healthy when the file exists, parses, was written at most max_age seconds before now,
/// says "starting" or "running", and each thread's age is at most max_age.
/// max_age <= 0: three of the file's periods, at least 3 s.
HealthVerdict check_health_file(const std::string& path, double max_age, double now_unix);

}  // namespace usvfdi::dds_service
