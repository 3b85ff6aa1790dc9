// usv-fdi dashboard: the shore's fleet board in a browser. A DDS participant like `monitor`
// (the same FleetView: late-join aware FaultEvent reader, FdiStatus for liveness, instance
// ownership), plus an HTTP server (cpp-httplib) on a configurable address that serves the page
// carried in the binary (dashboard/web/), the board as JSON (/api/board), the board pushed on
// every change and once a second (server-sent events, /api/stream) and acknowledgements
// (/api/ack, written as FaultAck by the DDS thread, their outcome shown on the board).
//
// Threads: the main thread owns DDS and the fleet view; the HTTP server's threads see only the
// Hub (the latest board as text, and the queue of acknowledgements asked for).
#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "ack_protocol.hpp"
#include "commands.hpp"
#include "credentials.hpp"
#include "dashboard/board.hpp"
#include "dashboard_assets.hpp"
#include "dds_options.hpp"
#include "fleet_view.hpp"
#include "usv_fdi/core/text.hpp"

// Last: it includes <resolv.h>, whose _res macro breaks Eigen's headers included after it.
#include <httplib.h>

namespace usvfdi::app {
namespace {

using nlohmann::json;
namespace db = dashboard;

struct DashboardArgs {
  MonitorArgs m;
  std::string listen = "127.0.0.1:8080";
  bool read_only = false;
  std::size_t history = 1000;
};

/// What the HTTP threads share with the DDS thread: the latest board and the acks asked for.
class Hub {
 public:
  void publish(std::string board) {
    {
      std::lock_guard<std::mutex> l(m_);
      board_ = std::move(board);
      ++version_;
    }
    cv_.notify_all();
  }
  /// Waits up to `timeout` for a board newer than *seen; true and that board if there is one.
  bool next(std::uint64_t* seen, std::string* out, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> l(m_);
    cv_.wait_for(l, timeout, [&] { return stop_ || version_ > *seen; });
    if (stop_ || version_ <= *seen) return false;
    *seen = version_;
    *out = board_;
    return true;
  }
  std::string current() {
    std::lock_guard<std::mutex> l(m_);
    return board_;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> l(m_);
      stop_ = true;
    }
    cv_.notify_all();
  }
  bool stopped() {
    std::lock_guard<std::mutex> l(m_);
    return stop_;
  }
  void ask(db::AckWork w) {
    std::lock_guard<std::mutex> l(m_);
    acks_.push_back(std::move(w));
  }
  std::vector<db::AckWork> take_asked() {
    std::lock_guard<std::mutex> l(m_);
    std::vector<db::AckWork> out;
    out.swap(acks_);
    return out;
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::string board_ = "{}";
  std::uint64_t version_ = 0;
  bool stop_ = false;
  std::vector<db::AckWork> acks_;
};

void reply_json(httplib::Response& res, int status, const json& j) {
  res.status = status;
  res.set_content(j.dump(), "application/json");
}

void routes(httplib::Server& svr, Hub& hub, const DashboardArgs& a) {
  const auto page = [](const char* body, const char* type) {
    return [body, type](const httplib::Request&, httplib::Response& res) {
      res.set_header("Content-Security-Policy", "default-src 'self'");
      res.set_header("Cache-Control", "no-cache");
      res.set_content(body, type);
    };
  };
  svr.Get("/", page(db::assets::kIndexHtml, "text/html; charset=utf-8"));
  svr.Get("/index.html", page(db::assets::kIndexHtml, "text/html; charset=utf-8"));
  svr.Get("/app.js", page(db::assets::kAppJs, "text/javascript; charset=utf-8"));
  svr.Get("/style.css", page(db::assets::kStyleCss, "text/css; charset=utf-8"));
  svr.Get("/favicon.ico",
          [](const httplib::Request&, httplib::Response& res) { res.status = 204; });
  svr.Get("/api/board", [&hub](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    res.set_content(hub.current(), "application/json");
  });
  svr.Get("/api/stream", [&hub](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    auto seen = std::make_shared<std::uint64_t>(0);
    res.set_chunked_content_provider(
        "text/event-stream", [&hub, seen](std::size_t, httplib::DataSink& sink) {
          std::string board;
          if (hub.next(seen.get(), &board, std::chrono::milliseconds(2000))) {
            const std::string msg = "data: " + board + "\n\n";
            return sink.write(msg.data(), msg.size());
          }
          if (hub.stopped()) {
            sink.done();
            return true;
          }
          static const std::string keepalive = ": keepalive\n\n";
          return sink.write(keepalive.data(), keepalive.size());
        });
  });
  svr.Post("/api/ack", [&hub, &a](const httplib::Request& req, httplib::Response& res) {
    if (a.read_only) {
      reply_json(res, 403,
                 {{"error", "this dashboard is read-only (observers cannot acknowledge)"}});
      spdlog::warn("refused an acknowledgement from {}: the dashboard is read-only",
                   req.remote_addr);
      return;
    }
    db::AckWork w;
    std::string why;
    if (!db::parse_ack_body(req.body, &w, &why)) {
      reply_json(res, 400, {{"error", why}});
      spdlog::warn("refused an acknowledgement request from {}: {}", req.remote_addr,
                   escape_text(why));
      return;
    }
    reply_json(res, 202, {{"queued", true}});
    hub.ask(std::move(w));
  });
}

/// Splits HOST:PORT (an IPv6 host in brackets); false if it is not that.
bool split_listen(const std::string& s, std::string* host, int* port) {
  const std::size_t colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size()) return false;
  std::string h = s.substr(0, colon);
  if (h.size() > 2 && h.front() == '[' && h.back() == ']') h = h.substr(1, h.size() - 2);
  try {
    std::size_t used = 0;
    const int p = std::stoi(s.substr(colon + 1), &used);
    if (used != s.size() - colon - 1 || p < 0 || p > 65535) return false;
    *host = h;
    *port = p;
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

/// The acknowledgements the DDS thread sends and follows until the sidecar's verdict.
class Acks {
 public:
  Acks(dds::DdsContext& ctx, FleetView& view, const MonitorArgs& a)
      : ctx_(ctx), view_(view), a_(a) {}

  void ask(const db::AckWork& w) {
    Pending p;
    p.work = w;
    p.id = ++next_id_;
    p.asked = mono_now();
    db::AckOutcome o;
    o.mmsi = w.req.mmsi;
    o.sensor = w.req.sensor;
    o.sequence = w.req.sequence;
    o.operator_id = w.operator_id;
    o.sent = wall_now();
    o.state = "pending";
    outcomes_.push_front({p.id, o});
    while (outcomes_.size() > 100) outcomes_.pop_back();
    spdlog::info("ack asked from the dashboard: MMSI {} {} #{} by {}", w.req.mmsi,
                 to_string(w.req.sensor), w.req.sequence, escape_text(w.operator_id));
    pending_.push_back(p);
  }

  /// Writes what can be written, and settles what the sidecar has answered. True if an outcome
  /// changed.
  bool turn() {
    bool changed = false;
    const double now = mono_now();
    for (auto it = pending_.begin(); it != pending_.end();) {
      if (step(&*it, now, &changed)) {
        it = pending_.erase(it);
      } else {
        ++it;
      }
    }
    return changed;
  }

  std::deque<db::AckOutcome> outcomes() const {
    std::deque<db::AckOutcome> out;
    for (const auto& [id, o] : outcomes_) out.push_back(o);
    return out;
  }

 private:
  struct Pending {
    db::AckWork work;
    std::uint64_t id = 0;
    double asked = 0.0;   ///< [mono s]
    double written = -1;  ///< [mono s]; < 0: not yet
  };

  void settle(std::uint64_t id, const std::string& state, const std::string& reason) {
    for (auto& [i, o] : outcomes_) {
      if (i != id) continue;
      o.state = state;
      o.reason = reason;
      const std::string who =
          std::to_string(o.mmsi) + " " + to_string(o.sensor) + " #" + std::to_string(o.sequence);
      if (state == "accepted") {
        spdlog::info("ack {} by {} accepted", who, escape_text(o.operator_id));
      } else {
        spdlog::warn("ack {} by {} not accepted: {}", who, escape_text(o.operator_id), reason);
      }
    }
  }

  /// One pending ack; true when it is settled.
  bool step(Pending* p, double now, bool* changed) {
    const AckRequest& req = p->work.req;
    const RowKey key{req.mmsi, static_cast<int>(req.sensor)};
    if (p->written < 0) {
      fdds::DataWriter* w = writer(req.mmsi);
      if (w == nullptr) {
        settle(p->id, "refused", "cannot write acknowledgements to this vessel (see the log)");
        *changed = true;
        return true;
      }
      fdds::PublicationMatchedStatus st;
      w->get_publication_matched_status(st);
      const Row* row = view_.row(key);
      if (st.current_count == 0 || row == nullptr) {
        if (now - p->asked < a_.discovery_timeout) return false;
        settle(p->id, "refused",
               row == nullptr ? "no latched event of this vessel and sensor is known here"
                              : "no sidecar of this vessel subscribes to acknowledgements");
        *changed = true;
        return true;
      }
      if (ack_already_past(req, row)) {
        settle(p->id, "refused", refusal_reason(req, row));
        *changed = true;
        return true;
      }
      fdi::FaultAck ack;
      ack.mmsi(req.mmsi);
      ack.sensor(static_cast<std::uint8_t>(req.sensor));
      ack.sequence(req.sequence);
      ack.operator_id(p->work.operator_id.substr(0, 63).c_str());
      ack.stamp(wall_now());
      ack.incarnation(row->ev.incarnation);
      dds::write(*w, ack);
      p->written = now;
      return false;
    }
    const Row* row = view_.row(key);
    if (ack_confirmed(req, row)) {
      settle(p->id, "accepted", "");
      *changed = true;
      return true;
    }
    if (now - p->written >= a_.ack_timeout) {
      settle(p->id, "refused", refusal_reason(req, row));
      *changed = true;
      return true;
    }
    return false;
  }

  fdds::DataWriter* writer(std::uint32_t mmsi) {
    const auto it = writers_.find(mmsi);
    if (it != writers_.end()) return it->second;
    fdds::DataWriter* w = nullptr;
    try {
      w = &ctx_.create_writer_in_partitions(
          dds::TopicId::kFaultAck, dds::profiles::kFaultAckWriter,
          ack_partitions(ctx_.config().publisher_partitions, mmsi));
    } catch (const std::exception& e) {
      spdlog::error(
          "cannot acknowledge vessel {}: {}{}", mmsi, e.what(),
          ctx_.secure() ? " (under DDS Security: is this identity granted the vessel?)" : "");
    }
    writers_[mmsi] = w;
    return w;
  }

  dds::DdsContext& ctx_;
  FleetView& view_;
  const MonitorArgs& a_;
  std::map<std::uint32_t, fdds::DataWriter*> writers_;
  std::vector<Pending> pending_;
  std::deque<std::pair<std::uint64_t, db::AckOutcome>> outcomes_;
  std::uint64_t next_id_ = 0;
};

std::string make_board(const FleetView& view, const db::EventHistory& events, const Acks& acks,
                       bool can_ack) {
  db::BoardInput in;
  view.rows().for_each([&](const RowKey& k, const Row& r) { in.rows[k] = r; });
  if (view.vessels() != nullptr) {
    view.vessels()->for_each(
        [&](const std::uint32_t& m, const VesselStatus& v) { in.statuses[m] = v; });
  }
  const double mono = mono_now();
  for (const std::uint32_t m : view.liveness().vessels()) {
    in.heard_age[m] = view.liveness().age(m, mono);
    in.silent[m] = view.liveness().silent(m);
  }
  in.roster_never_heard = view.roster().never_heard(view.liveness());
  in.silent_after = view.liveness().silent_after();
  in.conflicts = view.conflicts();
  json j = db::board_json(in, events, acks.outcomes(), wall_now());
  j["can_ack"] = can_ack;
  return j.dump();
}

int run_dashboard(DashboardArgs& a) {
  block_stop_signals();  // before Fast DDS and the HTTP server start their threads
  route_fastdds_log_to_spdlog();
  std::string host;
  int port = 0;
  if (!split_listen(a.listen, &host, &port)) {
    spdlog::error("--listen {}: expected HOST:PORT (e.g. 127.0.0.1:8080; port 0: any free one)",
                  a.listen);
    return kExitUsage;
  }
  a.m.status = true;  // the board shows each vessel's detector status
  std::unique_ptr<dds::DdsContext> ctx;
  std::unique_ptr<FleetView> view;
  CredentialExpiry expiry;
  int rc = join_fleet_domain(a.m, &ctx, &view, &expiry);
  if (rc != kExitOk) return rc;
  db::EventHistory events(a.history);
  view->on_row([&events](const Row& r) { events.add(r); });
  Acks acks(*ctx, *view, a.m);
  Hub hub;
  hub.publish(make_board(*view, events, acks, !a.read_only));

  httplib::Server svr;
  svr.new_task_queue = [] { return new httplib::ThreadPool(32); };
  routes(svr, hub, a);
  const int bound =
      port == 0 ? svr.bind_to_any_port(host) : (svr.bind_to_port(host, port) ? port : -1);
  if (bound < 0) {
    spdlog::error("cannot listen on {}: the address is not this host's or the port is taken",
                  a.listen);
    return kExitFailure;
  }
  std::thread http([&svr] { svr.listen_after_bind(); });
  spdlog::info("dashboard on http://{}:{}/ ({}; DDS domain {}): running",
               host.find(':') != std::string::npos ? "[" + host + "]" : host, bound,
               a.read_only ? "read-only" : "operators may acknowledge", ctx->config().domain_id);

  double last_board = mono_now();
  for (;;) {
    bool changed = view->poll(0.1);
    for (const db::AckWork& w : hub.take_asked()) acks.ask(w);
    changed = acks.turn() || changed;
    const double now = mono_now();
    if (changed || now - last_board >= 1.0) {
      hub.publish(make_board(*view, events, acks, !a.read_only));
      last_board = now;
    }
    if (expiry.expired(wall_now())) {
      spdlog::error("{}", expired_message(expiry));
      rc = kExitFailure;
      break;
    }
    if (wait_for_stop_signal(0.0) != 0) break;
  }
  hub.stop();
  svr.stop();
  http.join();
  spdlog::info("dashboard stopped: {} event(s) seen", events.size());
  return rc;
}

}  // namespace

void register_dashboard_command(CommandRegistry& registry) {
  static DashboardArgs args;
  CLI::App* sub =
      registry.add("dashboard",
                   "the shore's fleet board in a browser: every vessel's latched faults (IEC 62923 "
                   "presentation), the events, acknowledgements",
                   [] { return run_dashboard(args); });
  add_dds_options(sub, &args.m.dds);
  sub->add_option("--listen", args.listen, "HTTP address HOST:PORT (port 0: any free port, logged)")
      ->capture_default_str();
  sub->add_flag("--read-only", args.read_only,
                "observers only: no acknowledge button, acknowledgements refused (403)");
  sub->add_option("--mmsi", args.m.mmsi, "only these vessels (repeatable)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_option("--silent-after", args.m.silent_after,
                  "mark a vessel silent when nothing has been received from it for this long [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--roster", args.m.roster,
                  "file of the fleet's MMSIs: a roster vessel never heard is shown")
      ->check(CLI::ExistingFile);
  sub->add_option("--history", args.history, "events kept in the event list")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  sub->add_option("--ack-timeout", args.m.ack_timeout,
                  "wait this long for the sidecar's confirmation of an acknowledgement [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--discovery-timeout", args.m.discovery_timeout,
                  "wait this long for a vessel's acknowledgement reader [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

}  // namespace usvfdi::app
