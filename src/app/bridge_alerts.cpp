#include "bridge_alerts.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>

namespace usvfdi::app {

std::string check(const BridgeAlertConfig& c) {
  if (c.talker.size() != 2) return "talker '" + c.talker + "' is not two characters";
  for (char ch : c.talker) {
    if (!std::isdigit(static_cast<unsigned char>(ch)) &&
        !std::isupper(static_cast<unsigned char>(ch))) {
      return "talker '" + c.talker + "' is not A-Z, 0-9";
    }
  }
  if (c.manufacturer.size() != 3) {
    return "manufacturer mnemonic '" + c.manufacturer + "' is not three characters";
  }
  for (char ch : c.manufacturer) {
    if (!std::isdigit(static_cast<unsigned char>(ch)) &&
        !std::isupper(static_cast<unsigned char>(ch))) {
      return "manufacturer mnemonic '" + c.manufacturer + "' is not A-Z, 0-9";
    }
  }
  for (std::size_t i = 0; i < c.alert_ids.size(); ++i) {
    if (c.alert_ids[i] < 0 || c.alert_ids[i] > 9999999) {
      return "alert identifier " + std::to_string(c.alert_ids[i]) + " is not 0..9999999";
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (c.alert_ids[i] == c.alert_ids[j]) {
        return "alert identifier " + std::to_string(c.alert_ids[i]) + " is given twice";
      }
    }
  }
  if (c.instance < 1 || c.instance > 999999) {
    return "alert instance " + std::to_string(c.instance) + " is not 1..999999";
  }
  return {};
}

nmea::AlertState alert_state(FaultState s) {
  switch (s) {
    case FaultState::kRaised:
      return nmea::AlertState::kActiveUnacknowledged;
    case FaultState::kActiveAcknowledged:
      return nmea::AlertState::kActiveAcknowledged;
    case FaultState::kClearedUnacknowledged:
      return nmea::AlertState::kRectifiedUnacknowledged;
    case FaultState::kAcknowledged:
    case FaultState::kNormal:
      break;
  }
  return nmea::AlertState::kNormal;
}

int alert_revision(std::uint64_t sequence) {
  return sequence == 0 ? 1 : static_cast<int>((sequence - 1) % 99) + 1;
}

nmea::AlertIdentity alert_of(const BridgeAlertConfig& c, Sensor s) {
  nmea::AlertIdentity a;
  a.manufacturer = c.manufacturer;
  a.id = c.alert_ids[static_cast<std::size_t>(s) < c.alert_ids.size() ? static_cast<std::size_t>(s)
                                                                      : c.alert_ids.size() - 1];
  a.instance = c.instance;
  return a;
}

std::optional<Sensor> sensor_of(const BridgeAlertConfig& c, const nmea::AlertIdentity& alert) {
  if (alert.manufacturer != c.manufacturer || alert.instance != c.instance) return std::nullopt;
  for (std::size_t i = 0; i < c.alert_ids.size(); ++i) {
    if (alert.id == c.alert_ids[i]) return static_cast<Sensor>(i);
  }
  return std::nullopt;
}

namespace {

const char* title_of(Sensor s) {
  switch (s) {
    case Sensor::kAccelerometer:
      return "INS accelerometer fault";
    case Sensor::kGyro:
      return "INS gyro fault";
    case Sensor::kUnknown:
      break;
  }
  return "INS fault, sensor unknown";
}

}  // namespace

std::vector<std::string> alf_sentences(const BridgeAlertConfig& c, const Row& row, int message_id,
                                       const nmea::UtcTime& now) {
  nmea::Alf alf;
  alf.talker = c.talker;
  alf.message_id = message_id % 10;
  alf.time = now;
  alf.category = c.category;
  alf.priority = c.priority;
  alf.state = alert_state(row.ev.state);
  alf.alert = alert_of(c, row.ev.sensor);
  alf.revision = alert_revision(row.ev.sequence);
  alf.escalation = 0;
  alf.text = title_of(row.ev.sensor);
  char description[96];
  std::snprintf(description, sizeof description, "%s %s Ca %.2f Cg %.2f MMSI %u",
                to_string(row.ev.kind), to_string(row.ev.state), row.ev.c_a, row.ev.c_g,
                static_cast<unsigned>(row.mmsi));
  const auto r = nmea::format_alf_message(alf, description);
  // Refused only for an unusable configuration, which check() has ruled out.
  return r.ok() ? r.value() : std::vector<std::string>{};
}

std::vector<nmea::AlcEntry> alc_entries(const BridgeAlertConfig& c, const std::vector<Row>& rows) {
  std::vector<nmea::AlcEntry> out;
  for (int s = 0; s < 3; ++s) {
    for (const Row& r : rows) {
      if (static_cast<int>(r.ev.sensor) != s) continue;
      if (alert_state(r.ev.state) == nmea::AlertState::kNormal) continue;
      out.push_back({alert_of(c, r.ev.sensor), alert_revision(r.ev.sequence)});
    }
  }
  return out;
}

AcnAction judge_acn(const BridgeAlertConfig& c, std::uint32_t mmsi, const nmea::Acn& acn,
                    const Row* row) {
  AcnAction act;
  const std::optional<Sensor> sensor = sensor_of(c, acn.alert);
  if (!sensor) return act;  // kNotOurs
  act.sensor = *sensor;
  switch (acn.command) {
    case nmea::AlertCommand::kRequestRepeat:
      act.what = AcnAction::kRepeat;
      return act;
    case nmea::AlertCommand::kSilence:
      act.what = AcnAction::kRefuse;
      act.why = "silence refused: this equipment has no audible signal";
      return act;
    case nmea::AlertCommand::kResponsibilityTransfer:
      act.what = AcnAction::kRefuse;
      act.why = "responsibility transfer refused: the alert stays with the bridge";
      return act;
    case nmea::AlertCommand::kAcknowledge:
      break;
  }
  act.ack.mmsi = mmsi;
  act.ack.sensor = *sensor;
  if (row == nullptr || (row->ev.state != FaultState::kRaised &&
                         row->ev.state != FaultState::kClearedUnacknowledged)) {
    act.what = AcnAction::kRefuse;
    act.why = std::string("nothing to acknowledge (") +
              (row == nullptr ? "no latched state" : to_string(row->ev.state)) + ")";
    return act;
  }
  if (!row->alive) {
    act.what = AcnAction::kRefuse;
    act.why = "the sidecar that published the alert is gone";
    return act;
  }
  act.what = AcnAction::kAcknowledge;
  act.ack.sequence = row->ev.sequence;  // the revision in force
  return act;
}

nmea::UtcTime utc_time_of(double unix_seconds) {
  const double day = std::fmod(unix_seconds, 86400.0);
  const double d = day < 0 ? day + 86400.0 : day;
  nmea::UtcTime t;
  t.hours = static_cast<int>(d / 3600.0);
  t.minutes = static_cast<int>((d - 3600.0 * t.hours) / 60.0);
  t.centiseconds =
      static_cast<int>(std::floor((d - 3600.0 * t.hours - 60.0 * t.minutes) * 100.0 + 1e-6));
  if (t.centiseconds > 5999) t.centiseconds = 5999;
  return t;
}

}  // namespace usvfdi::app
