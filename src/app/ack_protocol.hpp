// The acknowledgement protocol as the monitor sees it: the --ack spec, when the sidecar's
// confirmation has arrived, why an ack was not accepted, and where it is written. Pure functions
// of the latched state (Row), no DDS.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "monitor_model.hpp"

namespace usvfdi::app {

struct AckRequest {
  std::uint32_t mmsi = 0;
  Sensor sensor = Sensor::kAccelerometer;
  std::uint64_t sequence = 0;
};

/// Parses MMSI:SENSOR:SEQUENCE (e.g. 257000001:gyro:3); false and *why on a mistake.
bool parse_ack(const std::string& spec, AckRequest* out, std::string* why);
/// True once the instance moved past the acknowledged sequence to an acknowledged state.
bool ack_confirmed(const AckRequest& ack, const Row* row);
/// True if the latched state is already past the sequence (the sidecar will refuse it as stale).
bool ack_already_past(const AckRequest& ack, const Row* row);
/// Why the sidecar will refuse an ack, judged from the latched state the monitor sees.
std::string refusal_reason(const AckRequest& ack, const Row* row);
/// The partitions an acknowledgement to vessel `mmsi` is written in: the monitor's own, with a
/// vessel wildcard ("vessel-*", after any prefix) narrowed to that vessel's partition. Under DDS
/// Security a shore identity may write acks only into the partitions of the vessels it is granted.
std::vector<std::string> ack_partitions(const std::vector<std::string>& mine, std::uint32_t mmsi);

}  // namespace usvfdi::app
