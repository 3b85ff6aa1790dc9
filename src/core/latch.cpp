#include "usv_fdi/core/latch.hpp"

namespace usvfdi {

const char* to_string(AckResult r) {
  switch (r) {
    case AckResult::kAccepted:
      return "accepted";
    case AckResult::kStaleSequence:
      return "stale sequence";
    case AckResult::kUnknownSequence:
      return "unknown sequence";
    case AckResult::kNothingToAck:
      return "nothing to acknowledge";
  }
  return "?";
}

bool FaultLatch::on_detection(const Detection& d, const Mat2& A, FaultEvent* event) {
  const FaultState s = ev_.state;
  FaultState next = s;
  if (d.active) {
    if (s == FaultState::kNormal || s == FaultState::kAcknowledged ||
        s == FaultState::kClearedUnacknowledged) {
      next = FaultState::kRaised;
    }
  } else {
    if (s == FaultState::kRaised) next = FaultState::kClearedUnacknowledged;
    if (s == FaultState::kActiveAcknowledged) next = FaultState::kAcknowledged;
  }
  if (next == s) {
    // A refined kind of a raised fault is published (same state, next sequence).
    const bool raised = s == FaultState::kRaised || s == FaultState::kActiveAcknowledged;
    if (!(d.active && d.update && raised && d.kind != ev_.kind)) return false;
    ev_.kind = d.kind;
    ev_.t = d.detection_time;
    ev_.A = A;
    ev_.message = d.message;
    ++ev_.sequence;
    *event = ev_;
    return true;
  }
  ev_.state = next;
  ev_.t = d.detection_time;
  ev_.statistic = d.statistic;
  ev_.threshold = d.threshold;
  ev_.A = A;
  ev_.message = d.message;
  if (d.active) {
    ev_.kind = d.kind;
    ev_.c_a = d.c_a;
    ev_.c_g = d.c_g;
    ev_.onset_time = d.onset_time;
    ev_.detection_time = d.detection_time;
  }
  ++ev_.sequence;
  *event = ev_;
  return true;
}

AckResult FaultLatch::acknowledge(std::uint64_t sequence, double t, const std::string& who,
                                  FaultEvent* event) {
  if (sequence > ev_.sequence) return AckResult::kUnknownSequence;
  if (sequence < ev_.sequence) return AckResult::kStaleSequence;
  if (ev_.state == FaultState::kRaised) {
    ev_.state = FaultState::kActiveAcknowledged;
  } else if (ev_.state == FaultState::kClearedUnacknowledged) {
    ev_.state = FaultState::kAcknowledged;
  } else {
    return AckResult::kNothingToAck;
  }
  ev_.t = t;
  ev_.message = "acknowledged by " + who;
  ++ev_.sequence;
  *event = ev_;
  return AckResult::kAccepted;
}

}  // namespace usvfdi
