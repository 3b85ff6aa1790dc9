#include "monitor_format.hpp"

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

#include "usv_fdi/core/text.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::app {

std::string json_row(const Row& r, double heard_age, double now) {
  std::ostringstream os;
  FaultEvent shown = r.ev;
  shown.message = escape_text(shown.message);
  os << "{\"type\":\"fault\",\"mmsi\":" << r.mmsi << "," << io::fault_event_fields(shown)
     << ",\"age_s\":" << io::json_number(now - r.written)
     << ",\"heard_age_s\":" << io::json_number(heard_age)
     << ",\"alive\":" << (r.alive ? "true" : "false") << "}";
  return os.str();
}

std::string inputs_line(const fdi::FdiStatus& s) {
  std::string flags = pipeline::input_flag_names(s.input_flags());
  char counts[200];
  std::snprintf(counts, sizeof counts,
                "rejected timestamps %llu, invalid values %llu, gaps %llu, reordered %llu, queue "
                "drops %llu",
                static_cast<unsigned long long>(s.rejected_timestamps()),
                static_cast<unsigned long long>(s.invalid_values()),
                static_cast<unsigned long long>(s.gaps()),
                static_cast<unsigned long long>(s.reordered()),
                static_cast<unsigned long long>(s.dropped_inputs()));
  std::string line = "inputs: " + (flags.empty() ? std::string("ok") : flags) + " (" + counts + ")";
  line +=
      s.identification_paused() == 0
          ? std::string("; identification running")
          : "; identification paused: " + pipeline::pause_reason_names(s.identification_paused());
  line += s.isolation_paused() == 0
              ? std::string("; isolation running")
              : "; isolation paused: " + pipeline::pause_reason_names(s.isolation_paused());
  return line;
}

std::string json_status(const VesselStatus& v, double heard_age, double now) {
  const fdi::FdiStatus& s = v.st;
  std::ostringstream os;
  os << "{\"type\":\"status\",\"mmsi\":" << s.mmsi() << ",\"stamp\":" << io::json_number(s.stamp())
     << ",\"a\":[" << io::json_number(s.a()[0]) << "," << io::json_number(s.a()[1]) << ","
     << io::json_number(s.a()[2]) << "," << io::json_number(s.a()[3])
     << "],\"converged\":" << (s.converged() ? "true" : "false")
     << ",\"armed\":" << (s.armed() ? "true" : "false")
     << ",\"excitation\":" << io::json_number(s.excitation())
     << ",\"surge_speed\":" << io::json_number(s.surge_speed())
     << ",\"speed_ratio\":" << io::json_number(s.speed_ratio())
     << ",\"reference_speed\":" << io::json_number(s.reference_speed()) << ",\"j_peak\":["
     << io::json_number(s.j_peak()[0]) << "," << io::json_number(s.j_peak()[1]) << "],\"j_raise\":["
     << io::json_number(s.j_raise()[0]) << "," << io::json_number(s.j_raise()[1])
     << "],\"j_leave\":[" << io::json_number(s.j_leave()[0]) << ","
     << io::json_number(s.j_leave()[1]) << "],\"c_a\":" << io::json_number(s.c_a())
     << ",\"c_g\":" << io::json_number(s.c_g())
     << ",\"model_mismatch\":" << (s.model_mismatch() ? "true" : "false")
     << ",\"ins_healthy\":" << (s.ins_healthy() ? "true" : "false")
     << ",\"rudder_healthy\":" << (s.rudder_healthy() ? "true" : "false")
     << ",\"samples\":" << s.samples() << ",\"dropped\":" << s.dropped()
     << ",\"input_flags\":" << io::json_string_array(pipeline::input_flag_names(s.input_flags()))
     << ",\"rejected_timestamps\":" << s.rejected_timestamps()
     << ",\"invalid_values\":" << s.invalid_values() << ",\"gaps\":" << s.gaps()
     << ",\"reordered\":" << s.reordered() << ",\"dropped_inputs\":" << s.dropped_inputs()
     << ",\"identification_paused\":"
     << io::json_string_array(pipeline::pause_reason_names(s.identification_paused()))
     << ",\"isolation_paused\":"
     << io::json_string_array(pipeline::pause_reason_names(s.isolation_paused()))
     << ",\"age_s\":" << io::json_number(now - v.written)
     << ",\"heard_age_s\":" << io::json_number(heard_age)
     << ",\"alive\":" << (v.alive ? "true" : "false")
     << ",\"message\":" << io::json_string(escape_text(s.message().to_string())) << "}";
  return os.str();
}

std::string heard_line(std::uint32_t mmsi, const VesselLiveness& live, bool gone, double mono) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "vessel %u%s%s: last heard %.1f s ago", mmsi,
                gone ? " (sidecar gone)" : "", live.silent(mmsi) ? " (silent)" : "",
                live.age(mmsi, mono));
  return buf;
}

std::string change_line(const VesselLiveness::Change& c, double silent_after) {
  char buf[160];
  if (c.silent) {
    std::snprintf(buf, sizeof buf, "vessel %u silent: nothing heard for %.1f s (> %g s)", c.mmsi,
                  c.age, silent_after);
  } else {
    std::snprintf(buf, sizeof buf, "vessel %u heard again after %.1f s of silence", c.mmsi, c.gap);
  }
  return buf;
}

std::string json_change(const VesselLiveness::Change& c, double silent_after) {
  std::ostringstream os;
  os << "{\"type\":\"vessel\",\"mmsi\":" << c.mmsi
     << ",\"silent\":" << (c.silent ? "true" : "false")
     << ",\"heard_age_s\":" << io::json_number(c.age);
  if (!c.silent) os << ",\"gap_s\":" << io::json_number(c.gap);
  os << ",\"silent_after_s\":" << io::json_number(silent_after) << "}";
  return os.str();
}

std::string json_conflict(const OwnerDecision& d, std::uint32_t mmsi, const char* sensor,
                          const std::string& writer, std::uint64_t seq, const std::string& state) {
  const std::string owner = d.owner.id.empty() ? std::string("nobody") : d.owner.id;
  std::ostringstream os;
  os << "{\"type\":\"conflict\",\"mmsi\":" << mmsi << ",\"sensor\":\"" << sensor
     << "\",\"verdict\":\""
     << (d.verdict == OwnerDecision::Verdict::kShown  ? "shown"
         : d.verdict == OwnerDecision::Verdict::kHeld ? "held"
                                                      : "refused")
     << "\",\"why\":" << io::json_string(to_string(d.why))
     << ",\"writer\":" << io::json_string(writer) << ",\"sequence\":" << seq
     << ",\"state\":" << io::json_string(state) << ",\"owner\":" << io::json_string(owner)
     << ",\"owner_sequence\":" << d.owner_sequence << "}";
  return os.str();
}

std::string roster_line(const RosterWatch::Change& c) {
  char buf[200];
  switch (c.state) {
    case RosterState::kNeverHeard:
      std::snprintf(buf, sizeof buf, "vessel %u (on roster): never heard (%.1f s since start)",
                    c.mmsi, c.waited);
      break;
    case RosterState::kHeard:
      std::snprintf(buf, sizeof buf, "vessel %u (on roster): heard, %.1f s after start", c.mmsi,
                    c.waited);
      break;
    default:
      std::snprintf(buf, sizeof buf, "vessel %u heard: not on roster", c.mmsi);
      break;
  }
  return buf;
}

std::string json_roster(std::uint32_t mmsi, RosterState state, double heard_age) {
  std::ostringstream os;
  os << "{\"type\":\"roster\",\"mmsi\":" << mmsi << ",\"state\":\"" << to_string(state)
     << "\",\"on_roster\":" << (state == RosterState::kNotOnRoster ? "false" : "true")
     << ",\"heard\":" << (state == RosterState::kNeverHeard ? "false" : "true")
     << ",\"heard_age_s\":" << io::json_number(heard_age) << "}";
  return os.str();
}

std::string fault_row_line(const Row& r, double now) {
  std::string state = to_string(r.ev.state);
  if (!r.alive) state += "?";  // the sidecar is gone: last known state
  char buf[1024];
  std::snprintf(buf, sizeof buf, "%-10u %-13s %-21s %-8s %5.2f %5.2f %4llu %8.2f %8.2f %7.1f  %s",
                r.mmsi, to_string(r.ev.sensor), state.c_str(), to_string(r.ev.kind), r.ev.c_a,
                r.ev.c_g, static_cast<unsigned long long>(r.ev.sequence), r.ev.onset_time, r.ev.t,
                now - r.written, escape_text(r.ev.message).c_str());
  return buf;
}

std::string format_table(const InstanceOwners<RowKey, Row>& rows,
                         const InstanceOwners<std::uint32_t, VesselStatus>* vessels,
                         const VesselLiveness& live, int conflicts, double now, double mono,
                         const TableExtras& extras) {
  std::string out;
  const auto printf = [&out](const char* fmt, auto... args) {
    char buf[1024];
    std::snprintf(buf, sizeof buf, fmt, args...);
    out += buf;
  };
  const char* mark_blank = extras.marked != nullptr ? "  " : "";
  printf("%s%-10s %-13s %-21s %-8s %5s %5s %4s %8s %8s %7s  %s\n", mark_blank, "VESSEL", "SENSOR",
         "STATE", "KIND", "C_A", "C_G", "SEQ", "ONSET[s]", "T[s]", "AGE[s]", "MESSAGE");
  bool any_gone = false;
  std::set<std::uint32_t> gone_vessels;
  rows.for_each([&](const RowKey& key, const Row& r) {
    if (!r.alive) {
      any_gone = true;
      gone_vessels.insert(r.mmsi);
    }
    const char* mark = extras.marked == nullptr ? "" : extras.marked->count(key) > 0 ? "* " : "  ";
    printf("%s%s\n", mark, fault_row_line(r, now).c_str());
  });
  printf("(%zu fault instances%s%s)\n", rows.size(),
         any_gone ? "; '?': sidecar gone, last known state" : "",
         extras.marked != nullptr ? "; '*': changed in the last seconds" : "");
  if (conflicts > 0) {
    printf("!! %d conflicting writer(s) refused or held: see the log (CONFLICT ...)\n", conflicts);
  }
  const RosterWatch* roster =
      extras.roster != nullptr && extras.roster->active() ? extras.roster : nullptr;
  if (roster != nullptr) {
    const std::vector<std::uint32_t> missing = roster->never_heard(live);
    if (!missing.empty()) {
      printf("!! %zu of %zu roster vessel(s) never heard\n", missing.size(),
             roster->roster().size());
    }
  }
  // One line per vessel heard or on the roster: how long ago; with --status also its FdiStatus.
  for (const std::uint32_t mmsi : roster != nullptr ? roster->shown(live) : live.vessels()) {
    const RosterState rs = roster != nullptr ? roster->state(mmsi, live) : RosterState::kNoRoster;
    if (rs == RosterState::kNeverHeard) {
      printf("vessel %u (on roster): never heard\n", mmsi);
      continue;
    }
    const char* tag = rs == RosterState::kNotOnRoster ? " (not on roster)" : "";
    const VesselStatus* vs = vessels != nullptr ? vessels->shown(mmsi) : nullptr;
    if (vs == nullptr) {
      printf("%s%s\n", heard_line(mmsi, live, gone_vessels.count(mmsi) > 0, mono).c_str(), tag);
      continue;
    }
    const fdi::FdiStatus& s = vs->st;
    printf(
        "%s%s; t=%.1f s, %s%s, A=[%.4g %.4g; %.4g %.4g], %llu samples, %llu "
        "dropped: %s\n",
        heard_line(mmsi, live, !vs->alive, mono).c_str(), tag, s.stamp(),
        s.converged() ? "converged" : "identifying", s.armed() ? ", armed" : "", s.a()[0], s.a()[1],
        s.a()[2], s.a()[3], static_cast<unsigned long long>(s.samples()),
        static_cast<unsigned long long>(s.dropped()), escape_text(s.message().to_string()).c_str());
    printf("  %s\n", inputs_line(s).c_str());
  }
  return out;
}

}  // namespace usvfdi::app
