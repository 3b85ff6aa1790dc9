// usv-fdi monitor: the shore-side subscriber. Late-join aware: its FaultEvent reader is
// RELIABLE + TRANSIENT_LOCAL, KEEP_LAST 1 per instance, sized for a fleet (4096 instances),
// so on start it receives the latched state of every fault instance of every vessel.
// With --ack it acknowledges an event and waits for the sidecar's confirmation.
// It always reads FdiStatus too (printed with --status): every sample of a vessel updates its
// "last heard" time, and a vessel not heard for --silent-after s is flagged silent on a timer.
// With --roster it knows the fleet's MMSIs and shows (and reports) a vessel never heard. --once
// waits for the latched state (LatchedStateWait), not a fixed time. The table redraws in place
// on a terminal and prints only the changed rows elsewhere (TableOutput).
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "ack_protocol.hpp"
#include "commands.hpp"
#include "credentials.hpp"
#include "dds_options.hpp"
#include "fleet_view.hpp"
#include "monitor_format.hpp"
#include "table_output.hpp"
#include "usv_fdi/core/text.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::app {
namespace {

using Clock = std::chrono::steady_clock;

TableInput table_input(const FleetView& view) {
  return TableInput{view.rows(), view.vessels(), view.liveness(), view.conflicts(), &view.roster()};
}

void print_table(const FleetView& view) {
  TableExtras extras;
  extras.roster = &view.roster();
  const std::string t = format_table(view.rows(), view.vessels(), view.liveness(), view.conflicts(),
                                     wall_now(), mono_now(), extras);
  std::fputs(t.c_str(), stdout);
  std::fflush(stdout);
}

void write_stdout(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

/// True when the latched state of some instance of the vessel is shown.
bool has_vessel(const FleetView& view, std::uint32_t mmsi) {
  bool found = false;
  view.rows().for_each([&](const RowKey& key, const Row&) { found = found || key.first == mmsi; });
  return found;
}

/// Sends one ack and waits for the sidecar's confirmation. Returns true if it was accepted.
bool send_ack(fdds::DataWriter& w, FleetView& view, const MonitorArgs& a, const AckRequest& req,
              bool* stop) {
  const RowKey key{req.mmsi, static_cast<int>(req.sensor)};
  const Row* row = view.row(key);
  const std::string who = "MMSI " + std::to_string(req.mmsi) + " " + to_string(req.sensor) + " #" +
                          std::to_string(req.sequence);
  fdi::FaultAck ack;
  ack.mmsi(req.mmsi);
  ack.sensor(static_cast<std::uint8_t>(req.sensor));
  ack.sequence(req.sequence);
  ack.operator_id(a.operator_id.substr(0, 63).c_str());
  ack.stamp(wall_now());
  if (row != nullptr) ack.incarnation(row->ev.incarnation);  // else refused by the sidecar
  dds::write(w, ack);
  spdlog::info("ack sent: {} by {}", who, escape_text(a.operator_id));
  // If the latched state is already past the sequence, the ack is stale: the sidecar refuses it,
  // no need to wait.
  const bool already_past = ack_already_past(req, row);
  const auto confirm_by =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(already_past ? 0.0 : a.ack_timeout));
  bool confirmed = false;
  while (!confirmed && Clock::now() < confirm_by) {
    view.poll(0.05);
    confirmed = ack_confirmed(req, view.row(key));
    if (wait_for_stop_signal(0.0) != 0) {
      *stop = true;
      return false;
    }
  }
  if (!confirmed) {
    const Row* r = view.row(key);
    const std::string reason = refusal_reason(req, r != nullptr ? r : row);
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
              const std::vector<AckRequest>& acks) {
  int rc = kExitOk;
  std::map<std::uint32_t, fdds::DataWriter*> writers;  // one per vessel, in its partition
  for (const AckRequest& ack : acks) {
    fdds::DataWriter*& w = writers[ack.mmsi];
    if (w == nullptr) {
      const auto parts = ack_partitions(ctx.config().publisher_partitions, ack.mmsi);
      try {
        w = &ctx.create_writer_in_partitions(dds::TopicId::kFaultAck,
                                             dds::profiles::kFaultAckWriter, parts);
      } catch (const std::exception& e) {
        spdlog::error(
            "cannot acknowledge vessel {}: {}{}", ack.mmsi, e.what(),
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
            ack.mmsi, ctx.config().domain_id, a.discovery_timeout);
        rc = kExitFailure;
        continue;
      }
      spdlog::debug("{} sidecar(s) matched after {:.3f} s", st.current_count,
                    std::chrono::duration<double>(Clock::now() - t_start).count());
      // The reader side of the match completes asynchronously; give it, and the historical
      // FaultEvents, a moment (bounded).
      const auto settle = Clock::now() + std::chrono::milliseconds(300);
      while (Clock::now() < settle) view.poll(0.05);
      // On a busy machine the latched state may take longer: the ack must name the current
      // event's incarnation, so wait (bounded) until some instance of the vessel has arrived.
      while (!has_vessel(view, ack.mmsi) && Clock::now() < deadline) {
        view.poll(0.05);
        if (wait_for_stop_signal(0.0) != 0) return kExitFailure;
      }
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

/// The --ack specs; false (logged) for a bad one.
bool parse_acks(const MonitorArgs& a, std::vector<AckRequest>* acks) {
  for (const std::string& spec : a.acks) {
    AckRequest ack;
    std::string why;
    if (!parse_ack(spec, &ack, &why)) {
      spdlog::error("{}", why);
      return false;
    }
    acks->push_back(ack);
  }
  return true;
}

}  // namespace

int join_fleet_domain(const MonitorArgs& a, std::unique_ptr<dds::DdsContext>* ctx,
                      std::unique_ptr<FleetView>* view, CredentialExpiry* expiry) {
  std::set<std::uint32_t> roster;
  std::string why;
  if (!a.roster.empty() && !load_roster(a.roster, &roster, &why)) {
    spdlog::error("{}", why);
    return kExitConfig;
  }
  if (!roster.empty()) spdlog::info("roster {}: {} vessel(s)", a.roster, roster.size());
  dds::DdsConfig cfg;
  try {
    cfg = make_dds_config(a.dds);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  try {
    *ctx = std::make_unique<dds::DdsContext>(cfg);
    *view = std::make_unique<FleetView>(**ctx, a, std::move(roster));
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  try {
    *expiry = credential_expiry(cfg.participant_profile);
  } catch (const std::exception& e) {
    spdlog::error("DDS Security: {}", e.what());
    return kExitConfig;
  }
  if (expiry->secure()) spdlog::info("{}", validity_message(*expiry));
  if (expiry->expired(wall_now())) {
    spdlog::error("{}", expired_message(*expiry));
    return kExitFailure;
  }
  return kExitOk;
}

namespace {

/// Receives until --expect instances are known, --once has the latched state, --duration
/// (--once: kOnceDefaultDuration by default) has passed or a signal came, showing the table
/// unless --json or --once (TableOutput). Returns kExitOk, or kExitFailure when the credentials
/// expire.
int watch(const MonitorArgs& a, FleetView& view, const CredentialExpiry& expiry) {
  const double duration = a.once && a.duration == 0.0 ? kOnceDefaultDuration : a.duration;
  const bool show_table = !a.json && !a.once;
  TableOutput table(show_table && ::isatty(STDOUT_FILENO) == 1, write_stdout);
  const auto start = Clock::now();
  bool latched = false;
  for (;;) {
    const double wait = a.once ? 0.05 : std::min(0.2, table.due_in(mono_now()));
    const bool changed = view.poll(wait);
    if (show_table) table.update(table_input(view), changed, wall_now(), mono_now());
    if (expiry.expired(wall_now())) {  // Fast DDS would keep the session open
      spdlog::error("{}", expired_message(expiry));
      return kExitFailure;
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const bool enough = a.expect > 0 && static_cast<int>(view.rows().size()) >= a.expect;
    // --once --expect N: as before, N instances (or --duration) end the wait.
    latched = a.once && a.expect == 0 && view.latched_complete();
    if (enough || latched || (duration > 0 && elapsed >= duration) ||
        wait_for_stop_signal(0.0) != 0) {
      break;
    }
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  if (a.once && a.expect == 0) {
    if (latched) {
      spdlog::info("latched state received after {:.2f} s", elapsed);
    } else {
      std::string what;
      for (const std::string& p : view.latched_pending()) what += (what.empty() ? "" : "; ") + p;
      spdlog::warn("the latched state may be incomplete after {:.2f} s (--duration {:g} s): {}",
                   elapsed, duration, what.empty() ? "interrupted" : what);
    }
  }
  if (show_table) table.finish(table_input(view), wall_now(), mono_now());
  return kExitOk;
}

/// --once: the latched state of every instance (and each vessel's status), as JSON Lines with
/// --json, else as the table.
void print_once(const MonitorArgs& a, const FleetView& view) {
  if (!a.json) {
    print_table(view);
    return;
  }
  view.rows().for_each([&](const RowKey&, const Row& r) {
    std::printf("%s\n", json_row(r, view.heard_age(r.mmsi), wall_now()).c_str());
  });
  if (view.vessels() != nullptr) {
    view.vessels()->for_each([&](const std::uint32_t& m, const VesselStatus& v) {
      std::printf("%s\n", json_status(v, view.heard_age(m), wall_now()).c_str());
    });
  }
  const RosterWatch& roster = view.roster();
  if (roster.active()) {
    for (const std::uint32_t m : roster.shown(view.liveness())) {
      std::printf("%s\n",
                  json_roster(m, roster.state(m, view.liveness()), view.heard_age(m)).c_str());
    }
  }
  std::fflush(stdout);
}

/// With a roster: warns about every roster vessel never heard (and silent), and returns
/// kExitIncomplete with --once if one was never heard.
int report_roster(const MonitorArgs& a, const FleetView& view) {
  const RosterWatch& roster = view.roster();
  if (!roster.active()) return kExitOk;
  const std::vector<std::uint32_t> missing = roster.never_heard(view.liveness());
  for (const std::uint32_t m : missing) {
    spdlog::warn("roster vessel {} was never heard", m);
  }
  for (const std::uint32_t m : roster.roster()) {
    if (roster.state(m, view.liveness()) == RosterState::kSilent) {
      spdlog::warn("roster vessel {} is silent: last heard {:.1f} s ago", m, view.heard_age(m));
    }
  }
  if (missing.empty()) {
    spdlog::info("every vessel of the roster ({}) heard", roster.roster().size());
    return kExitOk;
  }
  spdlog::warn("{} of {} roster vessel(s) never heard: this view of the fleet is partial",
               missing.size(), roster.roster().size());
  return a.once ? kExitIncomplete : kExitOk;
}

int run_monitor(const MonitorArgs& a) {
  block_stop_signals();  // before Fast DDS starts its threads
  route_fastdds_log_to_spdlog();
  std::vector<AckRequest> acks;
  if (!parse_acks(a, &acks)) return kExitUsage;
  std::unique_ptr<dds::DdsContext> ctx;
  std::unique_ptr<FleetView> view;
  CredentialExpiry expiry;
  int rc = join_fleet_domain(a, &ctx, &view, &expiry);
  if (rc != kExitOk) return rc;
  const bool keep_watching = a.once || a.duration > 0.0 || a.expect > 0;
  if (!a.acks.empty()) {
    rc = send_acks(*ctx, *view, a, acks);
    if (rc != kExitOk || !keep_watching) return rc;
  }
  rc = watch(a, *view, expiry);
  if (rc != kExitOk) return rc;
  if (a.once) print_once(a, *view);
  if (a.expect > 0 && static_cast<int>(view->rows().size()) < a.expect) {
    spdlog::error("saw {} fault instances, expected {}", view->rows().size(), a.expect);
    return kExitFailure;
  }
  return report_roster(a, *view);
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
  sub->add_option("--duration", args.duration,
                  "stop after this many seconds (0: on a signal; --once: the longest wait for "
                  "the latched state, default 10 s)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--once", args.once,
                "wait until the latched state has arrived (discovery settled, every sidecar's "
                "status received; at most --duration), print it once, exit");
  sub->add_option("--expect", args.expect, "exit 0 once this many fault instances are known")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--silent-after", args.silent_after,
                  "flag a vessel silent when nothing (status or fault event) has been received "
                  "from it for this long [s]; printed once when it goes silent and when it is "
                  "heard again")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--roster", args.roster,
                  "file of the fleet's MMSIs (one per line, '#' comments): a roster vessel never "
                  "heard is shown and reported (--once: exit 6), a vessel heard that is not on "
                  "it is marked")
      ->check(CLI::ExistingFile);
}

}  // namespace usvfdi::app
