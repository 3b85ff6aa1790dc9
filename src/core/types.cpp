#include "usv_fdi/core/types.hpp"

namespace usvfdi {

const char* to_string(Sensor s) {
  switch (s) {
    case Sensor::kAccelerometer:
      return "accelerometer";
    case Sensor::kGyro:
      return "gyro";
    case Sensor::kUnknown:
      return "unknown";
  }
  return "unknown";
}

const char* to_string(FaultKind k) {
  switch (k) {
    case FaultKind::kUnknown:
      return "unknown";
    case FaultKind::kBias:
      return "bias";
    case FaultKind::kDrift:
      return "drift";
    case FaultKind::kStuck:
      return "stuck";
    case FaultKind::kNoise:
      return "noise";
    case FaultKind::kSpikes:
      return "spikes";
    case FaultKind::kScale:
      return "scale";
    case FaultKind::kStale:
      return "stale";
    case FaultKind::kInvalid:
      return "invalid";
  }
  return "unknown";
}

const char* to_string(FaultState s) {
  switch (s) {
    case FaultState::kNormal:
      return "normal";
    case FaultState::kRaised:
      return "raised";
    case FaultState::kActiveAcknowledged:
      return "active_acknowledged";
    case FaultState::kClearedUnacknowledged:
      return "cleared";
    case FaultState::kAcknowledged:
      return "acknowledged";
  }
  return "normal";
}

bool parse_sensor(const std::string& text, Sensor* out) {
  for (Sensor s : {Sensor::kAccelerometer, Sensor::kGyro, Sensor::kUnknown}) {
    if (text == to_string(s)) {
      *out = s;
      return true;
    }
  }
  return false;
}

bool parse_fault_kind(const std::string& text, FaultKind* out) {
  for (int i = 0; i <= static_cast<int>(FaultKind::kInvalid); ++i) {
    const auto k = static_cast<FaultKind>(i);
    if (text == to_string(k)) {
      *out = k;
      return true;
    }
  }
  return false;
}

bool parse_fault_state(const std::string& text, FaultState* out) {
  for (int i = 0; i <= static_cast<int>(FaultState::kAcknowledged); ++i) {
    const auto s = static_cast<FaultState>(i);
    if (text == to_string(s)) {
      *out = s;
      return true;
    }
  }
  return false;
}

}  // namespace usvfdi
