#include "board.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "usv_fdi/core/text.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::app::dashboard {
namespace {

using nlohmann::json;

/// A number, or null when it is not finite (JSON has no NaN).
json num(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

}  // namespace

const char* presentation(FaultState s) {
  switch (s) {
    case FaultState::kRaised:
      return "active-unacknowledged";
    case FaultState::kActiveAcknowledged:
      return "active-acknowledged";
    case FaultState::kClearedUnacknowledged:
      return "rectified-unacknowledged";
    case FaultState::kNormal:
    case FaultState::kAcknowledged:
      break;
  }
  return "normal";
}

json row_json(const Row& r, double now) {
  const FaultEvent& e = r.ev;
  return json{{"mmsi", r.mmsi},
              {"sensor", to_string(e.sensor)},
              {"state", to_string(e.state)},
              {"presentation", presentation(e.state)},
              {"kind", to_string(e.kind)},
              {"c_a", num(e.c_a)},
              {"c_g", num(e.c_g)},
              {"statistic", num(e.statistic)},
              {"threshold", num(e.threshold)},
              {"sequence", e.sequence},
              {"incarnation", e.incarnation},
              {"t", num(e.t)},
              {"onset_time", num(e.onset_time)},
              {"detection_time", num(e.detection_time)},
              {"message", escape_text(e.message)},  // a peer's text: never raw
              {"written", num(r.written)},
              {"age_s", num(now - r.written)},
              {"alive", r.alive}};
}

json status_json(const VesselStatus& v) {
  const fdi::FdiStatus& s = v.st;
  return json{{"stamp", num(s.stamp())},
              {"a", {num(s.a()[0]), num(s.a()[1]), num(s.a()[2]), num(s.a()[3])}},
              {"converged", s.converged()},
              {"armed", s.armed()},
              {"excitation", num(s.excitation())},
              {"sigma_v", num(s.sigma_v())},
              {"sigma_r", num(s.sigma_r())},
              {"ins_healthy", s.ins_healthy()},
              {"rudder_healthy", s.rudder_healthy()},
              {"input_flags", pipeline::input_flag_names(s.input_flags())},
              {"identification_paused", pipeline::pause_reason_names(s.identification_paused())},
              {"isolation_paused", pipeline::pause_reason_names(s.isolation_paused())},
              {"samples", s.samples()},
              {"dropped", s.dropped()},
              {"message", escape_text(s.message().to_string())},
              {"surge_speed", num(s.surge_speed())},
              {"speed_ratio", num(s.speed_ratio())},
              {"written", num(v.written)},
              {"alive", v.alive}};
}

void EventHistory::add(const Row& r) {
  const RowKey key{r.mmsi, static_cast<int>(r.ev.sensor)};
  const auto it = last_sequence_.find(key);
  if (it != last_sequence_.end() && it->second == r.ev.sequence) return;
  last_sequence_[key] = r.ev.sequence;
  if (r.ev.state == FaultState::kRaised) {
    const auto last = last_state_.find(key);
    const bool same_raise = last != last_state_.end() &&
                            last->second.first == FaultState::kRaised &&
                            last->second.second == r.ev.detection_time;
    if (!same_raise) ++raises_[key];
  }
  last_state_[key] = {r.ev.state, r.ev.detection_time};
  events_.push_front(r);
  ++added_;
  while (events_.size() > capacity_) events_.pop_back();
}

/// Checks an acknowledgement request's body; false and *why (naming what is wrong) if bad.
bool parse_ack_body(const std::string& body, AckWork* out, std::string* why) {
  json j;
  try {
    j = json::parse(body);
  } catch (const json::parse_error& e) {
    *why = std::string("the body is not JSON: ") + e.what();
    return false;
  }
  if (!j.is_object()) {
    *why = "the body must be a JSON object {mmsi, sensor, sequence, operator}";
    return false;
  }
  const auto field = [&](const char* name) -> const json* {
    const auto it = j.find(name);
    return it == j.end() ? nullptr : &*it;
  };
  const json* m = field("mmsi");
  if (m == nullptr || !m->is_number_unsigned() || m->get<std::uint64_t>() == 0 ||
      m->get<std::uint64_t>() > 999999999u) {
    *why = "mmsi: an integer 1..999999999 is required";
    return false;
  }
  const json* s = field("sensor");
  if (s == nullptr || !s->is_string() || !parse_sensor(s->get<std::string>(), &out->req.sensor)) {
    *why = "sensor: accelerometer, gyro or unknown is required";
    return false;
  }
  const json* q = field("sequence");
  if (q == nullptr || !q->is_number_unsigned() || q->get<std::uint64_t>() == 0) {
    *why = "sequence: an integer >= 1 is required (the event's sequence shown on the board)";
    return false;
  }
  const json* o = field("operator");
  if (o == nullptr || !o->is_string() || o->get<std::string>().empty() ||
      o->get<std::string>().size() > 63) {
    *why = "operator: the operator's name (1 to 63 characters) is required";
    return false;
  }
  for (const char c : o->get<std::string>()) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      *why = "operator: control characters are not allowed";
      return false;
    }
  }
  out->req.mmsi = static_cast<std::uint32_t>(m->get<std::uint64_t>());
  out->req.sequence = q->get<std::uint64_t>();
  out->operator_id = o->get<std::string>();
  return true;
}

json EventHistory::to_json(double now) const { return newest_json(events_.size(), now); }

json EventHistory::newest_json(std::size_t n, double now) const {
  json out = json::array();
  for (std::size_t i = 0; i < n && i < events_.size(); ++i)
    out.push_back(row_json(events_[i], now));
  return out;
}

std::set<std::uint32_t> board_vessels(const BoardInput& in) {
  std::set<std::uint32_t> mmsis;
  for (const auto& [key, row] : in.rows) mmsis.insert(key.first);
  for (const auto& [m, st] : in.statuses) mmsis.insert(m);
  for (const auto& [m, age] : in.heard_age) mmsis.insert(m);
  for (const std::uint32_t m : in.roster_never_heard) mmsis.insert(m);
  return mmsis;
}

namespace {

/// Every vessel's entry on the board, by MMSI (rows grouped in one pass, not per vessel).
std::vector<std::pair<std::uint32_t, json>> vessel_entries(const BoardInput& in, double now) {
  std::map<std::uint32_t, json> sensors;
  for (const auto& [key, row] : in.rows) {
    sensors[key.first][to_string(row.ev.sensor)] = row_json(row, now);
  }
  const std::set<std::uint32_t> never(in.roster_never_heard.begin(), in.roster_never_heard.end());
  std::vector<std::pair<std::uint32_t, json>> out;
  for (const std::uint32_t m : board_vessels(in)) {
    json v{{"mmsi", m}};
    const auto se = sensors.find(m);
    v["sensors"] = se == sensors.end() ? json::object() : std::move(se->second);
    const auto st = in.statuses.find(m);
    v["status"] = st == in.statuses.end() ? json(nullptr) : status_json(st->second);
    const auto age = in.heard_age.find(m);
    v["heard_age_s"] = age == in.heard_age.end() ? json(nullptr) : num(age->second);
    const auto sil = in.silent.find(m);
    v["silent"] = sil != in.silent.end() && sil->second;
    v["never_heard"] = never.count(m) > 0;
    out.emplace_back(m, std::move(v));
  }
  return out;
}

json ack_list_json(const std::deque<AckOutcome>& acks) {
  json out = json::array();
  for (const AckOutcome& a : acks) {
    out.push_back(json{{"mmsi", a.mmsi},
                       {"sensor", to_string(a.sensor)},
                       {"sequence", a.sequence},
                       {"operator", a.operator_id},
                       {"sent", num(a.sent)},
                       {"state", a.state},
                       {"reason", a.reason}});
  }
  return out;
}

std::string dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

/// What every board and every delta carries beside its vessels and events.
json board_fields(const BoardInput& in, double now, const std::deque<AckOutcome>& acks) {
  return json{{"now", num(now)},
              {"silent_after", num(in.silent_after)},
              {"conflicts", in.conflicts},
              {"acks", ack_list_json(acks)}};
}

}  // namespace

json board_json(const BoardInput& in, const EventHistory& events,
                const std::deque<AckOutcome>& acks, double now) {
  json vessels = json::array();
  for (auto& [m, v] : vessel_entries(in, now)) vessels.push_back(std::move(v));
  json board = board_fields(in, now, acks);
  board["vessels"] = std::move(vessels);
  board["events"] = events.to_json(now);
  return board;
}

BoardFrame BoardFramer::frame(const BoardInput& in, const EventHistory& events,
                              const std::deque<AckOutcome>& acks, double now, bool can_ack) {
  json vessels = json::array(), changed = json::array(), removed = json::array();
  json ages = json::object();
  std::map<std::uint32_t, std::string> keys;
  for (auto& [m, v] : vessel_entries(in, now)) {
    // what the entry says besides its ages, which move on with every board
    json bare = v;
    bare.erase("heard_age_s");
    for (auto& [sensor, row] : bare["sensors"].items()) row.erase("age_s");
    std::string key = dump(bare);
    const auto was = keys_.find(m);
    if (was == keys_.end() || was->second != key) changed.push_back(v);
    keys.emplace(m, std::move(key));
    const auto age = in.heard_age.find(m);
    if (age != in.heard_age.end()) ages[std::to_string(m)] = num(age->second);
    vessels.push_back(std::move(v));
  }
  for (const auto& [m, key] : keys_) {
    if (keys.count(m) == 0) removed.push_back(m);
  }
  keys_.swap(keys);
  const std::uint64_t added = events.added();
  const std::size_t fresh =
      static_cast<std::size_t>(std::min<std::uint64_t>(added - events_framed_, events.size()));
  events_framed_ = added;
  json full = board_fields(in, now, acks);
  full["can_ack"] = can_ack;
  json delta = full;
  full["vessels"] = std::move(vessels);
  full["events"] = events.to_json(now);
  delta["delta"] = true;
  delta["vessels"] = std::move(changed);
  delta["removed"] = std::move(removed);
  delta["events"] = events.newest_json(fresh, now);
  delta["event_capacity"] = events.capacity();
  delta["heard_age"] = std::move(ages);
  return BoardFrame{dump(full), dump(delta)};
}

bool acknowledged_by(const std::string& message, const std::string& operator_id) {
  static const std::string kBy = "acknowledged by ";
  if (message.rfind(kBy, 0) != 0 || operator_id.empty()) return false;
  const std::string who = message.substr(kBy.size());
  if (who == operator_id) return true;
  // <CN>:<operator>, the CN without ':' (the sidecar writes the CN alone when it equals the name)
  const std::size_t colon = who.find(':');
  return colon != std::string::npos && colon > 0 && who.substr(colon + 1) == operator_id;
}

}  // namespace usvfdi::app::dashboard
