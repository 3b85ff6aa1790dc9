// The dashboard's picture of the fleet, as JSON for the browser: the fleet board (one entry per
// vessel, each sensor's latched state in the IEC 62923 presentation), the event list (newest
// first) and the acknowledgements the dashboard sent. Pure functions of the monitor's model
// (Row, VesselStatus, VesselLiveness): no DDS, no HTTP.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../ack_protocol.hpp"
#include "../monitor_model.hpp"
#include "../vessel_liveness.hpp"

namespace usvfdi::app::dashboard {

/// IEC 62923-1 alert state of a latched instance: active-unacknowledged (raised),
/// active-acknowledged, rectified-unacknowledged (cleared, not acknowledged), normal.
const char* presentation(FaultState s);

/// One fault instance as the browser shows it. `now`: wall clock [s since epoch].
nlohmann::json row_json(const Row& r, double now);
/// One vessel's detector status (FdiStatus) as the browser shows it.
nlohmann::json status_json(const VesselStatus& v);

/// Every event the dashboard received (each FaultEvent shown), newest first, at most `capacity`.
class EventHistory {
 public:
  explicit EventHistory(std::size_t capacity = 1000) : capacity_(capacity) {}
  /// Records an event unless the same (vessel, sensor, sequence) was recorded last for that
  /// instance (a late joiner's copy of the latched state, or a writer's repeat).
  void add(const Row& r);
  nlohmann::json to_json(double now) const;
  /// The `n` newest events (at most size()), newest first.
  nlohmann::json newest_json(std::size_t n, double now) const;
  std::size_t size() const { return events_.size(); }
  std::size_t capacity() const { return capacity_; }
  /// Events recorded since the start (the oldest leave the history at capacity).
  std::uint64_t added() const { return added_; }
  /// Raises recorded per instance (vessel, sensor), since the start (not bounded by capacity):
  /// an event in the raised state after one in another state, or with another detection time
  /// (a raise whose clearing was not seen); a refined kind (the same raise republished with
  /// the next sequence) is none, as in the sidecar's own count.
  const std::map<RowKey, std::uint64_t>& raises() const { return raises_; }

 private:
  std::size_t capacity_;
  std::uint64_t added_ = 0;
  std::deque<Row> events_;
  std::map<RowKey, std::uint64_t> last_sequence_;
  std::map<RowKey, std::uint64_t> raises_;
  std::map<RowKey, std::pair<FaultState, double>> last_state_;  ///< state, detection time
};

/// An acknowledgement asked for by a browser.
struct AckWork {
  AckRequest req;
  std::string operator_id;
};

/// Checks a POST /api/ack body {mmsi, sensor, sequence, operator}; false and *why (naming the
/// field that is wrong) if it is not one.
bool parse_ack_body(const std::string& body, AckWork* out, std::string* why);

/// True if an event's message is the sidecar's record of an acknowledgement by `operator_id`:
/// "acknowledged by <operator>", or under DDS Security "acknowledged by <CN>:<operator>" (the
/// sidecar names the writer's authenticated identity, then the name it claimed; both escaped).
bool acknowledged_by(const std::string& message, const std::string& operator_id);

/// What became of an acknowledgement sent from the dashboard.
struct AckOutcome {
  std::uint32_t mmsi = 0;
  Sensor sensor = Sensor::kUnknown;
  std::uint64_t sequence = 0;
  std::string operator_id;
  double sent = 0.0;   ///< wall clock [s since epoch]
  std::string state;   ///< "pending", "accepted", "refused" or "unconfirmed"
  std::string reason;  ///< why it was refused ("" otherwise)
};

/// The whole board: vessels (those heard, those with a latched instance and those of the
/// roster), each with its sensors' rows, status and liveness; the events; the acknowledgements.
struct BoardInput {
  std::map<RowKey, Row> rows;
  std::map<std::uint32_t, VesselStatus> statuses;
  std::map<std::uint32_t, double> heard_age;  ///< seconds since last heard
  std::map<std::uint32_t, bool> silent;
  std::vector<std::uint32_t> roster_never_heard;
  double silent_after = 5.0;
  int conflicts = 0;
};
/// The vessels on the board: heard, with a latched instance or on the roster, by MMSI.
std::set<std::uint32_t> board_vessels(const BoardInput& in);
nlohmann::json board_json(const BoardInput& in, const EventHistory& events,
                          const std::deque<AckOutcome>& acks, double now);

/// One board for the live pages: whole, and as the change from the board framed before it.
struct BoardFrame {
  std::string full;  ///< board_json plus can_ack (GET /api/board; a page's first message)
  /// {"delta": true, ...}: what turns the previous full board into this one: the vessels whose
  /// entry changed other than in its ages (whole), the MMSIs gone ("removed"), the events added
  /// since (newest first; "event_capacity": how many the history keeps), every vessel's heard
  /// age ("heard_age", by MMSI), and now, silent_after, conflicts, acks and can_ack as in the
  /// full board; "status_numbers" (by MMSI): the numbers of the statuses that changed nothing
  /// else of their vessel's entry (stamp, a, excitation, sigma_v, sigma_r, samples, dropped,
  /// surge_speed, speed_ratio, written), to be set into that entry's status. A sensor's age_s
  /// is now - written.
  ///
  /// Both carry "revision": the number of the delta (1, 2, ...; the whole board: that of the
  /// last delta), so that a page knows when a delta is missing, and a board can be compared
  /// with a page's at the same revision.
  std::string delta;
};

/// Frames successive boards. Keeps each vessel's entry (without its ages) between frames and
/// rebuilds only those whose rows or status changed, or whose liveness words (silent, never
/// heard) did: at 1000 vessels a change touches a few, and every entry rebuilt, dumped and
/// compared on every change (5 times a second) held an arriving event 20-40 ms. The whole board
/// (~500 kB) is built only when asked for (a page that joins, GET /api/board).
class BoardFramer {
 public:
  /// The delta since the previous one (BoardFrame::delta). `touched`: the vessels whose rows or
  /// status changed since then; nullptr: any may have (every entry rebuilt and compared).
  std::string delta(const BoardInput& in, const std::set<std::uint32_t>* touched,
                    const EventHistory& events, const std::deque<AckOutcome>& acks, double now,
                    bool can_ack);
  /// The whole board as of the last delta (BoardFrame::full), its ages at `now`.
  std::string full(const BoardInput& in, const EventHistory& events,
                   const std::deque<AckOutcome>& acks, double now, bool can_ack) const;
  /// Both, every vessel compared.
  BoardFrame frame(const BoardInput& in, const EventHistory& events,
                   const std::deque<AckOutcome>& acks, double now, bool can_ack);
  /// Entries rebuilt by the last delta (a measure of its work).
  std::size_t rebuilt() const { return rebuilt_; }
  /// The last delta's revision (0 before the first).
  std::uint64_t revision() const { return revision_; }

 private:
  struct Entry {
    nlohmann::json bare;  ///< the vessel's entry without heard_age_s and the sensors' age_s
    std::string key;      ///< bare, dumped: what a page is sent again when it changes
    bool silent = false, never_heard = false;
  };
  std::map<std::uint32_t, Entry> entries_;
  std::uint64_t events_framed_ = 0;  ///< EventHistory::added() at the last delta
  std::size_t rebuilt_ = 0;
  std::uint64_t revision_ = 0;
};

}  // namespace usvfdi::app::dashboard
