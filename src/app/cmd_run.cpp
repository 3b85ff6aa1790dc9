// usv-fdi run: the FDI sidecar of one vessel on Fast DDS.
#include <spdlog/async.h>
#include <spdlog/spdlog.h>

#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "credentials.hpp"
#include "dds_options.hpp"
#include "usv_fdi/dds_service/health.hpp"
#include "usv_fdi/dds_service/service.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/metrics/metrics.hpp"

namespace usvfdi::app {
namespace {

/// Exit code when another sidecar holds the state directory's lock for this MMSI
/// (EX_TEMPFAIL: it may start once the other one has stopped). Documented in docs/dds.md.
constexpr int kExitStateInUse = 75;

struct RunArgs {
  DdsCli dds;
  std::optional<std::uint32_t> mmsi;
  std::optional<std::string> state_dir;
  bool no_state = false;
  std::string health_file;
  std::string metrics;
  const CLI::App* root = nullptr;
};

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// Writes the health file (if one is configured), logging a failure once per distinct error.
class HealthWriter {
 public:
  HealthWriter(std::string path, std::uint32_t mmsi, double period) : path_(std::move(path)) {
    r_.mmsi = mmsi;
    r_.pid = static_cast<long>(::getpid());
    r_.period = period;
    // A thread that has not gone round its loop for this long is stalled (an idle one goes
    // round every 50-100 ms; a DDS write blocks at most 100 ms).
    r_.stall_limit = std::max(5.0, 3.0 * period);
  }
  bool enabled() const { return !path_.empty(); }
  void write(const std::string& state, const std::string& reason,
             const dds_service::FdiService* svc = nullptr) {
    if (!enabled()) return;
    r_.time = unix_now();
    r_.state = state;
    r_.reason = reason;
    if (svc != nullptr) {
      const pipeline::PipelineStatus st = svc->status();
      r_.live = svc->liveness();
      r_.samples = st.samples;
      r_.converged = st.estimate.converged;
      r_.armed = st.isolation.armed;
      r_.input_flags = st.input_flags;
      r_.identification_paused = st.identification_paused;
      r_.isolation_paused = st.isolation_paused;
      r_.dropped = st.dropped_inputs + st.dropped_ident + st.dropped_output;
      r_.fault_event_readers = svc->matches().event_readers;
      r_.state_file = svc->state_file();
      r_.state_error = svc->state_error();
      if (state == "running") dds_service::judge_threads(&r_);
    }
    if (r_.state == "failed" && r_.reason != logged_failure_) {
      spdlog::error("health: {}", r_.reason);
      logged_failure_ = r_.reason;
    }
    std::string error;
    if (!dds_service::write_health_file(path_, r_, &error)) {
      if (error != logged_error_) spdlog::error("health file: {}", error);
      logged_error_ = error;
    } else if (!logged_error_.empty()) {
      spdlog::info("health file {} written again", path_);
      logged_error_.clear();
    }
  }

 private:
  std::string path_;
  dds_service::HealthReport r_;
  std::string logged_error_, logged_failure_;
};

/// The sidecar logs through spdlog's asynchronous logger: every thread (the pipeline's, Fast
/// DDS's, the main one waiting for SIGTERM) only puts the line in a bounded queue; one
/// logging thread writes stderr. When stderr is not read (a pipe nobody drains), that thread
/// blocks in write(2) and the queue overflows, dropping its oldest lines (counted): detection,
/// publishing and the reaction to signals go on. At exit the queue is given a bounded time to
/// drain; if stderr still does not take it, the process exits without waiting for it.
class AsyncLogging {
 public:
  static constexpr std::size_t kQueue = 8192;  ///< lines

  AsyncLogging() : sync_(spdlog::default_logger()) {
    pool_ = std::make_shared<spdlog::details::thread_pool>(kQueue, 1);
    auto logger = std::make_shared<spdlog::async_logger>(
        sync_->name(), sync_->sinks().begin(), sync_->sinks().end(), pool_,
        spdlog::async_overflow_policy::overrun_oldest);
    logger->set_level(sync_->level());
    spdlog::set_default_logger(logger);
  }
  /// Lines dropped because the queue was full.
  std::size_t dropped() const { return pool_->overrun_counter(); }
  /// Waits (at most `timeout` s) until the queue is written, then goes back to the
  /// synchronous logger. False: stderr does not take it (the caller must not wait for the
  /// logging thread: it exits with _exit).
  bool finish(double timeout) {
    const auto end = std::chrono::steady_clock::now() +
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double>(timeout));
    while (pool_->queue_size() > 0) {
      if (std::chrono::steady_clock::now() >= end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    const spdlog::level::level_enum level = spdlog::default_logger()->level();
    spdlog::default_logger()->flush();  // queued behind the last line
    while (pool_->queue_size() > 0) {
      if (std::chrono::steady_clock::now() >= end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    sync_->set_level(level);
    spdlog::set_default_logger(sync_);
    pool_.reset();  // joins the logging thread, which has written everything
    return true;
  }

 private:
  std::shared_ptr<spdlog::logger> sync_;
  std::shared_ptr<spdlog::details::thread_pool> pool_;
};

void log_line(int level, const std::string& msg) {
  switch (level) {
    case 0:
      spdlog::debug("{}", msg);
      break;
    case 1:
      spdlog::info("{}", msg);
      break;
    case 2:
      spdlog::warn("{}", msg);
      break;
    default:
      spdlog::error("{}", msg);
      break;
  }
}

/// The sidecar's configuration: --config, then the command line's overrides. Returns kExitOk,
/// or kExitConfig after logging why it does not fit.
int load_run_config(const RunArgs& a, dds_service::ServiceConfig* out) {
  dds_service::ServiceConfig& cfg = *out;
  try {
    cfg = dds_service::load_service_config(a.dds.config);
    cfg.dds = make_dds_config(a.dds, &cfg.reliable_inputs);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  if (a.mmsi) cfg.mmsi = *a.mmsi;
  if (a.state_dir) {
    cfg.state_dir = *a.state_dir;
    cfg.state_dir_explicit = true;
  }
  if (a.no_state) {
    cfg.state_dir.clear();
    cfg.state_dir_explicit = true;
  }
  if (!a.health_file.empty()) cfg.health_file = a.health_file;
  if (!a.metrics.empty()) cfg.metrics = a.metrics;
  if (cfg.mmsi == 0) {
    spdlog::error("{}: service.mmsi is not set (give the vessel's MMSI there or with --mmsi)",
                  a.dds.config);
    return kExitConfig;
  }
  // service.log_level applies unless --log-level was given on the command line.
  if (a.root == nullptr || a.root->get_option("--log-level")->count() == 0) {
    spdlog::set_level(spdlog::level::from_str(cfg.log_level));
  }
  return kExitOk;
}

/// Creates the service (every DDS entity, the pipeline) and reads the credentials' validity.
/// Returns kExitOk, or the exit code after logging (and writing to the health file) why not.
int create_service(const dds_service::ServiceConfig& cfg, HealthWriter* health,
                   std::unique_ptr<dds_service::FdiService>* svc, CredentialExpiry* expiry) {
  try {
    *svc = std::make_unique<dds_service::FdiService>(cfg, log_line);
  } catch (const dds_service::StateInUse& e) {
    // Not a word to the health file: it is the running sidecar's (same configuration).
    spdlog::error("refusing to start: {}", e.what());
    return kExitStateInUse;
  } catch (const std::exception& e) {
    spdlog::error("cannot start the DDS service: {}", e.what());
    health->write("failed", std::string("cannot start the DDS service: ") + e.what());
    return kExitFailure;
  }
  try {  // Fast DDS checks it at the handshake only: watched while running
    *expiry = credential_expiry(cfg.dds.participant_profile);
  } catch (const std::exception& e) {
    spdlog::error("DDS Security: {}", e.what());
    health->write("failed", std::string("DDS Security: ") + e.what());
    return kExitConfig;
  }
  if (expiry->secure()) spdlog::info("{}", validity_message(*expiry));
  return kExitOk;
}

void log_started(const dds_service::ServiceConfig& cfg, const dds_service::FdiService& svc) {
  spdlog::info(
      "sidecar for MMSI {} (incarnation {}) on DDS domain {} (participant profile {}, QoS {}, "
      "{} inputs, status made every {:g} s and sent {}, state {}, health file {}): waiting for "
      "INS and rudder",
      cfg.mmsi, svc.incarnation(), cfg.dds.domain_id, cfg.dds.participant_profile,
      cfg.dds.profiles_file,
      cfg.input == dds_service::InputSource::kNmea ? "NMEA 0183 over UDP"
      : cfg.reliable_inputs                        ? "RELIABLE"
                                                   : "BEST_EFFORT",
      cfg.pipeline.status_period,
      cfg.uplink.event ? fmt::format("on change with a {:g} s heartbeat", cfg.uplink.heartbeat)
                       : std::string("every time"),
      svc.state_file().empty() ? std::string("not persisted") : svc.state_file(),
      cfg.health_file.empty() ? std::string("none") : cfg.health_file);
}

/// The Prometheus endpoint (service.metrics), or nullptr when none is configured or it cannot
/// listen (logged: the sidecar runs on without it, since its alarms matter more).
std::unique_ptr<metrics::SidecarMetrics> start_metrics(const dds_service::ServiceConfig& cfg) {
  if (cfg.metrics.empty()) return nullptr;
  try {
    auto m = std::make_unique<metrics::SidecarMetrics>(cfg.metrics, cfg.mmsi);
    const std::vector<int> ports = m->ports();
    const std::string host = cfg.metrics.substr(0, cfg.metrics.rfind(':'));
    spdlog::info("metrics: http://{}:{}/metrics", host, ports.empty() ? 0 : ports.front());
    return m;
  } catch (const std::exception& e) {
    spdlog::error("{} (service.metrics / --metrics; the sidecar runs without metrics)", e.what());
    return nullptr;
  }
}

/// Runs until SIGINT or SIGTERM (*sig), writing the health file every status period and
/// logging every change of the matched endpoints. Returns kExitOk, or kExitFailure (the
/// service stopped) when the credentials expire.
int watch_until_signal(dds_service::FdiService* svc, HealthWriter* health,
                       metrics::SidecarMetrics* metrics, const CredentialExpiry& expiry,
                       double period, int* sig) {
  dds_service::FdiService::Matches seen;
  auto last_health = std::chrono::steady_clock::now();
  while ((*sig = wait_for_stop_signal(std::min(0.5, period))) == 0) {
    const auto now = std::chrono::steady_clock::now();
    if (expiry.expired(unix_now())) {
      spdlog::error("{}", expired_message(expiry));
      health->write("failed", expired_message(expiry));
      svc->stop();
      return kExitFailure;
    }
    if (std::chrono::duration<double>(now - last_health).count() >= period) {
      last_health = now;
      health->write("running", "", svc);
    }
    if (metrics != nullptr) metrics->update(svc->status(), svc->liveness());
    const dds_service::FdiService::Matches m = svc->matches();
    if (m != seen) {
      spdlog::info(
          "matched: {} INS writer(s), {} rudder writer(s), {} speed writer(s), {} ack writer(s), "
          "{} fault-event reader(s), {} status reader(s)",
          m.ins_writers, m.rudder_writers, m.speed_writers, m.ack_writers, m.event_readers,
          m.status_readers);
      seen = m;
    }
  }
  return kExitOk;
}

/// Stops the service after signal `sig` and logs what it did.
void stop_service(int sig, dds_service::FdiService* svc, HealthWriter* health,
                  const AsyncLogging& logging) {
  const auto t0 = std::chrono::steady_clock::now();
  spdlog::info("signal {}: stopping", sig);
  health->write("stopped", "signal " + std::to_string(sig));
  svc->stop();
  const pipeline::PipelineStatus st = svc->status();
  spdlog::info(
      "stopped in {:.3f} s ({} samples, {} rejected, dropped: {} input, {} identification, {} "
      "output; {} samples of other vessels skipped; {} log lines dropped)",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), st.samples,
      st.rejected, st.dropped_inputs, st.dropped_ident, st.dropped_output, svc->foreign_samples(),
      logging.dropped());
}

int run_service(const RunArgs& a, const AsyncLogging& logging) {
  // SIGINT/SIGTERM are blocked (run_service_logged) before any thread exists and received
  // with sigtimedwait below: no signal handler, so nothing runs in signal context.
  route_fastdds_log_to_spdlog();
  dds_service::ServiceConfig cfg;
  int rc = load_run_config(a, &cfg);
  if (rc != kExitOk) return rc;
  const double period = cfg.pipeline.status_period;
  HealthWriter health(cfg.health_file, cfg.mmsi, period);
  health.write("starting", "creating the DDS participant");
  std::unique_ptr<dds_service::FdiService> svc;
  CredentialExpiry expiry;
  rc = create_service(cfg, &health, &svc, &expiry);
  if (rc != kExitOk) return rc;
  svc->start();
  health.write("running", "", svc.get());
  log_started(cfg, *svc);
  const std::unique_ptr<metrics::SidecarMetrics> metrics = start_metrics(cfg);
  int sig = 0;
  rc = watch_until_signal(svc.get(), &health, metrics.get(), expiry, period, &sig);
  if (rc != kExitOk) return rc;
  stop_service(sig, svc.get(), &health, logging);
  return kExitOk;
}

/// Seconds the log queue may take to reach stderr at exit.
constexpr double kLogDrainAtExit = 2.0;

int run_service_logged(const RunArgs& a) {
  // Blocked before the logging thread exists too: a thread that does not block SIGTERM may
  // be the one the kernel hands it to, and its default action ends the process (exit 143,
  // nothing saved; once in about a hundred stops on a loaded machine).
  block_stop_signals();
  AsyncLogging logging;
  const int code = run_service(a, logging);
  // Everything is stopped and saved; only the log may be stuck behind an unread stderr.
  // Exit without touching stdio: ThreadSanitizer's _exit interceptor flushes stderr first,
  // which waits for the stdio lock that the blocked logging thread holds.
  if (!logging.finish(kLogDrainAtExit)) ::syscall(SYS_exit_group, code);
  return code;
}

}  // namespace

void register_run_command(CommandRegistry& registry) {
  static RunArgs args;
  args.root = &registry.root();
  CLI::App* sub = registry.add("run", "run the FDI sidecar of one vessel on Fast DDS",
                               [] { return run_service_logged(args); });
  add_dds_options(sub, &args.dds);
  sub->get_option("--config")->required();
  sub->add_option("--mmsi", args.mmsi, "the vessel's MMSI (overrides service.mmsi)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_flag("--reliable-inputs", args.dds.reliable,
                "RELIABLE INS and rudder readers (pair with sim --publish --reliable)");
  sub->add_option("--state-dir", args.state_dir,
                  "directory of the latched-fault journal (overrides service.state_dir; default "
                  "/var/lib/usv-fdi if it exists); created if missing");
  sub->add_flag("--no-state", args.no_state,
                "do not persist latched faults (they will not survive a restart)")
      ->excludes("--state-dir");
  sub->add_option("--health-file", args.health_file,
                  "rewrite this JSON file every status period for `usv-fdi health` (overrides "
                  "service.health_file)");
  sub->add_option("--metrics", args.metrics,
                  "serve Prometheus metrics on HOST:PORT, GET /metrics (overrides "
                  "service.metrics; port 0: any free port, logged)")
      ->check(CLI::Validator(
          [](const std::string& s) {
            return dds_service::is_host_port(s)
                       ? std::string()
                       : "must be HOST:PORT (port 0-65535), got '" + s + "'";
          },
          "HOST:PORT"));
}

}  // namespace usvfdi::app
