// Latched fault events, after IEC 62923 bridge alert management:
//   normal -> raised (active, unacknowledged)
//   raised --ack--> active-acknowledged --condition clears--> acknowledged (= normal)
//   raised --condition clears--> cleared-unacknowledged --ack--> acknowledged (= normal)
//   cleared-unacknowledged --condition returns--> raised
// A raised event is never lost or silently downgraded: only an acknowledgement of the
// sequence number currently in force moves an unacknowledged event on.
#pragma once

#include <cstdint>
#include <string>

#include "usv_fdi/core/detection.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi {

struct FaultEvent {
  Sensor sensor = Sensor::kUnknown;
  FaultState state = FaultState::kNormal;
  FaultKind kind = FaultKind::kUnknown;
  double c_a = 0.0, c_g = 0.0;   ///< isolation confidences at the decision
  double statistic = 0.0;        ///< residual statistic at this event
  double threshold = 0.0;        ///< threshold in force
  double onset_time = kNaN;      ///< estimated fault onset [s, source clock]
  double detection_time = kNaN;  ///< time of the raise [s, source clock]
  double t = kNaN;               ///< time of this event [s, source clock]
  std::uint64_t sequence = 0;    ///< per-instance, increases with every event
  Mat2 A = Mat2::Zero();         ///< estimate of A in force
  std::string message;
  /// The service run that issued `sequence` (set by the sidecar's pipeline; 0 elsewhere).
  std::uint64_t incarnation = 0;
};

enum class AckResult : std::uint8_t {
  kAccepted = 0,
  kStaleSequence,    ///< refers to an older event of this instance
  kUnknownSequence,  ///< refers to an event that was never published
  kNothingToAck,     ///< the instance is not awaiting an acknowledgement
};
const char* to_string(AckResult r);

class FaultLatch {
 public:
  explicit FaultLatch(Sensor sensor = Sensor::kUnknown) { ev_.sensor = sensor; }

  /// Applies a change of the sensor's condition. Returns true and fills *event when the
  /// latched state changed (an event to publish).
  bool on_detection(const Detection& d, const Mat2& A, FaultEvent* event);

  /// Operator acknowledgement of the event with this sequence number.
  AckResult acknowledge(std::uint64_t sequence, double t, const std::string& who,
                        FaultEvent* event);

  /// Restores a persisted event (restart without loss); later events continue its sequence.
  void restore(const FaultEvent& ev) { ev_ = ev; }

  const FaultEvent& current() const { return ev_; }
  FaultState state() const { return ev_.state; }
  /// True while the event is latched (not normal/acknowledged).
  bool latched() const {
    return ev_.state == FaultState::kRaised || ev_.state == FaultState::kActiveAcknowledged ||
           ev_.state == FaultState::kClearedUnacknowledged;
  }

 private:
  FaultEvent ev_;
};

}  // namespace usvfdi
