#include "board.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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

/// Compact JSON text; invalid UTF-8 replaced, never thrown on.
std::string dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

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
              {"model_mismatch", s.model_mismatch()},
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

/// One vessel's entry on the board without its ages (heard_age_s, the sensors' age_s).
json bare_entry(std::uint32_t m, const BoardInput& in, bool silent, bool never_heard) {
  json sensors = json::object();
  for (auto it = in.rows.lower_bound(RowKey{m, std::numeric_limits<int>::min()});
       it != in.rows.end() && it->first.first == m; ++it) {
    json r = row_json(it->second, 0.0);
    r.erase("age_s");
    sensors[to_string(it->second.ev.sensor)] = std::move(r);
  }
  json v{{"mmsi", m}, {"sensors", std::move(sensors)}};
  const auto st = in.statuses.find(m);
  v["status"] = st == in.statuses.end() ? json(nullptr) : status_json(st->second);
  v["silent"] = silent;
  v["never_heard"] = never_heard;
  return v;
}

/// An entry with its ages at `now`: the vessel's heard age, each sensor's now - written.
json with_ages(json v, const BoardInput& in, double now) {
  const auto age = in.heard_age.find(v["mmsi"].get<std::uint32_t>());
  v["heard_age_s"] = age == in.heard_age.end() ? json(nullptr) : num(age->second);
  for (auto& [sensor, r] : v["sensors"].items()) {
    const json& w = r["written"];
    r["age_s"] = w.is_number() ? num(now - w.get<double>()) : json(nullptr);
  }
  return v;
}

/// The fields of a vessel's status that move with every status it sends (once a second): a
/// delta sends them apart from the entry, so that a status changes no entry unless it changes
/// what the board says.
constexpr const char* kStatusNumbers[] = {"stamp",       "a",       "excitation", "sigma_v",
                                          "sigma_r",     "samples", "dropped",    "surge_speed",
                                          "speed_ratio", "written"};

/// An entry's key: the entry without its status numbers, dumped.
std::string entry_key(json bare) {
  json& st = bare["status"];
  if (st.is_object()) {
    for (const char* f : kStatusNumbers) st.erase(f);
  }
  return dump(bare);
}

json status_numbers(const json& status) {
  json n = json::object();
  for (const char* f : kStatusNumbers) {
    const auto it = status.find(f);
    if (it != status.end()) n[f] = *it;
  }
  return n;
}

bool is_silent(const BoardInput& in, std::uint32_t m) {
  const auto sil = in.silent.find(m);
  return sil != in.silent.end() && sil->second;
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
  const std::set<std::uint32_t> never(in.roster_never_heard.begin(), in.roster_never_heard.end());
  json vessels = json::array();
  for (const std::uint32_t m : board_vessels(in)) {
    vessels.push_back(with_ages(bare_entry(m, in, is_silent(in, m), never.count(m) > 0), in, now));
  }
  json board = board_fields(in, now, acks);
  board["vessels"] = std::move(vessels);
  board["events"] = events.to_json(now);
  return board;
}

std::string BoardFramer::delta(const BoardInput& in, const std::set<std::uint32_t>* touched,
                               const EventHistory& events, const std::deque<AckOutcome>& acks,
                               double now, bool can_ack) {
  const std::set<std::uint32_t> vessels = board_vessels(in);
  const std::set<std::uint32_t> never(in.roster_never_heard.begin(), in.roster_never_heard.end());
  json changed = json::array(), removed = json::array(), ages = json::object();
  json numbers = json::object();
  rebuilt_ = 0;
  for (const std::uint32_t m : vessels) {
    const bool silent = is_silent(in, m), never_heard = never.count(m) > 0;
    auto it = entries_.find(m);
    const bool stale = it == entries_.end() || touched == nullptr || touched->count(m) > 0 ||
                       it->second.silent != silent || it->second.never_heard != never_heard;
    if (stale) {
      ++rebuilt_;
      json bare = bare_entry(m, in, silent, never_heard);
      std::string key = entry_key(bare);
      // (what the entry says besides its ages, which move on with every board, and its
      // status's numbers, which move on with every status)
      if (it == entries_.end() || it->second.key != key) {
        changed.push_back(with_ages(bare, in, now));
        entries_[m] = Entry{std::move(bare), std::move(key), silent, never_heard};
      } else if (bare["status"] != it->second.bare["status"]) {
        numbers[std::to_string(m)] = status_numbers(bare["status"]);
        it->second.bare["status"] = std::move(bare["status"]);
      }
    }
    const auto age = in.heard_age.find(m);
    if (age != in.heard_age.end()) ages[std::to_string(m)] = num(age->second);
  }
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (vessels.count(it->first) > 0) {
      ++it;
      continue;
    }
    removed.push_back(it->first);
    it = entries_.erase(it);
  }
  const std::uint64_t added = events.added();
  const std::size_t fresh =
      static_cast<std::size_t>(std::min<std::uint64_t>(added - events_framed_, events.size()));
  events_framed_ = added;
  json delta = board_fields(in, now, acks);
  delta["can_ack"] = can_ack;
  delta["delta"] = true;
  delta["revision"] = ++revision_;
  delta["vessels"] = std::move(changed);
  delta["removed"] = std::move(removed);
  delta["events"] = events.newest_json(fresh, now);
  delta["event_capacity"] = events.capacity();
  delta["heard_age"] = std::move(ages);
  delta["status_numbers"] = std::move(numbers);
  return dump(delta);
}

std::string BoardFramer::full(const BoardInput& in, const EventHistory& events,
                              const std::deque<AckOutcome>& acks, double now, bool can_ack) const {
  json vessels = json::array();
  for (const auto& [m, e] : entries_) vessels.push_back(with_ages(e.bare, in, now));
  json board = board_fields(in, now, acks);
  board["can_ack"] = can_ack;
  board["revision"] = revision_;
  board["vessels"] = std::move(vessels);
  board["events"] = events.to_json(now);
  return dump(board);
}

BoardFrame BoardFramer::frame(const BoardInput& in, const EventHistory& events,
                              const std::deque<AckOutcome>& acks, double now, bool can_ack) {
  BoardFrame f;
  f.delta = delta(in, nullptr, events, acks, now, can_ack);
  f.full = full(in, events, acks, now, can_ack);
  return f;
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
