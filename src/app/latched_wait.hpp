// When `monitor --once` has the latched state (issue 12, section 3). Fast DDS 2.9 has no working
// wait_for_historical_data(), so the monitor decides from what it can see: the writers matched
// on its FaultEvent and FdiStatus readers (with when each was matched), which FdiStatus writers
// have delivered a sample, and (with a roster) which vessels have been heard. Pure logic on a
// caller-supplied monotonic clock (seconds), no DDS: the fleet view feeds it.
//
// The latched state is taken as complete when
//  1. discovery has settled: no writer newly matched for kDiscoveryQuiet, and at least one
//     writer matched (with a roster: every roster vessel heard instead);
//  2. every matched FdiStatus writer has delivered a sample (sidecars publish their status
//     periodically, TRANSIENT_LOCAL: a matched one delivers within one period);
//  3. every matched FaultEvent writer has been matched for kEventSettle: a sidecar without any
//     fault has nothing to deliver, and its historical samples follow the match within a few of
//     its heartbeat periods (100 ms).
// The caller bounds the wait (--duration) and reports what pending() names.
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace usvfdi::app {

class LatchedStateWait {
 public:
  /// No writer newly matched for this long: discovery has settled [s].
  static constexpr double kDiscoveryQuiet = 0.5;
  /// A matched FaultEvent writer has delivered its latched samples after this long: five of the
  /// writers' heartbeat periods (100 ms in config/qos/usv_fdi_profiles.xml) [s].
  static constexpr double kEventSettle = 0.5;

  enum class Topic { kFaultEvent, kStatus };

  /// A writer matched (or matched again) at `now`.
  void matched(Topic t, const std::string& writer, double now) {
    auto& m = t == Topic::kFaultEvent ? events_ : statuses_;
    m[writer] = now;
    last_match_ = now;
    any_match_ = true;
  }
  /// A writer is no longer matched (it left): nothing more to wait for from it.
  void unmatched(Topic t, const std::string& writer) {
    (t == Topic::kFaultEvent ? events_ : statuses_).erase(writer);
  }
  /// An FdiStatus writer delivered a sample.
  void status_sample(const std::string& writer) { status_heard_.insert(writer); }

  /// True once the latched state is complete (see the file comment). `roster_unheard`: the roster
  /// vessels not heard yet (with a roster); `with_roster`: a roster was given.
  bool complete(double now, bool with_roster,
                const std::vector<std::uint32_t>& roster_unheard) const {
    return pending(now, with_roster, roster_unheard).empty();
  }

  /// What is still awaited, one short text each ("" none): for the final warning.
  std::vector<std::string> pending(double now, bool with_roster,
                                   const std::vector<std::uint32_t>& roster_unheard) const {
    std::vector<std::string> out;
    if (with_roster) {
      for (const std::uint32_t m : roster_unheard) {
        out.push_back("roster vessel " + std::to_string(m) + " not heard");
      }
    } else if (events_.empty() && statuses_.empty()) {
      out.push_back("no sidecar's writer matched");
    }
    if (any_match_ && now - last_match_ < kDiscoveryQuiet) {
      out.push_back("discovery not settled (a writer matched " + seconds(now - last_match_) +
                    " ago)");
    }
    for (const auto& [w, at] : statuses_) {
      if (!status_heard_.count(w)) {
        out.push_back("FdiStatus writer " + w + " (matched " + seconds(now - at) +
                      " ago) has delivered no sample");
      }
    }
    for (const auto& [w, at] : events_) {
      if (now - at < kEventSettle) {
        out.push_back("FaultEvent writer " + w + " matched only " + seconds(now - at) + " ago");
      }
    }
    return out;
  }

  std::size_t matched_writers() const { return events_.size() + statuses_.size(); }

 private:
  static std::string seconds(double s) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f s", s);
    return buf;
  }

  std::map<std::string, double> events_, statuses_;  ///< matched writer -> when [s]
  std::set<std::string> status_heard_;               ///< status writers that delivered a sample
  double last_match_ = 0.0;                          ///< the latest new match [s]
  bool any_match_ = false;                           ///< a writer has matched
};

}  // namespace usvfdi::app
