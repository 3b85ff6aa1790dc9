// usv-fdi dashboard: the shore's fleet board in a browser. A DDS participant like `monitor`
// (the same FleetView: late-join aware FaultEvent reader, FdiStatus for liveness, instance
// ownership), plus an HTTP server (cpp-httplib) on a configurable address that serves the page
// carried in the binary (dashboard/web/), the board as JSON (/api/board), the board pushed on
// every change and once a second (server-sent events, /api/stream) and acknowledgements
// (/api/ack, written as FaultAck by the DDS thread, their outcome shown on the board), and the
// fleet's Prometheus metrics (/metrics, refreshed once a second). With an accounts file every
// request carries HTTP Basic credentials (operators acknowledge under their own name, observers
// only look); with a certificate and key it serves HTTPS.
//
// Threads: the main thread owns DDS and the fleet view; the HTTP server's threads see only the
// Hub (the latest board as text, and the queue of acknowledgements asked for).
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <iterator>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "ack_protocol.hpp"
#include "commands.hpp"
#include "credentials.hpp"
#include "dashboard/accounts.hpp"
#include "dashboard/board.hpp"
#include "dashboard/metrics.hpp"
#include "dashboard/vessel_history.hpp"
#include "dashboard_assets.hpp"
#include "dashboard_vendor.hpp"
#include "dds_options.hpp"
#include "fleet_view.hpp"
#include "usv_fdi/core/text.hpp"
#include "usv_fdi/io/output_file.hpp"

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
  std::size_t chart_points = 300;  ///< statuses kept per vessel for its page's charts
  std::string accounts;            ///< accounts file (dashboard/accounts.hpp); "" none: no sign-in
  std::string tls_cert, tls_key;   ///< PEM files: HTTPS when both are given
  bool tls() const { return !tls_cert.empty(); }
};

/// What the HTTP threads share with the DDS thread: the boards (deltas, and the whole board
/// when a page or GET /api/board asks for it) and the acks asked for.
class Hub {
 public:
  /// A new board, as the change from the one before (every live page's next message), and
  /// its revision (BoardFramer::revision(): one more than the last).
  void publish_delta(std::uint64_t revision, std::string delta) {
    {
      std::lock_guard<std::mutex> l(m_);
      version_ = revision;
      deltas_.emplace_back(version_, std::move(delta));
      while (deltas_.size() > kDeltas) deltas_.pop_front();
    }
    cv_.notify_all();
  }
  /// The whole board as of the latest delta, built because someone asked (full_wanted()).
  void publish_full(std::string full) {
    {
      std::lock_guard<std::mutex> l(m_);
      full_ = std::move(full);
      full_version_ = version_;
      want_full_ = false;
    }
    cv_.notify_all();
  }
  /// Whether a page or a request waits for the whole board (the DDS thread builds it then).
  bool full_wanted() {
    std::lock_guard<std::mutex> l(m_);
    return want_full_;
  }
  /// Waits up to `timeout` for a board newer than *seen; true and the server-sent events that
  /// bring a page from board *seen to the newest: the deltas since, or, for a page that has no
  /// board yet or is further behind than the deltas kept, the whole board and the deltas after
  /// it (the whole board is asked of the DDS thread when the last one built is too old).
  bool next(std::uint64_t* seen, std::string* out, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> l(m_);
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (stop_) return false;
      if (version_ > *seen) {
        out->clear();
        if (*seen > 0 && kept_after(*seen)) {
          append_deltas_after(*seen, out);
          *seen = version_;
          return true;
        }
        if (full_version_ > 0 && kept_after(full_version_) &&
            version_ - full_version_ <= kFullLag) {
          *out = "data: " + full_ + "\n\n";
          append_deltas_after(full_version_, out);
          *seen = version_;
          return true;
        }
        want_full_ = true;
      }
      if (cv_.wait_until(l, until) == std::cv_status::timeout) return false;
    }
  }
  /// The whole board as of now (GET /api/board): asks the DDS thread for it and waits up to
  /// `timeout` (then the last one built).
  std::string current(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> l(m_);
    const std::uint64_t asked = version_;
    if (full_version_ < asked) {
      want_full_ = true;
      cv_.wait_for(l, timeout, [&] { return stop_ || full_version_ >= asked; });
    }
    return full_;
  }
  void set_metrics(std::string text) {
    std::lock_guard<std::mutex> l(m_);
    metrics_ = std::move(text);
  }
  std::string metrics() {
    std::lock_guard<std::mutex> l(m_);
    return metrics_;
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
  /// Queues an ack for the DDS thread; false when too many wait already.
  bool ask(db::AckWork w) {
    std::lock_guard<std::mutex> l(m_);
    if (acks_.size() >= kMaxQueued) return false;
    acks_.push_back(std::move(w));
    return true;
  }
  /// A live stream holds an HTTP thread: at most kMaxStreams at once, so that pages and
  /// acknowledgements always find one.
  bool open_stream() {
    std::lock_guard<std::mutex> l(m_);
    if (streams_ >= kMaxStreams) return false;
    ++streams_;
    return true;
  }
  void close_stream() {
    std::lock_guard<std::mutex> l(m_);
    --streams_;
  }

  static constexpr std::size_t kMaxQueued = 100;
  static constexpr int kMaxStreams = 24;
  static constexpr int kThreads = 32;
  std::vector<db::AckWork> take_asked() {
    std::lock_guard<std::mutex> l(m_);
    std::vector<db::AckWork> out;
    out.swap(acks_);
    return out;
  }

 private:
  /// Whether the deltas after version v are all kept.
  bool kept_after(std::uint64_t v) const {
    return v == version_ || (!deltas_.empty() && deltas_.front().first <= v + 1);
  }
  void append_deltas_after(std::uint64_t v, std::string* out) const {
    for (const auto& [version, delta] : deltas_) {
      if (version > v) *out += "data: " + delta + "\n\n";
    }
  }

  std::mutex m_;
  std::condition_variable cv_;
  std::string full_ = "{}";
  std::uint64_t full_version_ = 0;  ///< the delta the whole board is as of (0: none yet)
  bool want_full_ = false;
  std::deque<std::pair<std::uint64_t, std::string>> deltas_;  ///< (version, delta), newest last
  static constexpr std::size_t kDeltas = 16;
  /// A page that joins takes the last whole board with at most this many deltas after it;
  /// older: a new one is built.
  static constexpr std::uint64_t kFullLag = 4;
  std::string metrics_;
  std::uint64_t version_ = 0;
  bool stop_ = false;
  int streams_ = 0;
  std::vector<db::AckWork> acks_;
};

void reply_json(httplib::Response& res, int status, const json& j) {
  res.status = status;
  res.set_content(j.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

/// The Host values a request may carry (empty: any, when listening on every address): a page
/// served under another name (DNS rebinding) gets nothing.
std::set<std::string> allowed_hosts(const std::string& host, int port) {
  if (host.empty() || host == "0.0.0.0" || host == "::") return {};
  const std::string p = ":" + std::to_string(port);
  std::set<std::string> out{(host.find(':') != std::string::npos ? "[" + host + "]" : host) + p};
  if (host == "127.0.0.1" || host == "::1" || host == "localhost") {
    out.insert({"localhost" + p, "127.0.0.1" + p, "[::1]" + p});
  }
  return out;
}

/// Who asks: the account its credentials prove (with an accounts file), or the anonymous user
/// of a dashboard without accounts (name ""; an operator unless the dashboard is read-only).
std::optional<db::Account> requester(db::Authenticator* auth, const httplib::Request& req) {
  if (auth == nullptr) return db::Account{"", db::Role::kOperator, ""};
  return auth->check(req.get_header_value("Authorization"));
}

void routes(httplib::Server& svr, Hub& hub, const DashboardArgs& a,
            const std::set<std::string>& hosts, db::Authenticator* auth,
            const db::VesselHistory& curves) {
  svr.set_payload_max_length(4096);  // an ack request is a few dozen bytes
  svr.set_keep_alive_timeout(1);
  svr.set_pre_routing_handler([hosts, auth](const httplib::Request& req, httplib::Response& res) {
    if (!hosts.empty() && hosts.count(req.get_header_value("Host")) == 0) {
      reply_json(res, 421,
                 {{"error", "this dashboard does not serve the host '" +
                                escape_text(req.get_header_value("Host")) + "'"}});
      return httplib::Server::HandlerResponse::Handled;
    }
    // With accounts, nothing (page, board, stream, metrics, acks) without valid credentials.
    if (auth != nullptr) {
      const db::Authenticator::Result r = auth->authenticate(req.get_header_value("Authorization"));
      if (r.account) return httplib::Server::HandlerResponse::Unhandled;
      if (r.busy) {
        res.set_header("Retry-After", "1");
        reply_json(res, 503, {{"error", "too many sign-ins being checked; try again"}});
        return httplib::Server::HandlerResponse::Handled;
      }
      if (req.has_header("Authorization")) {
        spdlog::warn("refused {} {} from {}: wrong name or password (for '{}')", req.method,
                     escape_text(req.path), req.remote_addr, escape_text(r.tried));
      }
      res.set_header("WWW-Authenticate", "Basic realm=\"usv-fdi dashboard\", charset=\"UTF-8\"");
      reply_json(res, 401, {{"error", "sign in with a dashboard account"}});
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // Every answer: not to be framed by another site (a hidden Acknowledge button), no sniffing
  // of types; with TLS, browsers keep to HTTPS.
  const bool tls = a.tls();
  svr.set_post_routing_handler([tls](const httplib::Request&, httplib::Response& res) {
    res.set_header("X-Frame-Options", "DENY");
    res.set_header("X-Content-Type-Options", "nosniff");
    if (!res.has_header("Content-Security-Policy")) {
      res.set_header("Content-Security-Policy", "default-src 'self'; frame-ancestors 'none'");
    }
    if (tls) res.set_header("Strict-Transport-Security", "max-age=31536000");
  });
  const auto page = [](const char* body, const char* type) {
    return [body, type](const httplib::Request&, httplib::Response& res) {
      res.set_header("Content-Security-Policy", "default-src 'self'; frame-ancestors 'none'");
      res.set_header("Cache-Control", "no-cache");
      res.set_content(body, type);
    };
  };
  svr.Get("/", page(db::assets::kIndexHtml, "text/html; charset=utf-8"));
  svr.Get("/index.html", page(db::assets::kIndexHtml, "text/html; charset=utf-8"));
  svr.Get("/app.js", page(db::assets::kAppJs, "text/javascript; charset=utf-8"));
  svr.Get("/style.css", page(db::assets::kStyleCss, "text/css; charset=utf-8"));
  svr.Get("/vessel.html", page(db::assets::kVesselHtml, "text/html; charset=utf-8"));
  svr.Get("/vessel.js", page(db::assets::kVesselJs, "text/javascript; charset=utf-8"));
  svr.Get("/common.js", page(db::assets::kCommonJs, "text/javascript; charset=utf-8"));
  if (db::vendor::kHaveCharts) {
    svr.Get("/uplot.js", page(db::vendor::kUplotJs, "text/javascript; charset=utf-8"));
    svr.Get("/uplot.css", page(db::vendor::kUplotCss, "text/css; charset=utf-8"));
  }
  // A vessel's curves: its statuses later than `since` [s, the source time of a status].
  svr.Get("/api/vessel", [&curves](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    std::uint32_t mmsi = 0;
    double since = 0.0;
    try {
      std::size_t used = 0;
      const std::string m = req.get_param_value("mmsi");
      const unsigned long v = std::stoul(m, &used);
      if (used != m.size() || m[0] == '-' || v < 1 || v > 999999999) throw std::out_of_range(m);
      mmsi = static_cast<std::uint32_t>(v);
    } catch (const std::exception&) {
      reply_json(res, 400, {{"error", "mmsi: a vessel's MMSI (1 to 999999999) is required"}});
      return;
    }
    if (req.has_param("since")) {
      try {
        std::size_t used = 0;
        const std::string t = req.get_param_value("since");
        since = std::stod(t, &used);
        if (used != t.size() || !std::isfinite(since)) throw std::invalid_argument(t);
      } catch (const std::exception&) {
        reply_json(res, 400, {{"error", "since: a time in seconds (the last point's t)"}});
        return;
      }
    }
    json j;
    if (!curves.to_json(mmsi, since, &j)) {
      reply_json(res, 404,
                 {{"error", "no status of vessel " + std::to_string(mmsi) +
                                " has reached this dashboard yet"}});
      return;
    }
    reply_json(res, 200, j);
  });
  svr.Get("/favicon.ico",
          [](const httplib::Request&, httplib::Response& res) { res.status = 204; });
  svr.Get("/api/board", [&hub](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    res.set_content(hub.current(std::chrono::milliseconds(2000)), "application/json");
  });
  // Who the page's user is and whether they may acknowledge.
  svr.Get("/api/me", [auth, &a](const httplib::Request& req, httplib::Response& res) {
    const std::optional<db::Account> who = requester(auth, req);
    const bool can_ack = who && who->role == db::Role::kOperator && !a.read_only;
    res.set_header("Cache-Control", "no-cache");
    // (an operator on a read-only dashboard stays an operator who cannot acknowledge here)
    reply_json(res, 200,
               {{"name", who && !who->name.empty() ? json(who->name) : json(nullptr)},
                {"role", who && !a.read_only ? db::to_string(who->role) : "observer"},
                {"can_ack", can_ack}});
  });
  svr.Get("/metrics", [&hub](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    res.set_content(hub.metrics(), "text/plain; version=0.0.4; charset=utf-8");
  });
  svr.Get("/api/stream", [&hub](const httplib::Request&, httplib::Response& res) {
    if (!hub.open_stream()) {
      res.set_header("Retry-After", "5");
      reply_json(res, 503, {{"error", "too many live pages on this dashboard"}});
      return;
    }
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    auto seen = std::make_shared<std::uint64_t>(0);
    res.set_chunked_content_provider(
        "text/event-stream",
        [&hub, seen](std::size_t, httplib::DataSink& sink) {
          std::string msgs;
          if (hub.next(seen.get(), &msgs, std::chrono::milliseconds(2000))) {
            return sink.write(msgs.data(), msgs.size());
          }
          if (hub.stopped()) {
            sink.done();
            return true;
          }
          static const std::string keepalive = ": keepalive\n\n";
          return sink.write(keepalive.data(), keepalive.size());
        },
        [&hub](bool) { hub.close_stream(); });
  });
  svr.Post("/api/ack", [&hub, &a, auth](const httplib::Request& req, httplib::Response& res) {
    if (a.read_only) {
      reply_json(res, 403,
                 {{"error", "this dashboard is read-only (observers cannot acknowledge)"}});
      spdlog::warn("refused an acknowledgement from {}: the dashboard is read-only",
                   req.remote_addr);
      return;
    }
    const std::optional<db::Account> who = requester(auth, req);
    if (!who || who->role != db::Role::kOperator) {
      const std::string name = who ? escape_text(who->name) : std::string("?");
      reply_json(
          res, 403,
          {{"error", "the account '" + name + "' is an observer: observers cannot acknowledge"}});
      spdlog::warn("refused an acknowledgement from {}: the account {} is an observer",
                   req.remote_addr, name);
      return;
    }
    // JSON only (a cross-site form or a "simple" fetch cannot send it without the browser
    // asking first, and nothing here allows that), and from this dashboard's own page.
    const std::string origin = req.get_header_value("Origin");
    const std::string scheme = a.tls() ? "https://" : "http://";
    if (!origin.empty() && origin != scheme + req.get_header_value("Host")) {
      reply_json(res, 403, {{"error", "acknowledgements come from this dashboard's own page"}});
      spdlog::warn("refused an acknowledgement from {}: origin {}", req.remote_addr,
                   escape_text(origin));
      return;
    }
    if (req.get_header_value("Content-Type").rfind("application/json", 0) != 0) {
      reply_json(res, 415, {{"error", "the body must be application/json"}});
      return;
    }
    db::AckWork w;
    std::string why;
    std::string body = req.body;
    if (auth != nullptr) {
      // Signed in: the acknowledgement is the account's, whatever name the body gives.
      json j = json::parse(body, nullptr, false);
      if (j.is_object()) {
        j["operator"] = who->name;
        body = j.dump();
      }
    }
    if (!db::parse_ack_body(body, &w, &why)) {
      reply_json(res, 400, {{"error", why}});
      spdlog::warn("refused an acknowledgement request from {}: {}", req.remote_addr,
                   escape_text(why));
      return;
    }
    if (!hub.ask(std::move(w))) {
      reply_json(res, 429, {{"error", "too many acknowledgements waiting; try again"}});
      return;
    }
    reply_json(res, 202, {{"queued", true}});
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

/// The acknowledgements the DDS thread sends and follows until the sidecar's answer. An ack is
/// "accepted" only when the instance's next event (sequence + 1) is an acknowledged state whose
/// message names this operator (the sidecar writes "acknowledged by <operator>"); "refused" when
/// the sidecar will not take it (stale sequence, nothing to acknowledge: refusal_reason) or the
/// next event is something else; "unconfirmed" when no answer came within --ack-timeout (it is
/// still watched for kWatch s, and settled if the answer comes).
class Acks {
 public:
  static constexpr std::size_t kMaxPending = 100;
  static constexpr double kWatch = 60.0;  ///< [s] an unconfirmed ack is still watched this long
  static constexpr double kMatchSettle = 1.0;  ///< [s] a new writer's first ack waits this long

  Acks(dds::DdsContext& ctx, FleetView& view, const MonitorArgs& a)
      : ctx_(ctx), view_(view), a_(a) {}

  void ask(const db::AckWork& w) {
    Pending p;
    p.work = w;
    p.work.operator_id = w.operator_id.substr(0, 63);
    p.id = ++next_id_;
    p.asked = mono_now();
    db::AckOutcome o;
    o.mmsi = w.req.mmsi;
    o.sensor = w.req.sensor;
    o.sequence = w.req.sequence;
    o.operator_id = p.work.operator_id;
    o.sent = wall_now();
    o.state = "pending";
    outcomes_.push_front({p.id, o});
    while (outcomes_.size() > 100) outcomes_.pop_back();
    spdlog::info("ack asked from the dashboard: MMSI {} {} #{} by {}", w.req.mmsi,
                 to_string(w.req.sensor), w.req.sequence, escape_text(p.work.operator_id));
    for (const Pending& q : pending_) {
      if (q.work.req.mmsi == w.req.mmsi && q.work.req.sensor == w.req.sensor &&
          q.work.req.sequence == w.req.sequence && q.state == "pending") {
        settle(p.id, "refused",
               "an acknowledgement of this event by " + escape_text(q.work.operator_id) +
                   " is already on its way");
        return;
      }
    }
    if (pending_.size() >= kMaxPending) {
      settle(p.id, "refused", "too many acknowledgements waiting for an answer");
      return;
    }
    pending_.push_back(p);
  }

  /// Every fault event the view shows (FleetView::on_row): the sidecar's answers.
  void on_event(const Row& r) {
    for (Pending& p : pending_) {
      const AckRequest& req = p.work.req;
      if (p.written < 0 || r.mmsi != req.mmsi || r.ev.sensor != req.sensor ||
          r.ev.sequence <= req.sequence || p.state == "done") {
        continue;
      }
      const bool acked =
          r.ev.state == FaultState::kActiveAcknowledged || r.ev.state == FaultState::kAcknowledged;
      if (r.ev.sequence == req.sequence + 1 && acked &&
          db::acknowledged_by(r.ev.message, escape_text(p.work.operator_id))) {
        settle(p.id, "accepted", "");
      } else if (r.ev.sequence == req.sequence + 1) {
        settle(p.id, "refused",
               "the event moved on to #" + std::to_string(r.ev.sequence) + " " +
                   to_string(r.ev.state) + ": " + escape_text(r.ev.message));
      } else {
        settle(p.id, "unconfirmed",
               "the event moved on to #" + std::to_string(r.ev.sequence) +
                   " before its answer was seen");
      }
      p.state = "done";
      changed_ = true;
    }
  }

  /// Writes what can be written, times out what is not answered. True if an outcome changed.
  bool turn() {
    bool changed = changed_;
    changed_ = false;
    const double now = mono_now();
    for (auto it = pending_.begin(); it != pending_.end();) {
      if (it->state != "done") step(&*it, now, &changed);
      const bool over = it->state == "done" || (it->written >= 0 && now - it->written >= kWatch);
      it = over ? pending_.erase(it) : it + 1;
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
    double asked = 0.0;             ///< [mono s]
    double written = -1;            ///< [mono s]; < 0: not yet
    std::string state = "pending";  ///< pending, unconfirmed (still watched) or done
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
        spdlog::warn("ack {} by {} {}: {}", who, escape_text(o.operator_id),
                     state == "refused" ? "not accepted" : "unconfirmed", reason);
      }
    }
  }

  /// One pending ack: written once its instance is known and a sidecar reads acks; timed out.
  void step(Pending* p, double now, bool* changed) {
    const AckRequest& req = p->work.req;
    const RowKey key{req.mmsi, static_cast<int>(req.sensor)};
    const Row* row = view_.row(key);
    if (p->written < 0) {
      // No writer before the instance is known: a request for any MMSI must not make one.
      fdds::DataWriter* w = row == nullptr ? nullptr : writer(req.mmsi);
      fdds::PublicationMatchedStatus st;
      if (w != nullptr) w->get_publication_matched_status(st);
      if (row == nullptr || w == nullptr || st.current_count == 0) {
        matched_at_.erase(req.mmsi);  // a sidecar matched again later waits again
        if (now - p->asked < a_.discovery_timeout && (row == nullptr || w != nullptr)) return;
        settle(p->id, "refused",
               row == nullptr ? "no latched event of this vessel and sensor is known here"
               : w == nullptr ? "cannot write acknowledgements to this vessel (see the log)"
                              : "no sidecar of this vessel subscribes to acknowledgements");
        p->state = "done";
        *changed = true;
        return;
      }
      // The writer matched the sidecar's reader; the sidecar may not have matched the writer yet
      // (its side of discovery, under DDS Security its side of the handshake, comes later), and a
      // volatile ack written before that is lost: a new writer waits kMatchSettle first.
      const auto m = matched_at_.emplace(req.mmsi, now).first;
      if (now - m->second < kMatchSettle) return;
      if (ack_already_past(req, row)) {
        settle(p->id, "refused", refusal_reason(req, row));
        p->state = "done";
        *changed = true;
        return;
      }
      fdi::FaultAck ack;
      ack.mmsi(req.mmsi);
      ack.sensor(static_cast<std::uint8_t>(req.sensor));
      ack.sequence(req.sequence);
      ack.operator_id(p->work.operator_id.c_str());
      ack.stamp(wall_now());
      ack.incarnation(row->ev.incarnation);
      dds::write(*w, ack);
      p->written = now;
      return;
    }
    if (p->state == "pending" && now - p->written >= a_.ack_timeout) {
      settle(p->id, "unconfirmed",
             fmt::format("no answer from the sidecar within {:g} s ({})", a_.ack_timeout,
                         refusal_reason(req, row)));
      p->state = "unconfirmed";
      *changed = true;
    }
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
  std::map<std::uint32_t, double> matched_at_;  ///< when a vessel's writer first matched [mono s]
  std::vector<Pending> pending_;
  std::deque<std::pair<std::uint64_t, db::AckOutcome>> outcomes_;
  std::uint64_t next_id_ = 0;
  bool changed_ = false;
};

bool same_row(const Row& a, const Row& b) {
  return a.ev.sequence == b.ev.sequence && a.ev.incarnation == b.ev.incarnation &&
         a.ev.state == b.ev.state && a.written == b.written && a.alive == b.alive &&
         a.writer == b.writer;
}
bool same_status(const VesselStatus& a, const VesselStatus& b) {
  return a.written == b.written && a.alive == b.alive && a.writer == b.writer;
}

/// Brings `mine` (kept between boards) to what the view shows: copies the samples that
/// changed, drops those the view no longer shows, and adds their vessels to *touched.
template <class K, class V, class Same>
void refresh(const InstanceOwners<K, V>& view, std::map<K, V>* mine, Same same,
             std::set<std::uint32_t>* touched) {
  const auto vessel = [](const K& k) -> std::uint32_t {
    if constexpr (std::is_same_v<K, RowKey>) {
      return k.first;
    } else {
      return k;
    }
  };
  std::size_t shown = 0;
  view.for_each([&](const K& k, const V& v) {
    ++shown;
    const auto it = mine->find(k);
    if (it == mine->end()) {
      mine->emplace(k, v);
    } else if (!same(it->second, v)) {
      it->second = v;
    } else {
      return;
    }
    touched->insert(vessel(k));
  });
  if (shown == mine->size()) return;
  std::set<K> keys;
  view.for_each([&](const K& k, const V&) { keys.insert(k); });
  for (auto it = mine->begin(); it != mine->end();) {
    if (keys.count(it->first) > 0) {
      ++it;
      continue;
    }
    touched->insert(vessel(it->first));
    it = mine->erase(it);
  }
}

/// Brings `in` (kept between boards) to the fleet view: the rows and statuses that changed
/// (their vessels into *touched), the liveness, the roster and the counts afresh. (Copying the
/// whole view, 1000 vessels, took 4-8 ms on every change.)
void refresh_board_input(const FleetView& view, db::BoardInput* in,
                         std::set<std::uint32_t>* touched) {
  refresh(view.rows(), &in->rows, same_row, touched);
  if (view.vessels() != nullptr) refresh(*view.vessels(), &in->statuses, same_status, touched);
  const double mono = mono_now();
  in->heard_age.clear();
  in->silent.clear();
  for (const std::uint32_t m : view.liveness().vessels()) {
    in->heard_age[m] = view.liveness().age(m, mono);
    in->silent[m] = view.liveness().silent(m);
  }
  in->roster_never_heard = view.roster().never_heard(view.liveness());
  in->silent_after = view.liveness().silent_after();
  in->conflicts = view.conflicts();
}

/// The DDS thread's loop: the fleet view, the acks, the board; until a stop signal or the
/// credentials expire. Returns the exit code.
int serve(const DashboardArgs& a, FleetView& view, const db::EventHistory& events, Acks& acks,
          Hub& hub, db::BoardFramer& framer, db::BoardInput& in, const CredentialExpiry& expiry) {
  double last_board = mono_now(), last_metrics = last_board;
  std::set<std::uint32_t> touched;
  for (;;) {
    bool changed = view.poll(0.1);
    for (const db::AckWork& w : hub.take_asked()) acks.ask(w);
    changed = acks.turn() || changed;
    const double now = mono_now();
    const bool board = changed || now - last_board >= 1.0, metrics = now - last_metrics >= 1.0;
    if (board || metrics) {
      refresh_board_input(view, &in, &touched);
      if (board) {
        std::string delta =
            framer.delta(in, &touched, events, acks.outcomes(), wall_now(), !a.read_only);
        hub.publish_delta(framer.revision(), std::move(delta));
        touched.clear();
        last_board = now;
      }
      // The metrics once a second (a scrape is seconds apart), not on every change.
      if (metrics) {
        hub.set_metrics(db::fleet_metrics(in, events, acks.outcomes()));
        last_metrics = now;
      }
    }
    // The whole board only when a page that joins or GET /api/board asks for it.
    if (hub.full_wanted()) {
      hub.publish_full(framer.full(in, events, acks.outcomes(), wall_now(), !a.read_only));
    }
    if (expiry.expired(wall_now())) {
      spdlog::error("{}", expired_message(expiry));
      return kExitFailure;
    }
    if (wait_for_stop_signal(0.0) != 0) return kExitOk;
  }
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
  if (a.tls_cert.empty() != a.tls_key.empty()) {
    spdlog::error("--tls-cert and --tls-key go together (HTTPS needs the certificate and its key)");
    return kExitUsage;
  }
  for (const std::string* f : {&a.tls_cert, &a.tls_key}) {
    if (!f->empty() && !std::ifstream(*f).good()) {
      spdlog::error("{} {}: cannot read it", f == &a.tls_cert ? "--tls-cert" : "--tls-key", *f);
      return kExitUsage;
    }
  }
  std::unique_ptr<db::Authenticator> auth;
  if (!a.accounts.empty()) {
    try {
      auth = std::make_unique<db::Authenticator>(db::load_accounts(a.accounts));
    } catch (const std::exception& e) {
      spdlog::error("--accounts: {}", e.what());
      return kExitUsage;
    }
    std::error_code ec;
    const auto perms = std::filesystem::status(a.accounts, ec).permissions();
    const auto shared = std::filesystem::perms::others_read | std::filesystem::perms::group_read;
    if (!ec && (perms & shared) != std::filesystem::perms::none) {
      spdlog::warn(
          "--accounts {}: other users of this host may read the password hashes "
          "(chmod 600)",
          a.accounts);
    }
    const bool loopback = host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
    if (!a.tls() && !loopback) {
      spdlog::error(
          "--accounts on {} without --tls-cert/--tls-key: passwords would cross the network in "
          "clear; give a certificate and key, or listen on a loopback address",
          a.listen);
      return kExitUsage;
    }
  }
  a.m.status = true;  // the board shows each vessel's detector status
  std::unique_ptr<dds::DdsContext> ctx;
  std::unique_ptr<FleetView> view;
  CredentialExpiry expiry;
  int rc = join_fleet_domain(a.m, &ctx, &view, &expiry);
  if (rc != kExitOk) return rc;
  db::EventHistory events(a.history);
  Acks acks(*ctx, *view, a.m);
  db::VesselHistory curves(a.chart_points);
  view->on_status([&curves](const VesselStatus& v) { curves.add(v); });
  view->on_row([&events, &acks](const Row& r) {
    events.add(r);
    acks.on_event(r);
  });
  Hub hub;
  db::BoardFramer framer;
  db::BoardInput in;  // the fleet view as the board last saw it (refresh_board_input)
  {
    std::set<std::uint32_t> touched;
    refresh_board_input(*view, &in, &touched);
    std::string delta =
        framer.delta(in, nullptr, events, acks.outcomes(), wall_now(), !a.read_only);
    hub.publish_delta(framer.revision(), std::move(delta));
    hub.publish_full(framer.full(in, events, acks.outcomes(), wall_now(), !a.read_only));
    hub.set_metrics(db::fleet_metrics(in, events, acks.outcomes()));
  }

  std::unique_ptr<httplib::Server> server;
  if (a.tls()) {
    auto ssl = std::make_unique<httplib::SSLServer>(a.tls_cert.c_str(), a.tls_key.c_str());
    if (!ssl->is_valid()) {
      spdlog::error("--tls-cert {} / --tls-key {}: not a PEM certificate and its private key",
                    a.tls_cert, a.tls_key);
      return kExitUsage;
    }
    server = std::move(ssl);
  } else {
    server = std::make_unique<httplib::Server>();
  }
  httplib::Server& svr = *server;
  svr.new_task_queue = [] { return new httplib::ThreadPool(Hub::kThreads); };
  const int bound =
      port == 0 ? svr.bind_to_any_port(host) : (svr.bind_to_port(host, port) ? port : -1);
  if (bound < 0) {
    spdlog::error("cannot listen on {}: the address is not this host's or the port is taken",
                  a.listen);
    return kExitFailure;
  }
  routes(svr, hub, a, allowed_hosts(host, bound), auth.get(), curves);
  std::thread http([&svr] { svr.listen_after_bind(); });
  // svr.stop() does nothing before the server runs: wait for it (bounded) so that a stop joins.
  for (int i = 0; i < 500 && !svr.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  spdlog::info("dashboard on {}://{}:{}/ ({}; {}; DDS domain {}): running",
               a.tls() ? "https" : "http",
               host.find(':') != std::string::npos ? "[" + host + "]" : host, bound,
               a.read_only ? "read-only" : "operators may acknowledge",
               auth ? std::to_string(auth->size()) + " account(s) from " + a.accounts
                    : std::string("no sign-in"),
               ctx->config().domain_id);
  try {
    rc = serve(a, *view, events, acks, hub, framer, in, expiry);
  } catch (const std::exception& e) {
    spdlog::error("dashboard: {}", e.what());
    rc = kExitFailure;
  }
  hub.stop();
  svr.stop();
  http.join();
  spdlog::info("dashboard stopped: {} event(s) seen", events.size());
  return rc;
}

struct AccountArgs {
  std::string name;
  std::string role = "operator";
  unsigned iterations = db::kDefaultIterations;
  std::string file;  ///< append to this accounts file (made if missing) instead of printing
};

/// usv-fdi dashboard-account: reads a password (the first line of stdin; typed without echo on
/// a terminal) and prints the account's entry for the accounts file, the password salted and
/// hashed.
termios g_saved_tty{};
bool g_tty_quiet = false;

/// Ctrl-C (or a stop) while the password is typed without echo: echo back on, then the default.
void restore_tty_and_die(int sig) {
  if (g_tty_quiet) tcsetattr(STDIN_FILENO, TCSAFLUSH, &g_saved_tty);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

/// Reads one line of stdin; on a terminal, prompted on stderr and typed without echo.
bool read_secret(const std::string& prompt, bool tty, std::string* out) {
  if (tty) {
    std::cerr << prompt << std::flush;
    if (tcgetattr(STDIN_FILENO, &g_saved_tty) == 0) {
      termios quiet = g_saved_tty;
      quiet.c_lflag &= ~static_cast<tcflag_t>(ECHO);
      std::signal(SIGINT, restore_tty_and_die);
      std::signal(SIGTERM, restore_tty_and_die);
      std::signal(SIGQUIT, restore_tty_and_die);
      g_tty_quiet = tcsetattr(STDIN_FILENO, TCSAFLUSH, &quiet) == 0;
    }
  }
  const bool got = static_cast<bool>(std::getline(std::cin, *out));
  if (tty) {
    if (g_tty_quiet) tcsetattr(STDIN_FILENO, TCSAFLUSH, &g_saved_tty);
    g_tty_quiet = false;
    std::cerr << "\n";
  }
  if (!out->empty() && out->back() == '\r') out->pop_back();
  return got;
}

/// Writes `text` to `path` through io::OutputFile (a temporary file beside it, fsynced and
/// renamed over it: the old file is never half written), made 0600 before anything is written
/// (the hashes are never readable by others). False, *why saying what failed, on failure.
bool replace_file(const std::string& path, const std::string& text, std::string* why) {
  try {
    io::OutputFile f(path == "-" ? "./-" : path);  // a file named "-", not standard output
    struct stat st {};
    if (::fstat(f.fd(), &st) == 0 && S_ISREG(st.st_mode) && ::fchmod(f.fd(), 0600) != 0) {
      *why = "cannot make " + path + " readable by its owner only: " + std::strerror(errno);
      return false;
    }
    f.stream() << text;
    f.commit();
    return true;
  } catch (const io::OutputError& e) {
    *why = e.what();
    return false;
  }
}

int run_dashboard_account(const AccountArgs& a) {
  if (const std::string why = db::check_account_name(a.name); !why.empty()) {
    spdlog::error("account name '{}': {}", escape_text(a.name), why);
    return kExitUsage;
  }
  std::string before;  // the accounts file as it is ("" when missing or blank)
  if (!a.file.empty()) {
    std::ifstream in(a.file, std::ios::binary);
    before.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (before.find_first_not_of(" \t\r\n") == std::string::npos) before.clear();
    if (!before.empty()) {
      try {
        if (db::load_accounts(a.file).count(a.name) > 0) {
          spdlog::error("{} has an account '{}' already (remove its entry to set a new password)",
                        a.file, escape_text(a.name));
          return kExitUsage;
        }
      } catch (const std::exception& e) {
        spdlog::error("{}", e.what());
        return kExitUsage;
      }
    }
  }
  const bool tty = isatty(STDIN_FILENO) != 0;
  std::string password, again;
  const bool got = read_secret("password for " + a.name + ": ", tty, &password);
  if (!got || password.size() < 8) {
    spdlog::error("the password (the first line of stdin) must have at least 8 characters");
    return kExitUsage;
  }
  if (tty && (!read_secret("the same again: ", tty, &again) || again != password)) {
    spdlog::error("the two passwords differ: nothing written");
    return kExitUsage;
  }
  const db::Role role = a.role == "observer" ? db::Role::kObserver : db::Role::kOperator;
  const std::string entry =
      db::account_entry(a.name, role, db::hash_password(password, a.iterations));
  if (a.file.empty()) {
    std::cout << entry;
    return kExitOk;
  }
  // The entry goes at the end of the file (the accounts list must be its last key), read back
  // before it replaces the file: a layout it cannot be appended to is said, nothing is lost.
  std::string text = before.empty() ? std::string("accounts:\n") : before;
  if (text.back() != '\n') text += '\n';
  text += entry;
  const std::string check = a.file + ".check." + std::to_string(::getpid());
  std::string why;
  bool fits = false;
  if (replace_file(check, text, &why)) {
    try {
      const auto accounts = db::load_accounts(check);
      fits = accounts.count(a.name) > 0 &&
             (before.empty() || accounts.size() == db::load_accounts(a.file).size() + 1);
    } catch (const std::exception& e) {
      why = e.what();
    }
    ::unlink(check.c_str());
  }
  if (!fits) {
    spdlog::error(
        "cannot append to {} ({}): its accounts list is not its last, block-indented key; add "
        "this entry to the list by hand:\n{}",
        a.file, why.empty() ? "the entry did not read back" : why, entry);
    return kExitFailure;
  }
  if (!replace_file(a.file, text, &why)) {
    spdlog::error("{}", why);
    return kExitFailure;
  }
  spdlog::info("{} account '{}' added to {}", to_string(role), escape_text(a.name), a.file);
  return kExitOk;
}

}  // namespace

void register_dashboard_command(CommandRegistry& registry) {
  static AccountArgs account;
  CLI::App* acc = registry.add(
      "dashboard-account",
      "print an account entry for `usv-fdi dashboard --accounts` (the password, read from stdin, "
      "stored as a salted PBKDF2-SHA256 hash)",
      [] { return run_dashboard_account(account); });
  acc->add_option("name", account.name,
                  "the account's name (what acknowledgements are signed with)")
      ->required();
  acc->add_option("--role", account.role, "operator (may acknowledge) or observer (read only)")
      ->check(CLI::IsMember({"operator", "observer"}))
      ->capture_default_str();
  acc->add_option("--file", account.file,
                  "append the entry to this accounts file (made if missing; a name already in it "
                  "is refused) instead of printing it");
  acc->add_option("--iterations", account.iterations, "PBKDF2 iterations")
      ->check(CLI::Range(1000u, 100000000u))
      ->capture_default_str();

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
  sub->add_option("--accounts", args.accounts,
                  "accounts file (YAML; entries from `usv-fdi dashboard-account`): every request "
                  "must sign in (HTTP Basic); operators acknowledge under their name, observers "
                  "only look")
      ->check(CLI::ExistingFile);
  sub->add_option("--tls-cert", args.tls_cert, "PEM certificate (chain): serve HTTPS")
      ->check(CLI::ExistingFile);
  sub->add_option("--tls-key", args.tls_key, "PEM private key of --tls-cert")
      ->check(CLI::ExistingFile);
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
  sub->add_option("--chart-points", args.chart_points,
                  "statuses kept per vessel for the curves of its page")
      ->check(CLI::Range(10, 100000))
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
