// The bridge alert management side of `usv-fdi bridge` (IEC 62923 BAM over IEC 61162-450):
// which ALF sentences a latched fault instance is shown as, the cyclic ALC list, and what an
// ACN from the bridge asks for. Pure functions of the latched state (Row), no DDS, no sockets.
//
//   latched state (FaultEvent)   ALF state
//   raised                       V active-unacknowledged
//   active_acknowledged          A active-acknowledged
//   cleared_unacknowledged       U rectified-unacknowledged
//   acknowledged, normal         N normal
//
// One alert per sensor (accelerometer, gyro, unknown) with configurable identifiers under the
// configured manufacturer mnemonic, instance 1. The revision counter follows the event's
// sequence (1..99, wrapping), so every change of the latched state is a new revision.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ack_protocol.hpp"
#include "monitor_model.hpp"
#include "usv_fdi/nmea/alert.hpp"

namespace usvfdi::app {

struct BridgeAlertConfig {
  std::string talker = "II";         ///< talker of the sentences written
  std::string manufacturer = "UFD";  ///< manufacturer mnemonic code (3 characters A-Z, 0-9)
  /// Alert identifiers of the accelerometer, gyro and unknown-sensor alerts.
  std::array<long, 3> alert_ids{{3001, 3002, 3003}};
  long instance = 1;  ///< alert instance (1..999999)
  nmea::AlertCategory category = nmea::AlertCategory::kB;
  nmea::AlertPriority priority = nmea::AlertPriority::kWarning;
};

/// Checks the configuration; an empty string when usable, else what is wrong.
std::string check(const BridgeAlertConfig& c);

/// The ALF state of a latched state.
nmea::AlertState alert_state(FaultState s);
/// The revision counter of an event's sequence (1..99; sequence 0 and 1 are revision 1).
int alert_revision(std::uint64_t sequence);
/// The alert of a sensor under the configuration.
nmea::AlertIdentity alert_of(const BridgeAlertConfig& c, Sensor s);

/// The ALF sentences (with CR LF) of one latched instance: a title (the sensor) and a
/// description (kind, confidences, vessel). `message_id` is the sequential message identifier
/// (0..9) of this ALF message; `now` the time of the last change.
std::vector<std::string> alf_sentences(const BridgeAlertConfig& c, const Row& row, int message_id,
                                       const nmea::UtcTime& now);

/// The ALC entries of the instances that are not normal, in sensor order.
std::vector<nmea::AlcEntry> alc_entries(const BridgeAlertConfig& c, const std::vector<Row>& rows);

/// What an ACN from the bridge asks of this vessel's alerts.
struct AcnAction {
  enum What {
    kNotOurs,      ///< another equipment's alert (or an unknown identifier): ignored, no answer
    kAcknowledge,  ///< send `ack` (the revision in force) to the sidecar
    kRepeat,       ///< answer with the alert's ALF
    kRefuse,       ///< answer with ARC (`why` says why)
  };
  What what = kNotOurs;
  Sensor sensor = Sensor::kUnknown;
  AckRequest ack;
  std::string why;
};

/// Judges an ACN against the latched state of vessel `mmsi` (`row`: the instance of the sensor
/// the ACN names, nullptr when none is known). Acknowledge (A) is accepted for a raised or
/// cleared-unacknowledged instance, with the same rules as FaultAck; request/repeat (Q) for any
/// of our alerts; silence (S) and responsibility transfer (O) are refused (this equipment has
/// no audible signal and keeps responsibility).
AcnAction judge_acn(const BridgeAlertConfig& c, std::uint32_t mmsi, const nmea::Acn& acn,
                    const Row* row);

/// The sensor of one of our alerts; nullopt when the identity is not ours.
std::optional<Sensor> sensor_of(const BridgeAlertConfig& c, const nmea::AlertIdentity& alert);

/// The UTC time of day of a wall-clock time [s since the epoch].
nmea::UtcTime utc_time_of(double unix_seconds);

}  // namespace usvfdi::app
