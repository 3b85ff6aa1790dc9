// The DDS side of the monitor: the FaultEvent and FdiStatus readers, the writers that left, and
// the fleet as it is shown (InstanceOwners of rows and statuses, VesselLiveness).
#pragma once

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include <cstdio>
#include <sstream>

#include "credentials.hpp"
#include "discovery_limit.hpp"
#include "instance_owners.hpp"
#include "latched_wait.hpp"
#include "monitor_format.hpp"
#include "monitor_model.hpp"
#include "roster.hpp"
#include "usv_fdi/dds/dds_context.hpp"
#include "usv_fdi/dds_service/convert.hpp"
#include "vessel_liveness.hpp"

namespace usvfdi::app {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

/// Records the writers (sidecars) that matched and went away: Fast DDS 2.9 neither delivers an
/// instance-state sample when a writer disappears nor implements get_matched_publications(),
/// so the monitor learns it from on_subscription_matched. Only copies a handle and reads the
/// monotonic clock under a lock.
class GoneWriters : public fdds::DataReaderListener {
 public:
  void on_subscription_matched(fdds::DataReader*,
                               const fdds::SubscriptionMatchedStatus& info) override {
    std::lock_guard<std::mutex> lock(m_);
    if (info.current_count_change < 0) {
      gone_.push_back(info.last_publication_handle);
    } else if (info.current_count_change > 0) {
      back_.push_back(info.last_publication_handle);
      back_at_.push_back(mono_now());
    }
  }
  /// Moves the handles of writers gone (and matched, with when) since the last call into the
  /// outputs.
  void take(std::vector<fdds::InstanceHandle_t>* gone, std::vector<fdds::InstanceHandle_t>* back,
            std::vector<double>* back_at) {
    std::lock_guard<std::mutex> lock(m_);
    gone->swap(gone_);
    back->swap(back_);
    back_at->swap(back_at_);
    gone_.clear();
    back_.clear();
    back_at_.clear();
  }

 private:
  std::mutex m_;
  std::vector<fdds::InstanceHandle_t> gone_, back_;
  std::vector<double> back_at_;  ///< when each of back_ matched [mono s]
};

/// How many participants the participant QoS in use can discover at most: with unicast-only
/// discovery over UDPv4 (initial peers, no builtin transports) a participant announces itself
/// to the ports of participant ids 0..maxInitialPeersRange-1 of each initial peer, and two
/// participants whose ports lie beyond that never find each other (also bounded by
/// mutation_tries, the number of ports a participant tries when its own is taken). 0: no such
/// limit (multicast discovery, shared memory, discovery servers).
int unicast_discovery_limit(const fdds::DomainParticipantQos& qos);

/// The text naming a writer in a conflict report: its GUID, its identity's CN and its partitions.
std::string writer_name(const dds::DdsContext& ctx, const fdds::InstanceHandle_t& h);

/// The FaultEvent and FdiStatus side of the monitor. The FdiStatus reader exists even without
/// --status: the periodic status is what tells a quiet vessel from a silent one. Every sample
/// passes InstanceOwners: only the writer that owns an instance updates it.
class FleetView {
 public:
  /// `roster`: the MMSIs expected (empty: no roster).
  FleetView(dds::DdsContext& ctx, const MonitorArgs& a, std::set<std::uint32_t> roster = {})
      : ctx_(ctx),
        a_(a),
        secure_(ctx.secure()),
        filter_(a.mmsi.begin(), a.mmsi.end()),
        live_(a.silent_after),
        roster_(std::move(roster), mono_now(), a.silent_after),
        discovery_limit_(unicast_discovery_limit(ctx.participant().get_qos())) {
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
    check_discovery_limit();
    fdi::FaultEvent d;
    fdds::SampleInfo info;
    while (events_->take_next_sample(&d, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) {
        // Disposed / no writers: keep the last known state, flagged.
        const auto it = handles_.find(info.instance_handle);
        Row* r = it == handles_.end() ? nullptr : rows_.shown(it->second);
        if (r != nullptr && r->alive && writer_id(info.publication_handle) == r->writer) {
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
      if (!dds_service::from_dds(d, &r.ev)) {
        spdlog::warn("ignored a FaultEvent from MMSI {} with unknown sensor/state/kind octets",
                     d.mmsi());
        continue;
      }
      r.written = static_cast<double>(info.source_timestamp.to_ns()) * 1e-9;
      r.writer = writer_id(info.publication_handle);
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
      if (on_row_) on_row_(r);
    }
    {
      fdi::FdiStatus st;
      while (status_->take_next_sample(&st, &info) == ReturnCode_t::RETCODE_OK) {
        if (info.valid_data) latched_.status_sample(writer_id(info.publication_handle));
        if (!info.valid_data) {
          const auto it = status_handles_.find(info.instance_handle);
          VesselStatus* v = it == status_handles_.end() ? nullptr : vessels_.shown(it->second);
          if (v != nullptr && writer_id(info.publication_handle) == v->writer) {
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
        v.writer = writer_id(info.publication_handle);
        v.alive = true;
        status_handles_[info.instance_handle] = st.mmsi();
        const OwnerDecision dec =
            vessels_.offer(st.mmsi(), st.mmsi(), writer_ref(info.publication_handle), 0, v);
        if (dec.report) report(dec, st.mmsi(), "status", info.publication_handle, 0, "");
        if (dec.verdict != OwnerDecision::Verdict::kShown) continue;
        if (on_status_) on_status_(v);
        if (a_.json && a_.status) {
          std::printf("%s\n", json_status(v, live_.age(st.mmsi(), mono_now()), wall_now()).c_str());
          std::fflush(stdout);
        }
      }
    }
    for (const VesselLiveness::Change& c : live_.evaluate(mono_now())) {
      emit_change(c);
      changed = true;
    }
    for (const RosterWatch::Change& c : roster_.evaluate(live_, mono_now())) {
      emit_roster(c);
      changed = true;
    }
    return changed;
  }

  /// Calls `f` with every fault event shown (after the ownership check), as it is applied.
  void on_row(std::function<void(const Row&)> f) { on_row_ = std::move(f); }
  /// Called with every status shown (its writer owns the vessel's status instance).
  void on_status(std::function<void(const VesselStatus&)> f) { on_status_ = std::move(f); }

  /// --once: true when the latched state has arrived (LatchedStateWait).
  bool latched_complete() const {
    return latched_.complete(mono_now(), roster_.active(), roster_.never_heard(live_));
  }
  /// What the latched state still waits for (empty: nothing).
  std::vector<std::string> latched_pending() const {
    return latched_.pending(mono_now(), roster_.active(), roster_.never_heard(live_));
  }
  const RosterWatch& roster() const { return roster_; }

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
    const std::string line = json_conflict(d, mmsi, sensor, w, seq, state);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  /// Flags the rows (and vessel statuses) whose writer is gone, or shows the held writer that
  /// takes over. Returns true if one changed.
  bool mark_gone_writers() {
    bool changed = false;
    std::vector<fdds::InstanceHandle_t> gone, back;
    std::vector<double> back_at;
    events_gone_.take(&gone, &back, &back_at);
    for (std::size_t i = 0; i < back.size(); ++i) {
      rows_.writer_back(writer_id(back[i]));
      latched_.matched(LatchedStateWait::Topic::kFaultEvent, writer_id(back[i]), back_at[i]);
    }
    for (const auto& h : gone) {
      latched_.unmatched(LatchedStateWait::Topic::kFaultEvent, writer_id(h));
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
    status_gone_.take(&gone, &back, &back_at);
    for (std::size_t i = 0; i < back.size(); ++i) {
      vessels_.writer_back(writer_id(back[i]));
      latched_.matched(LatchedStateWait::Topic::kStatus, writer_id(back[i]), back_at[i]);
    }
    for (const auto& h : gone) {
      latched_.unmatched(LatchedStateWait::Topic::kStatus, writer_id(h));
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

  /// Warns once when the participants discovered approach the limit of unicast discovery of
  /// the participant profile in use (unicast_discovery_limit()).
  void check_discovery_limit() {
    if (discovery_limit_ <= 0) return;
    const std::size_t n = ctx_.peers().participant_count() + 1;  // this monitor included
    const int level = discovery_limit_level(n, discovery_limit_);
    if (level <= discovery_warned_) return;
    discovery_warned_ = level;
    spdlog::warn(
        "discovery: {} participants on domain {} (this monitor included) {} the {} the "
        "participant profile '{}' can discover by unicast (its UDPv4 transport's "
        "maxInitialPeersRange, at most its mutation_tries): participants beyond it may never "
        "be discovered and their "
        "vessels would be missing from this view{}; raise maxInitialPeersRange, or use "
        "multicast discovery or a discovery server",
        n, ctx_.config().domain_id, level >= 2 ? "have reached" : "approach", discovery_limit_,
        ctx_.config().participant_profile,
        roster_.active() ? "" : " (give the fleet's MMSIs with --roster to be told which)");
  }

  /// Reports a change against the roster once: a warning on stderr, a line (or a "roster" object
  /// with --json) on stdout; with --once only the final state is printed.
  void emit_roster(const RosterWatch::Change& c) const {
    if (a_.once) return;
    const std::string line = roster_line(c);
    if (c.state == RosterState::kHeard) {
      spdlog::info("{}", line);
    } else {
      spdlog::warn("{}", line);
    }
    const std::string out =
        a_.json ? json_roster(c.mmsi, roster_.state(c.mmsi, live_), live_.age(c.mmsi, mono_now()))
                : line;
    std::printf("%s\n", out.c_str());
    std::fflush(stdout);
  }

  /// Prints a vessel's change of silence once (not with --once: it prints the final state).
  void emit_change(const VesselLiveness::Change& c) const {
    if (c.silent && roster_.on_roster(c.mmsi)) {
      spdlog::warn("roster vessel {} silent: nothing heard for {:.1f} s", c.mmsi, c.age);
    }
    if (a_.once) return;
    const std::string line =
        a_.json ? json_change(c, live_.silent_after()) : change_line(c, live_.silent_after());
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  void emit_json(const Row& r) const {
    if (a_.once) return;  // --once prints the final state only
    std::printf("%s\n", json_row(r, live_.age(r.mmsi, mono_now()), wall_now()).c_str());
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
  RosterWatch roster_;
  LatchedStateWait latched_;
  int discovery_limit_ = 0;   ///< unicast_discovery_limit() of the participant QoS (0: none)
  int discovery_warned_ = 0;  ///< discovery_limit_level() already warned about
  int conflicts_ = 0;
  std::function<void(const Row&)> on_row_;
  std::function<void(const VesselStatus&)> on_status_;
};

/// Joins the DDS domain with a fleet view's readers (the roster of a.roster) and reads the
/// credentials' validity (monitor, dashboard). Returns kExitOk, or the exit code after logging
/// why not.
int join_fleet_domain(const MonitorArgs& a, std::unique_ptr<dds::DdsContext>* ctx,
                      std::unique_ptr<FleetView>* view, CredentialExpiry* expiry);

}  // namespace usvfdi::app
