// The fleet's roster: the MMSIs the shore expects to hear (`monitor --roster FILE`). A vessel on
// the roster that was never heard, or has gone silent, is shown and reported, so that a partial
// view cannot pass for a healthy fleet; a vessel heard that is not on the roster is shown and
// marked. Pure logic on a caller-supplied monotonic clock (seconds), no DDS.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "vessel_liveness.hpp"

namespace usvfdi::app {

/// Parses a roster file's text: one MMSI (1..999999999) per line; '#' starts a comment; blank
/// lines are skipped; an MMSI given twice counts once. False with `*why` naming `name`, the line
/// and the text for anything else (also for a roster without any MMSI).
bool parse_roster(const std::string& text, const std::string& name, std::set<std::uint32_t>* out,
                  std::string* why);

/// Reads and parses a roster file; false with `*why` (cannot read, or parse_roster's reason).
bool load_roster(const std::string& path, std::set<std::uint32_t>* out, std::string* why);

/// Where a vessel stands against the roster.
enum class RosterState {
  kHeard,        ///< on the roster, heard and not silent
  kSilent,       ///< on the roster, heard once, silent now
  kNeverHeard,   ///< on the roster, nothing received from it yet
  kNotOnRoster,  ///< heard, but not on the roster
  kNoRoster,     ///< no roster given: heard, nothing to compare with
};
const char* to_string(RosterState s);

class RosterWatch {
 public:
  /// One change to report once: a roster vessel not heard `grace` s after the start, a roster
  /// vessel heard for the first time after it was reported, a vessel heard that is not on the
  /// roster.
  struct Change {
    std::uint32_t mmsi = 0;
    RosterState state = RosterState::kNeverHeard;  ///< kNeverHeard, kHeard or kNotOnRoster
    double waited = 0.0;  ///< kNeverHeard / kHeard: seconds since the monitor started
  };

  RosterWatch() = default;
  /// `roster` empty: no roster (nothing is ever reported). `start`: the monitor's start [s];
  /// `grace`: how long a roster vessel may stay unheard before it is reported [s].
  RosterWatch(std::set<std::uint32_t> roster, double start, double grace)
      : roster_(std::move(roster)), start_(start), grace_(grace) {}

  bool active() const { return !roster_.empty(); }
  const std::set<std::uint32_t>& roster() const { return roster_; }
  bool on_roster(std::uint32_t mmsi) const { return roster_.count(mmsi) > 0; }

  RosterState state(std::uint32_t mmsi, const VesselLiveness& live) const;
  /// The roster vessels never heard so far, in MMSI order.
  std::vector<std::uint32_t> never_heard(const VesselLiveness& live) const;
  /// Every vessel to show, in MMSI order: the roster's and every vessel heard.
  std::vector<std::uint32_t> shown(const VesselLiveness& live) const;

  /// The changes since the last call (each reported once).
  std::vector<Change> evaluate(const VesselLiveness& live, double now);

 private:
  std::set<std::uint32_t> roster_;
  double start_ = 0.0;
  double grace_ = 0.0;
  std::set<std::uint32_t> reported_missing_;  ///< roster vessels reported never heard
  std::set<std::uint32_t> reported_foreign_;  ///< vessels reported not on the roster
};

}  // namespace usvfdi::app
