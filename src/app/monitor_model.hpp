// The monitor's model: its options, one fault instance as shown (Row) and one vessel's status.
// No Fast DDS in it (the FdiStatus type is the IDL's plain generated struct).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dds_options.hpp"
#include "usv_fdi/core/latch.hpp"
#include "usv_fdi/core/types.hpp"
#include "usv_fdi/dds/types.hpp"

namespace usvfdi::app {

struct MonitorArgs {
  DdsCli dds;
  std::vector<std::uint32_t> mmsi;  ///< filter (empty: every vessel)
  bool json = false;
  bool status = false;            ///< also show each vessel's FdiStatus
  std::vector<std::string> acks;  ///< MMSI:SENSOR:SEQUENCE
  std::string operator_id = "operator";
  double ack_timeout = 5.0;         ///< wait for the sidecar's confirmation of an ack [s]
  double discovery_timeout = 10.0;  ///< wait for a sidecar's ack reader [s]
  double duration = 0.0;            ///< stop after this long (0: until a signal; --once: 10 s)
  bool once = false;  ///< wait for the latched state (at most --duration), print it and exit
  int expect = 0;     ///< stop once this many instances are known
  double silent_after = 5.0;  ///< flag a vessel not heard for longer than this [s]
  std::string roster;         ///< file of the fleet's expected MMSIs ("" : no roster)
};

/// --once without --duration waits for the latched state at most this long [s].
constexpr double kOnceDefaultDuration = 10.0;

/// Wall-clock seconds since the epoch (the writer's source timestamps are on this clock).
inline double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// Monotonic seconds: the local receive times of "last heard".
inline double mono_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Row {
  std::uint32_t mmsi = 0;
  FaultEvent ev;
  double written = 0.0;  ///< the sidecar's write time (source timestamp) [s since epoch]
  bool alive = true;     ///< false: the sidecar that published it is gone
  std::string writer;    ///< the sidecar's FaultEvent writer (GUID text)
};
using RowKey = std::pair<std::uint32_t, int>;

struct VesselStatus {
  fdi::FdiStatus st;
  double written = 0.0;
  bool alive = true;
  std::string writer;  ///< the sidecar's FdiStatus writer (GUID text)
};

}  // namespace usvfdi::app
