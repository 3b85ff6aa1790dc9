// Bridge alert management sentences (IEC 62923-1/-2 BAM, carried by IEC 61162-1 / NMEA 0183):
// ALF, ALC, HBT and ARC written by the sidecar, ACN read from the bridge (and parsers of all
// five, so that what is written can be checked).
//
// Field layouts, as printed in the digital-interface chapters of the Icom GM600, Furuno BR-500
// and FMD-3300 and JRC JFE-680 manuals (found with the search tool; the IEC texts themselves
// were not available):
//   $--ALF,x,x,x,hhmmss.ss,a,a,a,aaa,x.x,x.x,x.x,x,c--c
//     1 total number of ALF sentences of this message (1-2), 2 sentence number (1-2),
//     3 sequential message identifier (0-9), 4 time of last change (null in sentence 2),
//     5 alert category A/B/C, 6 priority E emergency alarm, A alarm, W warning, C caution,
//     7 state (5-7 null in sentence 2), 8 manufacturer mnemonic code (null for a standardised
//     alert), 9 alert identifier, 10 alert instance (1-999999), 11 revision counter (1-99),
//     12 escalation counter (0-9), 13 alert text (sentence 1: title, sentence 2: description).
//     State letters (Furuno FMD-3300 and issue 12): V active-unacknowledged, S active-silenced,
//     A active-acknowledged, O active-responsibility transferred, U rectified-unacknowledged,
//     N normal. (The Icom GM600 page prints A and V the other way round, against the two
//     other sources; not followed.)
//   $--ALC,xx,xx,xx,x.x,aaa,x.x,x.x,x.x,...   cyclic alert list (every 30 s, Icom):
//     total sentences (1-99), sentence number (1-99), sequential message id (0-99), number of
//     alert entries, then per entry manufacturer mnemonic, alert identifier, instance,
//     revision counter; an entry is never split between two sentences (Furuno).
//   $--HBT,x.x,A,x   heartbeat: configured repeat interval [s], equipment status A normal /
//     V system fail, sequential sequence identifier (0-9).
//   $--ARC,hhmmss.ss,aaa,x.x,x.x,c   alert command refused: release time, manufacturer
//     mnemonic, alert identifier, alert instance, refused command A/Q/O/S.
//   $--ACN,hhmmss.ss,aaa,x.x,x.x,c,a   alert command: time, manufacturer mnemonic, alert
//     identifier, alert instance, command A acknowledge, Q request/repeat information,
//     O responsibility transfer, S silence; sentence status flag C ("a sentence without C is
//     not a command", Furuno BR-500), refused here with kBadField.
// Alert identifiers are read as 0..9999999, instances as 1..999999 or null, manufacturer
// mnemonic codes as null or three characters A-Z/0-9. Texts: '^hh' escapes are decoded when
// read, and reserved characters, ',' and '^' are written as '^hh'; an ALF text is truncated
// so that the sentence fits 82 characters.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "usv_fdi/nmea/result.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea {

/// UTC time of day hhmmss.ss; seconds up to 60.99 (a leap second). Read to the hundredth
/// (more digits are cut off); written with as few decimals as the value needs.
struct UtcTime {
  int hours = 0;         ///< 0..23
  int minutes = 0;       ///< 0..59
  int centiseconds = 0;  ///< 0..6099 (seconds x 100)
  bool operator==(const UtcTime& o) const {
    return hours == o.hours && minutes == o.minutes && centiseconds == o.centiseconds;
  }
};

/// Which alert: manufacturer mnemonic (empty for a standardised alert), identifier, instance.
struct AlertIdentity {
  std::string manufacturer;
  long id = 0;                   ///< 0..9999999
  std::optional<long> instance;  ///< 1..999999
  bool operator==(const AlertIdentity& o) const {
    return manufacturer == o.manufacturer && id == o.id && instance == o.instance;
  }
};

enum class AlertCategory : char { kA = 'A', kB = 'B', kC = 'C' };
enum class AlertPriority : char {
  kEmergencyAlarm = 'E',
  kAlarm = 'A',
  kWarning = 'W',
  kCaution = 'C',
};
enum class AlertState : char {
  kActiveUnacknowledged = 'V',
  kActiveSilenced = 'S',
  kActiveAcknowledged = 'A',
  kActiveResponsibilityTransferred = 'O',
  kRectifiedUnacknowledged = 'U',
  kNormal = 'N',
};
enum class AlertCommand : char {
  kAcknowledge = 'A',
  kRequestRepeat = 'Q',
  kResponsibilityTransfer = 'O',
  kSilence = 'S',
};

/// The revision counter after `revision`: 1..99, 99 wraps to 1.
inline int next_revision(int revision) { return revision >= 99 || revision < 1 ? 1 : revision + 1; }

/// $--ALF: one alert.
struct Alf {
  std::string talker = "II";
  int total_sentences = 1;                ///< 1..2
  int sentence_number = 1;                ///< 1..total_sentences
  int message_id = 0;                     ///< 0..9
  std::optional<UtcTime> time;            ///< of the last change; null in sentence 2
  std::optional<AlertCategory> category;  ///< required in sentence 1
  std::optional<AlertPriority> priority;  ///< required in sentence 1
  std::optional<AlertState> state;        ///< required in sentence 1
  AlertIdentity alert;
  int revision = 1;               ///< 1..99
  std::optional<int> escalation;  ///< 0..9
  std::string text;               ///< decoded; truncated by format_alf to fit 82 characters
  bool operator==(const Alf& o) const;
};

/// One entry of an ALC list.
struct AlcEntry {
  AlertIdentity alert;
  int revision = 1;  ///< 1..99
  bool operator==(const AlcEntry& o) const { return alert == o.alert && revision == o.revision; }
};

/// $--ALC: one sentence of the cyclic alert list.
struct Alc {
  std::string talker = "II";
  int total_sentences = 1;  ///< 1..99
  int sentence_number = 1;  ///< 1..total_sentences
  int message_id = 0;       ///< 0..99
  std::vector<AlcEntry> entries;
  bool operator==(const Alc& o) const {
    return talker == o.talker && total_sentences == o.total_sentences &&
           sentence_number == o.sentence_number && message_id == o.message_id &&
           entries == o.entries;
  }
};

/// $--HBT: heartbeat.
struct Hbt {
  std::string talker = "II";
  std::optional<double> interval_s;  ///< configured repeat interval, (0, 999]
  bool normal = true;                ///< status A (true) or V system fail (false)
  int sequence = 0;                  ///< 0..9, wraps
  bool operator==(const Hbt& o) const {
    return talker == o.talker && interval_s == o.interval_s && normal == o.normal &&
           sequence == o.sequence;
  }
};

/// $--ARC: alert command refused.
struct Arc {
  std::string talker = "II";
  std::optional<UtcTime> time;
  AlertIdentity alert;
  AlertCommand refused = AlertCommand::kAcknowledge;
  bool operator==(const Arc& o) const {
    return talker == o.talker && time == o.time && alert == o.alert && refused == o.refused;
  }
};

/// $--ACN: alert command from the bridge.
struct Acn {
  std::string talker = "BN";
  std::optional<UtcTime> time;
  AlertIdentity alert;
  AlertCommand command = AlertCommand::kAcknowledge;
  bool operator==(const Acn& o) const {
    return talker == o.talker && time == o.time && alert == o.alert && command == o.command;
  }
};

Result<Alf> parse_alf(const Sentence& s);
Result<Alc> parse_alc(const Sentence& s);
Result<Hbt> parse_hbt(const Sentence& s);
Result<Arc> parse_arc(const Sentence& s);
Result<Acn> parse_acn(const Sentence& s);

Sentence to_sentence(const Alf& x);  ///< the text not truncated (format_alf truncates)
Sentence to_sentence(const Alc& x);
Sentence to_sentence(const Hbt& x);
Sentence to_sentence(const Arc& x);
Sentence to_sentence(const Acn& x);

/// The sentence with checksum and CR LF, the text truncated to fit 82 characters; refused
/// (never throws) where parse_alf would refuse it.
Result<std::string> format_alf(const Alf& x);
Result<std::string> format_alc(const Alc& x);
Result<std::string> format_hbt(const Hbt& x);
Result<std::string> format_arc(const Arc& x);
Result<std::string> format_acn(const Acn& x);

/// An alert as ALF sentences: one (total 1) with `alert.text` as the title when `description`
/// is empty; otherwise two (total 2), the title in sentence 1 and the description in sentence 2,
/// whose time, category, priority and state are null. Each text is truncated to fit; the
/// total and sentence number of `alert` are ignored.
Result<std::vector<std::string>> format_alf_message(const Alf& alert,
                                                    const std::string& description);

/// The whole cyclic alert list as ALC sentences: as many entries per sentence as fit 82
/// characters (none split), total and sentence numbers set; one sentence with 0 entries for
/// an empty list.
Result<std::vector<std::string>> format_alc_list(const std::string& talker, int message_id,
                                                 const std::vector<AlcEntry>& entries);

}  // namespace usvfdi::nmea
