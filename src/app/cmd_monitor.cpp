// usv-fdi monitor: the shore-side subscriber. Late-join aware: its FaultEvent reader is
// RELIABLE + TRANSIENT_LOCAL, KEEP_LAST 1 per instance, sized for a fleet (4096 instances),
// so on start it receives the latched state of every fault instance of every vessel.
// With --ack it acknowledges an event and waits for the sidecar's confirmation.
// It always reads FdiStatus too (printed with --status): every sample of a vessel updates its
// "last heard" time, and a vessel not heard for --silent-after s is flagged silent on a timer.
#include <spdlog/spdlog.h>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "credentials.hpp"
#include "dds_options.hpp"
#include "instance_owners.hpp"
#include "usv_fdi/core/text.hpp"
#include "usv_fdi/dds_service/convert.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "vessel_liveness.hpp"

namespace usvfdi::app {
namespace {

namespace dds = usv_fdi::dds;
namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

struct MonitorArgs {
  DdsCli dds;
  std::vector<std::uint32_t> mmsi;  ///< filter (empty: every vessel)
  bool json = false;
  bool status = false;            ///< also show each vessel's FdiStatus
  std::vector<std::string> acks;  ///< MMSI:SENSOR:SEQUENCE
  std::string operator_id = "operator";
  double ack_timeout = 5.0;         ///< wait for the sidecar's confirmation of an ack [s]
  double discovery_timeout = 10.0;  ///< wait for a sidecar's ack reader [s]
  double duration = 0.0;            ///< stop after this long (0: until a signal)
  bool once = false;          ///< print the latched state after --duration (default 3 s) and exit
  int expect = 0;             ///< stop once this many instances are known
  double silent_after = 5.0;  ///< flag a vessel not heard for longer than this [s]
};

/// Wall-clock seconds since the epoch (the writer's source timestamps are on this clock).
double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// Monotonic seconds: the local receive times of "last heard".
double mono_now() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

struct Row {
  std::uint32_t mmsi = 0;
  FaultEvent ev;
  double written = 0.0;           ///< the sidecar's write time (source timestamp) [s since epoch]
  bool alive = true;              ///< false: the sidecar that published it is gone
  fdds::InstanceHandle_t writer;  ///< the sidecar's FaultEvent writer
};
using RowKey = std::pair<std::uint32_t, int>;

struct VesselStatus {
  fdi::FdiStatus st;
  double written = 0.0;
  bool alive = true;
  fdds::InstanceHandle_t writer;
};

std::string json_row(const Row& r, double heard_age) {
  std::ostringstream os;
  const FaultEvent& e = r.ev;
  os << "{\"type\":\"fault\",\"mmsi\":" << r.mmsi << ",\"sensor\":\"" << to_string(e.sensor)
     << "\",\"state\":\"" << to_string(e.state) << "\",\"kind\":\"" << to_string(e.kind)
     << "\",\"c_a\":" << io::json_number(e.c_a) << ",\"c_g\":" << io::json_number(e.c_g)
     << ",\"statistic\":" << io::json_number(e.statistic)
     << ",\"threshold\":" << io::json_number(e.threshold)
     << ",\"onset_time\":" << io::json_number(e.onset_time)
     << ",\"detection_time\":" << io::json_number(e.detection_time)
     << ",\"stamp\":" << io::json_number(e.t) << ",\"sequence\":" << e.sequence << ",\"a\":["
     << io::json_number(e.A(0, 0)) << "," << io::json_number(e.A(0, 1)) << ","
     << io::json_number(e.A(1, 0)) << "," << io::json_number(e.A(1, 1))
     << "],\"age_s\":" << io::json_number(wall_now() - r.written)
     << ",\"heard_age_s\":" << io::json_number(heard_age)
     << ",\"alive\":" << (r.alive ? "true" : "false")
     << ",\"message\":" << io::json_string(e.message) << "}";
  return os.str();
}

/// One line on the inputs of a vessel: problems, counters, pauses.
std::string inputs_line(const fdi::FdiStatus& s) {
  std::string flags = input_flag_names(s.input_flags());
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
  line += s.identification_paused() == 0
              ? std::string("; identification running")
              : "; identification paused: " + pause_reason_names(s.identification_paused());
  line += s.isolation_paused() == 0
              ? std::string("; isolation running")
              : "; isolation paused: " + pause_reason_names(s.isolation_paused());
  return line;
}

std::string json_status(const VesselStatus& v, double heard_age) {
  const fdi::FdiStatus& s = v.st;
  std::ostringstream os;
  os << "{\"type\":\"status\",\"mmsi\":" << s.mmsi() << ",\"stamp\":" << io::json_number(s.stamp())
     << ",\"a\":[" << io::json_number(s.a()[0]) << "," << io::json_number(s.a()[1]) << ","
     << io::json_number(s.a()[2]) << "," << io::json_number(s.a()[3])
     << "],\"converged\":" << (s.converged() ? "true" : "false")
     << ",\"armed\":" << (s.armed() ? "true" : "false")
     << ",\"excitation\":" << io::json_number(s.excitation())
     << ",\"ins_healthy\":" << (s.ins_healthy() ? "true" : "false")
     << ",\"rudder_healthy\":" << (s.rudder_healthy() ? "true" : "false")
     << ",\"samples\":" << s.samples() << ",\"dropped\":" << s.dropped()
     << ",\"input_flags\":" << io::json_string_array(input_flag_names(s.input_flags()))
     << ",\"rejected_timestamps\":" << s.rejected_timestamps()
     << ",\"invalid_values\":" << s.invalid_values() << ",\"gaps\":" << s.gaps()
     << ",\"reordered\":" << s.reordered() << ",\"dropped_inputs\":" << s.dropped_inputs()
     << ",\"identification_paused\":"
     << io::json_string_array(pause_reason_names(s.identification_paused()))
     << ",\"isolation_paused\":" << io::json_string_array(pause_reason_names(s.isolation_paused()))
     << ",\"age_s\":" << io::json_number(wall_now() - v.written)
     << ",\"heard_age_s\":" << io::json_number(heard_age)
     << ",\"alive\":" << (v.alive ? "true" : "false")
     << ",\"message\":" << io::json_string(escape_text(s.message().to_string())) << "}";
  return os.str();
}

/// "vessel 257000001 (silent): last heard 7.2 s ago" (the start of a vessel's line).
std::string heard_line(std::uint32_t mmsi, const VesselLiveness& live, bool gone) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "vessel %u%s%s: last heard %.1f s ago", mmsi,
                gone ? " (sidecar gone)" : "", live.silent(mmsi) ? " (silent)" : "",
                live.age(mmsi, mono_now()));
  return buf;
}

/// The line printed once when a vessel goes silent or is heard again.
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

void print_table(const InstanceOwners<RowKey, Row>& rows,
                 const InstanceOwners<std::uint32_t, VesselStatus>* vessels,
                 const VesselLiveness& live, int conflicts) {
  const double now = wall_now();
  std::printf("%-10s %-13s %-21s %-8s %5s %5s %4s %8s %8s %7s  %s\n", "VESSEL", "SENSOR", "STATE",
              "KIND", "C_A", "C_G", "SEQ", "ONSET[s]", "T[s]", "AGE[s]", "MESSAGE");
  bool any_gone = false;
  std::set<std::uint32_t> gone_vessels;
  rows.for_each([&](const RowKey&, const Row& r) {
    std::string state = to_string(r.ev.state);
    if (!r.alive) {
      state += "?";  // the sidecar is gone: last known state
      any_gone = true;
      gone_vessels.insert(r.mmsi);
    }
    std::printf("%-10u %-13s %-21s %-8s %5.2f %5.2f %4llu %8.2f %8.2f %7.1f  %s\n", r.mmsi,
                to_string(r.ev.sensor), state.c_str(), to_string(r.ev.kind), r.ev.c_a, r.ev.c_g,
                static_cast<unsigned long long>(r.ev.sequence), r.ev.onset_time, r.ev.t,
                now - r.written, r.ev.message.c_str());
  });
  std::printf("(%zu fault instances%s)\n", rows.size(),
              any_gone ? "; '?': sidecar gone, last known state" : "");
  if (conflicts > 0) {
    std::printf("!! %d conflicting writer(s) refused or held: see the log (CONFLICT ...)\n",
                conflicts);
  }
  // One line per vessel heard: how long ago; with --status also its FdiStatus.
  for (const std::uint32_t mmsi : live.vessels()) {
    const VesselStatus* vs = vessels != nullptr ? vessels->shown(mmsi) : nullptr;
    if (vs == nullptr) {
      std::printf("%s\n", heard_line(mmsi, live, gone_vessels.count(mmsi) > 0).c_str());
      continue;
    }
    const fdi::FdiStatus& s = vs->st;
    std::printf(
        "%s; t=%.1f s, %s%s, A=[%.4g %.4g; %.4g %.4g], %llu samples, %llu "
        "dropped: %s\n",
        heard_line(mmsi, live, !vs->alive).c_str(), s.stamp(),
        s.converged() ? "converged" : "identifying", s.armed() ? ", armed" : "", s.a()[0], s.a()[1],
        s.a()[2], s.a()[3], static_cast<unsigned long long>(s.samples()),
        static_cast<unsigned long long>(s.dropped()), escape_text(s.message().to_string()).c_str());
    std::printf("  %s\n", inputs_line(s).c_str());
  }
  std::fflush(stdout);
}

bool parse_ack(const std::string& spec, fdi::FaultAck* out, std::string* why) {
  std::stringstream ss(spec);
  std::string m, s, q;
  if (!std::getline(ss, m, ':') || !std::getline(ss, s, ':') || !std::getline(ss, q) || m.empty() ||
      q.empty()) {
    *why = "--ack " + spec + ": expected MMSI:SENSOR:SEQUENCE (e.g. 257000001:gyro:3)";
    return false;
  }
  Sensor sensor;
  if (!parse_sensor(s, &sensor)) {
    *why = "--ack " + spec + ": sensor '" + s + "' is not accelerometer, gyro or unknown";
    return false;
  }
  try {
    std::size_t pm = 0, pq = 0;
    const unsigned long mmsi = std::stoul(m, &pm);
    const unsigned long long seq = std::stoull(q, &pq);
    if (pm != m.size() || pq != q.size() || mmsi == 0 || mmsi > 999999999ul || seq == 0) {
      throw std::invalid_argument(spec);
    }
    out->mmsi(static_cast<std::uint32_t>(mmsi));
    out->sensor(static_cast<std::uint8_t>(sensor));
    out->sequence(seq);
  } catch (const std::exception&) {
    *why = "--ack " + spec + ": MMSI (1..999999999) and SEQUENCE (>= 1) must be integers";
    return false;
  }
  return true;
}

/// Records the writers (sidecars) that went away: Fast DDS 2.9 neither delivers an
/// instance-state sample when a writer disappears nor implements get_matched_publications(),
/// so the monitor learns it from on_subscription_matched. Only copies a handle under a lock.
class GoneWriters : public fdds::DataReaderListener {
 public:
  void on_subscription_matched(fdds::DataReader*,
                               const fdds::SubscriptionMatchedStatus& info) override {
    std::lock_guard<std::mutex> lock(m_);
    if (info.current_count_change < 0) {
      gone_.push_back(info.last_publication_handle);
    } else if (info.current_count_change > 0) {
      back_.push_back(info.last_publication_handle);
    }
  }
  /// Moves the handles of writers gone (and come back) since the last call into the outputs.
  void take(std::vector<fdds::InstanceHandle_t>* gone, std::vector<fdds::InstanceHandle_t>* back) {
    std::lock_guard<std::mutex> lock(m_);
    gone->swap(gone_);
    back->swap(back_);
    gone_.clear();
    back_.clear();
  }

 private:
  std::mutex m_;
  std::vector<fdds::InstanceHandle_t> gone_, back_;
};

/// The text naming a writer in a conflict report: its GUID, its identity's CN and its partitions.
std::string writer_name(const dds::DdsContext& ctx, const fdds::InstanceHandle_t& h) {
  std::ostringstream os;
  os << eprosima::fastrtps::rtps::iHandle2GUID(h);
  const auto w = ctx.peers().writer(h);
  if (w) {
    const std::string cn = dds::common_name(w->subject);
    if (!cn.empty()) os << " (identity " << cn << ")";
    std::string parts;
    for (const auto& p : w->partitions) parts += (parts.empty() ? "" : ",") + p;
    os << " [partition " << (parts.empty() ? std::string("<default>") : parts) << "]";
  }
  return escape_text(os.str());  // names and partitions come from the peer
}

/// The FaultEvent and FdiStatus side of the monitor. The FdiStatus reader exists even without
/// --status: the periodic status is what tells a quiet vessel from a silent one. Every sample
/// passes InstanceOwners: only the writer that owns an instance updates it.
class FleetView {
 public:
  FleetView(dds::DdsContext& ctx, const MonitorArgs& a)
      : ctx_(ctx),
        a_(a),
        secure_(ctx.secure()),
        filter_(a.mmsi.begin(), a.mmsi.end()),
        live_(a.silent_after) {
    events_ = &ctx.create_reader(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventReader,
                                 &events_gone_, fdds::StatusMask::subscription_matched());
    events_->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    ws_.attach_condition(events_->get_statuscondition());
    status_ = &ctx.create_reader(dds::TopicId::kStatus, dds::profiles::kStatusReader, &status_gone_,
                                 fdds::StatusMask::subscription_matched());
    status_->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    ws_.attach_condition(status_->get_statuscondition());
  }
  ~FleetView() {
    // The readers go before their listeners (a failure is logged by Fast DDS).
    try {
      if (status_ != nullptr) ctx_.delete_reader(*status_);
      ctx_.delete_reader(*events_);
    } catch (const std::exception& e) {
      spdlog::warn("{}", e.what());
    }
  }
  FleetView(const FleetView&) = delete;
  FleetView& operator=(const FleetView&) = delete;

  /// Waits up to `timeout` for data; applies what arrived, then flags the vessels that have
  /// gone silent. Returns true if a row, a vessel status or a vessel's silence changed.
  bool poll(double timeout) {
    fdds::ConditionSeq active;
    ws_.wait(active, eprosima::fastrtps::Duration_t(timeout));
    bool changed = mark_gone_writers();
    fdi::FaultEvent d;
    fdds::SampleInfo info;
    while (events_->take_next_sample(&d, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) {
        // Disposed / no writers: keep the last known state, flagged.
        const auto it = handles_.find(info.instance_handle);
        Row* r = it == handles_.end() ? nullptr : rows_.shown(it->second);
        if (r != nullptr && r->alive &&
            writer_id(info.publication_handle) == writer_id(r->writer)) {
          r->alive = false;
          changed = true;
          if (a_.json) emit_json(*r);
        }
        continue;
      }
      if (!filter_.empty() && !filter_.count(d.mmsi())) continue;
      changed |= heard(d.mmsi());
      Row r;
      r.mmsi = d.mmsi();
      if (!service::from_dds(d, &r.ev)) {
        spdlog::warn("ignored a FaultEvent from MMSI {} with unknown sensor/state/kind octets",
                     d.mmsi());
        continue;
      }
      r.written = static_cast<double>(info.source_timestamp.to_ns()) * 1e-9;
      r.writer = info.publication_handle;
      const RowKey key{r.mmsi, static_cast<int>(r.ev.sensor)};
      handles_[info.instance_handle] = key;
      const OwnerDecision dec =
          rows_.offer(key, r.mmsi, writer_ref(info.publication_handle), r.ev.sequence, r);
      if (dec.report)
        report(dec, r.mmsi, to_string(r.ev.sensor), info.publication_handle, r.ev.sequence,
               to_string(r.ev.state));
      if (dec.verdict != OwnerDecision::Verdict::kShown) continue;
      changed = true;
      if (a_.json) emit_json(r);
    }
    {
      fdi::FdiStatus st;
      while (status_->take_next_sample(&st, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) {
          const auto it = status_handles_.find(info.instance_handle);
          VesselStatus* v = it == status_handles_.end() ? nullptr : vessels_.shown(it->second);
          if (v != nullptr && writer_id(info.publication_handle) == writer_id(v->writer)) {
            v->alive = false;
            changed = a_.status || changed;
          }
          continue;
        }
        if (!filter_.empty() && !filter_.count(st.mmsi())) continue;
        changed |= heard(st.mmsi());
        VesselStatus v;
        v.st = st;
        v.written = static_cast<double>(info.source_timestamp.to_ns()) * 1e-9;
        v.writer = info.publication_handle;
        v.alive = true;
        status_handles_[info.instance_handle] = st.mmsi();
        const OwnerDecision dec =
            vessels_.offer(st.mmsi(), st.mmsi(), writer_ref(info.publication_handle), 0, v);
        if (dec.report) report(dec, st.mmsi(), "status", info.publication_handle, 0, "");
        if (dec.verdict != OwnerDecision::Verdict::kShown) continue;
        if (a_.json && a_.status) {
          std::printf("%s\n", json_status(v, live_.age(st.mmsi(), mono_now())).c_str());
          std::fflush(stdout);
        }
      }
    }
    for (const VesselLiveness::Change& c : live_.evaluate(mono_now())) {
      emit_change(c);
      changed = true;
    }
    return changed;
  }

  int matched_writers() const {
    fdds::SubscriptionMatchedStatus st;
    events_->get_subscription_matched_status(st);
    return st.current_count;
  }
  /// The fault instance shown for `key` (nullptr: none).
  const Row* row(const RowKey& key) const { return rows_.shown(key); }
  const InstanceOwners<RowKey, Row>& rows() const { return rows_; }
  const InstanceOwners<std::uint32_t, VesselStatus>* vessels() const {
    return a_.status ? &vessels_ : nullptr;
  }
  const VesselLiveness& liveness() const { return live_; }
  /// Seconds since anything was received from `mmsi` (NaN: never).
  double heard_age(std::uint32_t mmsi) const { return live_.age(mmsi, mono_now()); }
  /// Conflicts reported so far (writers refused or held).
  int conflicts() const { return conflicts_; }

 private:
  static std::string writer_id(const fdds::InstanceHandle_t& h) {
    std::ostringstream os;
    os << eprosima::fastrtps::rtps::iHandle2GUID(h);
    return os.str();
  }
  /// The writer as InstanceOwners sees it. Under DDS Security a writer whose only partition is a
  /// vessel's is authenticated for that vessel: access control matched it against the signed
  /// permissions of its identity.
  WriterRef writer_ref(const fdds::InstanceHandle_t& h) const {
    WriterRef w;
    w.id = writer_id(h);
    if (secure_) {
      const auto info = ctx_.peers().writer(h);
      if (info) w.vessel = dds::vessel_of_writer(info->partitions);
    }
    return w;
  }

  /// Says loudly that a writer other than an instance's owner wrote it (or that the owner
  /// changed): on stderr, and as a "conflict" object with --json.
  void report(const OwnerDecision& d, std::uint32_t mmsi, const char* sensor,
              const fdds::InstanceHandle_t& writer, std::uint64_t seq, const std::string& state) {
    const bool conflict = d.verdict != OwnerDecision::Verdict::kShown;
    if (conflict) ++conflicts_;
    const std::string w = writer_name(ctx_, writer);
    const std::string what = seq > 0 ? " #" + std::to_string(seq) + " " + state : std::string();
    const std::string owner = d.owner.id.empty() ? std::string("nobody") : d.owner.id;
    const std::string owner_seq =
        d.owner.id.empty() || seq == 0 ? std::string() : " #" + std::to_string(d.owner_sequence);
    if (conflict) {
      spdlog::warn(
          "CONFLICT vessel {} {}: writer {} wrote{} but the instance belongs to writer {}{}: {} "
          "({}); the owner's state is kept",
          mmsi, sensor, w, what, owner, owner_seq,
          d.verdict == OwnerDecision::Verdict::kHeld ? "held, not shown" : "refused",
          to_string(d.why));
    } else {
      spdlog::warn("vessel {} {}: writer {} now owns the instance ({}; it was writer {}{})", mmsi,
                   sensor, w, to_string(d.why), owner, owner_seq);
    }
    if (!a_.json) return;
    std::ostringstream os;
    os << "{\"type\":\"conflict\",\"mmsi\":" << mmsi << ",\"sensor\":\"" << sensor
       << "\",\"verdict\":\""
       << (d.verdict == OwnerDecision::Verdict::kShown  ? "shown"
           : d.verdict == OwnerDecision::Verdict::kHeld ? "held"
                                                        : "refused")
       << "\",\"why\":" << io::json_string(to_string(d.why)) << ",\"writer\":" << io::json_string(w)
       << ",\"sequence\":" << seq << ",\"state\":" << io::json_string(state)
       << ",\"owner\":" << io::json_string(owner) << ",\"owner_sequence\":" << d.owner_sequence
       << "}";
    std::printf("%s\n", os.str().c_str());
    std::fflush(stdout);
  }

  /// Flags the rows (and vessel statuses) whose writer is gone, or shows the held writer that
  /// takes over. Returns true if one changed.
  bool mark_gone_writers() {
    bool changed = false;
    std::vector<fdds::InstanceHandle_t> gone, back;
    events_gone_.take(&gone, &back);
    for (const auto& h : back) rows_.writer_back(writer_id(h));
    for (const auto& h : gone) {
      for (const auto& [key, next] : rows_.writer_gone(writer_id(h))) {
        Row* r = rows_.shown(key);
        if (r == nullptr) continue;
        if (next) {
          spdlog::warn("vessel {} {}: its writer left; now showing writer {}", key.first,
                       to_string(r->ev.sensor), next->id);
          r->alive = true;
        } else if (r->alive) {
          r->alive = false;
        } else {
          continue;
        }
        changed = true;
        if (a_.json) emit_json(*r);
      }
    }
    status_gone_.take(&gone, &back);
    for (const auto& h : back) vessels_.writer_back(writer_id(h));
    for (const auto& h : gone) {
      for (const auto& [m, next] : vessels_.writer_gone(writer_id(h))) {
        VesselStatus* v = vessels_.shown(m);
        if (v == nullptr) continue;
        v->alive = next.has_value();
        changed = a_.status || changed;
      }
    }
    return changed;
  }

  /// Records a sample received from `mmsi` now; prints "heard again" if it was silent.
  bool heard(std::uint32_t mmsi) {
    VesselLiveness::Change c;
    if (!live_.heard(mmsi, mono_now(), &c)) return false;
    emit_change(c);
    return true;
  }

  /// Prints a vessel's change of silence once (not with --once: it prints the final state).
  void emit_change(const VesselLiveness::Change& c) const {
    if (a_.once) return;
    const std::string line =
        a_.json ? json_change(c, live_.silent_after()) : change_line(c, live_.silent_after());
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  void emit_json(const Row& r) const {
    if (a_.once) return;  // --once prints the final state only
    std::printf("%s\n", json_row(r, live_.age(r.mmsi, mono_now())).c_str());
    std::fflush(stdout);
  }

  dds::DdsContext& ctx_;
  const MonitorArgs& a_;
  bool secure_;
  std::set<std::uint32_t> filter_;
  GoneWriters events_gone_, status_gone_;
  fdds::DataReader* events_ = nullptr;
  fdds::DataReader* status_ = nullptr;
  fdds::WaitSet ws_;
  InstanceOwners<RowKey, Row> rows_;
  std::map<fdds::InstanceHandle_t, RowKey> handles_;
  InstanceOwners<std::uint32_t, VesselStatus> vessels_;
  std::map<fdds::InstanceHandle_t, std::uint32_t> status_handles_;
  VesselLiveness live_;
  int conflicts_ = 0;
};

/// Why the sidecar will refuse an ack, judged from the latched state the monitor sees.
std::string refusal_reason(const fdi::FaultAck& ack, const Row* row) {
  if (row == nullptr) return "no such fault instance is latched on this domain/partition";
  const std::uint64_t cur = row->ev.sequence;
  std::string state = " (current #" + std::to_string(cur) + ", " + to_string(row->ev.state) + ")";
  if (ack.sequence() < cur) return "stale sequence" + state;
  if (ack.sequence() > cur) return "unknown sequence" + state;
  if (row->ev.state != FaultState::kRaised && row->ev.state != FaultState::kClearedUnacknowledged) {
    return "nothing to acknowledge" + state;
  }
  return "no confirmation from the sidecar" + state;
}

/// The partitions an acknowledgement to vessel `mmsi` is written in: the monitor's own, with a
/// vessel wildcard ("vessel-*", after any prefix) narrowed to that vessel's partition. Under DDS
/// Security a shore identity may write acks only into the partitions of the vessels it is granted.
std::vector<std::string> ack_partitions(const std::vector<std::string>& mine, std::uint32_t mmsi) {
  std::vector<std::string> out;
  for (const std::string& p : mine) {
    const std::string tag = "vessel-*";
    const bool wildcard =
        p.size() >= tag.size() && p.compare(p.size() - tag.size(), tag.size(), tag) == 0;
    out.push_back(wildcard ? p.substr(0, p.size() - 1) + std::to_string(mmsi) : p);
  }
  return out;
}

/// Sends one ack and waits for the sidecar's confirmation. Returns true if it was accepted.
bool send_ack(fdds::DataWriter& w, FleetView& view, const MonitorArgs& a, fdi::FaultAck ack,
              bool* stop) {
  const RowKey key{ack.mmsi(), ack.sensor()};
  const Row* row = view.row(key);
  const std::string who = "MMSI " + std::to_string(ack.mmsi()) + " " +
                          to_string(static_cast<Sensor>(ack.sensor())) + " #" +
                          std::to_string(ack.sequence());
  ack.stamp(wall_now());
  dds::write(w, ack);
  spdlog::info("ack sent: {} by {}", who, escape_text(a.operator_id));
  // Confirmed when the instance moves from the acknowledged sequence past it, to an
  // acknowledged state. If the latched state is already past it, the ack is stale: the
  // sidecar refuses it, no need to wait.
  const bool already_past = row != nullptr && row->ev.sequence > ack.sequence();
  const auto confirm_by =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(already_past ? 0.0 : a.ack_timeout));
  bool confirmed = false;
  while (!confirmed && Clock::now() < confirm_by) {
    view.poll(0.05);
    const Row* r = view.row(key);
    confirmed = r != nullptr && r->ev.sequence > ack.sequence() &&
                (r->ev.state == FaultState::kActiveAcknowledged ||
                 r->ev.state == FaultState::kAcknowledged);
    if (wait_for_stop_signal(0.0) != 0) {
      *stop = true;
      return false;
    }
  }
  if (!confirmed) {
    const Row* r = view.row(key);
    const std::string reason = refusal_reason(ack, r != nullptr ? r : row);
    if (already_past) {
      spdlog::error("ack {} not accepted: {} (the sidecar logs its refusal)", who, reason);
    } else {
      spdlog::error("ack {} not accepted within {:g} s: {} (the sidecar logs its reason)", who,
                    a.ack_timeout, reason);
    }
    return false;
  }
  const Row& now = *view.row(key);
  spdlog::info("ack {} accepted: now #{} {}", who, now.ev.sequence, to_string(now.ev.state));
  return true;
}

int send_acks(dds::DdsContext& ctx, FleetView& view, const MonitorArgs& a,
              const std::vector<fdi::FaultAck>& acks) {
  int rc = kExitOk;
  std::map<std::uint32_t, fdds::DataWriter*> writers;  // one per vessel, in its partition
  for (const fdi::FaultAck& ack : acks) {
    fdds::DataWriter*& w = writers[ack.mmsi()];
    if (w == nullptr) {
      const auto parts = ack_partitions(ctx.config().publisher_partitions, ack.mmsi());
      try {
        w = &ctx.create_writer_in_partitions(dds::TopicId::kFaultAck,
                                             dds::profiles::kFaultAckWriter, parts);
      } catch (const std::exception& e) {
        spdlog::error(
            "cannot acknowledge vessel {}: {}{}", ack.mmsi(), e.what(),
            ctx.secure() ? " (under DDS Security: is this identity granted the vessel?)" : "");
        rc = kExitFailure;
        continue;
      }
      // Bounded wait until a sidecar's ack reader is matched (so the ack is not lost) and the
      // latched state has arrived (so that the confirmation can be recognised).
      const auto t_start = Clock::now();
      const auto deadline = t_start + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(a.discovery_timeout));
      fdds::PublicationMatchedStatus st;
      for (;;) {
        w->get_publication_matched_status(st);
        if (st.current_count > 0 || Clock::now() >= deadline) break;
        view.poll(0.05);
        if (wait_for_stop_signal(0.0) != 0) return kExitFailure;
      }
      if (st.current_count == 0) {
        spdlog::error(
            "no sidecar subscribes to acknowledgements of vessel {} on domain {} (waited {:g} s)",
            ack.mmsi(), ctx.config().domain_id, a.discovery_timeout);
        rc = kExitFailure;
        continue;
      }
      spdlog::debug("{} sidecar(s) matched after {:.3f} s", st.current_count,
                    std::chrono::duration<double>(Clock::now() - t_start).count());
      // The reader side of the match completes asynchronously; give it, and the historical
      // FaultEvents, a moment (bounded).
      const auto settle = Clock::now() + std::chrono::milliseconds(300);
      while (Clock::now() < settle) view.poll(0.05);
    }
    fdds::PublicationMatchedStatus st;
    w->get_publication_matched_status(st);
    if (st.current_count == 0) {
      rc = kExitFailure;  // reported above
      continue;
    }
    bool stop = false;
    if (!send_ack(*w, view, a, ack, &stop)) rc = kExitFailure;
    if (stop) return kExitFailure;
  }
  return rc;
}

int run_monitor(const MonitorArgs& a) {
  block_stop_signals();  // before Fast DDS starts its threads
  route_fastdds_log_to_spdlog();
  std::vector<fdi::FaultAck> acks;
  for (const std::string& spec : a.acks) {
    fdi::FaultAck ack;
    std::string why;
    if (!parse_ack(spec, &ack, &why)) {
      spdlog::error("{}", why);
      return kExitUsage;
    }
    ack.operator_id(a.operator_id.substr(0, 63).c_str());
    acks.push_back(ack);
  }
  dds::DdsConfig cfg;
  try {
    cfg = make_dds_config(a.dds);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  std::unique_ptr<dds::DdsContext> ctx;
  std::unique_ptr<FleetView> view;
  try {
    ctx = std::make_unique<dds::DdsContext>(cfg);
    view = std::make_unique<FleetView>(*ctx, a);
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  CredentialExpiry expiry;
  try {
    expiry = credential_expiry(cfg.participant_profile);
  } catch (const std::exception& e) {
    spdlog::error("DDS Security: {}", e.what());
    return kExitConfig;
  }
  if (expiry.secure()) spdlog::info("{}", validity_message(expiry));
  if (expiry.expired(wall_now())) {
    spdlog::error("{}", expired_message(expiry));
    return kExitFailure;
  }
  const bool keep_watching = a.once || a.duration > 0.0 || a.expect > 0;
  if (!a.acks.empty()) {
    const int rc = send_acks(*ctx, *view, a, acks);
    if (rc != kExitOk || !keep_watching) return rc;
  }
  const double duration = a.once && a.duration == 0.0 ? 3.0 : a.duration;
  const auto start = Clock::now();
  bool printed = false;
  for (;;) {
    const bool changed = view->poll(0.2);
    if (changed && !a.json && !a.once) {
      print_table(view->rows(), view->vessels(), view->liveness(), view->conflicts());
      printed = true;
    }
    if (expiry.expired(wall_now())) {  // Fast DDS would keep the session open
      spdlog::error("{}", expired_message(expiry));
      return kExitFailure;
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const bool enough = a.expect > 0 && static_cast<int>(view->rows().size()) >= a.expect;
    if (enough || (duration > 0 && elapsed >= duration) || wait_for_stop_signal(0.0) != 0) break;
  }
  if (a.once) {
    if (a.json) {
      view->rows().for_each([&](const RowKey&, const Row& r) {
        std::printf("%s\n", json_row(r, view->heard_age(r.mmsi)).c_str());
      });
      if (view->vessels() != nullptr) {
        view->vessels()->for_each([&](const std::uint32_t& m, const VesselStatus& v) {
          std::printf("%s\n", json_status(v, view->heard_age(m)).c_str());
        });
      }
      std::fflush(stdout);
    } else {
      print_table(view->rows(), view->vessels(), view->liveness(), view->conflicts());
    }
  } else if (!a.json && !printed) {
    print_table(view->rows(), view->vessels(), view->liveness(), view->conflicts());
  }
  if (a.expect > 0 && static_cast<int>(view->rows().size()) < a.expect) {
    spdlog::error("saw {} fault instances, expected {}", view->rows().size(), a.expect);
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void register_monitor_command(CommandRegistry& registry) {
  static MonitorArgs args;
  CLI::App* sub = registry.add(
      "monitor",
      "shore-side table of every vessel's latched fault instances (late-join aware); --ack to "
      "acknowledge one",
      [] { return run_monitor(args); });
  add_dds_options(sub, &args.dds);
  sub->add_option("--mmsi", args.mmsi, "only these vessels (repeatable)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_flag("--json", args.json, "JSON Lines instead of a table: one line per received update");
  sub->add_flag("--status", args.status, "also show each vessel's detector status (FdiStatus)");
  sub->add_option("--ack", args.acks,
                  "acknowledge MMSI:SENSOR:SEQUENCE and wait for the sidecar's confirmation "
                  "(repeatable; exit 1 if one is not accepted)");
  sub->add_option("--operator", args.operator_id, "operator id sent with --ack")
      ->capture_default_str();
  sub->add_option("--ack-timeout", args.ack_timeout,
                  "wait this long for the sidecar's confirmation of each ack [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--discovery-timeout", args.discovery_timeout,
                  "--ack: wait this long for a sidecar's acknowledgement reader [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--duration", args.duration, "stop after this many seconds (0: on a signal)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--once", args.once,
                "wait --duration (default 3 s) for the latched state, print it once, exit");
  sub->add_option("--expect", args.expect, "exit 0 once this many fault instances are known")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--silent-after", args.silent_after,
                  "flag a vessel silent when nothing (status or fault event) has been received "
                  "from it for this long [s]; printed once when it goes silent and when it is "
                  "heard again")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

}  // namespace usvfdi::app
