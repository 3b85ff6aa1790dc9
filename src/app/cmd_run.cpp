// usv-fdi run: the FDI sidecar of one vessel on Fast DDS.
#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "dds_options.hpp"
#include "usv_fdi/dds_service/service.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::app {
namespace {

struct RunArgs {
  DdsCli dds;
  std::optional<std::uint32_t> mmsi;
  const CLI::App* root = nullptr;
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

int run_service(const RunArgs& a) {
  // SIGINT/SIGTERM are blocked before any DDS or pipeline thread exists and received with
  // sigtimedwait below: no signal handler, so nothing runs in signal context.
  block_stop_signals();
  route_fastdds_log_to_spdlog();
  service::ServiceConfig cfg;
  try {
    cfg = service::load_service_config(a.dds.config);
    cfg.dds = make_dds_config(a.dds, &cfg.reliable_inputs);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  if (a.mmsi) cfg.mmsi = *a.mmsi;
  if (cfg.mmsi == 0) {
    spdlog::error("{}: service.mmsi is not set (give the vessel's MMSI there or with --mmsi)",
                  a.dds.config);
    return kExitConfig;
  }
  // service.log_level applies unless --log-level was given on the command line.
  if (a.root == nullptr || a.root->get_option("--log-level")->count() == 0) {
    spdlog::set_level(spdlog::level::from_str(cfg.log_level));
  }
  std::unique_ptr<service::FdiService> svc;
  try {
    svc = std::make_unique<service::FdiService>(cfg, log_line);
  } catch (const std::exception& e) {
    spdlog::error("cannot start the DDS service: {}", e.what());
    return kExitFailure;
  }
  svc->start();
  spdlog::info(
      "sidecar for MMSI {} on DDS domain {} (participant profile {}, QoS {}, {} inputs, "
      "status every {:g} s): waiting for INS and rudder",
      cfg.mmsi, cfg.dds.domain_id, cfg.dds.participant_profile, cfg.dds.profiles_file,
      cfg.reliable_inputs ? "RELIABLE" : "BEST_EFFORT", cfg.pipeline.status_period);
  int sig = 0;
  service::FdiService::Matches seen;
  while ((sig = wait_for_stop_signal(0.5)) == 0) {
    const service::FdiService::Matches m = svc->matches();
    if (m != seen) {
      spdlog::info(
          "matched: {} INS writer(s), {} rudder writer(s), {} ack writer(s), {} "
          "fault-event reader(s), {} status reader(s)",
          m.ins_writers, m.rudder_writers, m.ack_writers, m.event_readers, m.status_readers);
      seen = m;
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  spdlog::info("signal {}: stopping", sig);
  svc->stop();
  const PipelineStatus st = svc->status();
  spdlog::info(
      "stopped in {:.3f} s ({} samples, {} rejected, dropped: {} input, {} identification, {} "
      "output; {} samples of other vessels skipped)",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), st.samples,
      st.rejected, st.dropped_inputs, st.dropped_ident, st.dropped_output, svc->foreign_samples());
  return kExitOk;
}

}  // namespace

void register_run_command(CommandRegistry& registry) {
  static RunArgs args;
  args.root = &registry.root();
  CLI::App* sub = registry.add("run", "run the FDI sidecar of one vessel on Fast DDS",
                               [] { return run_service(args); });
  add_dds_options(sub, &args.dds);
  sub->get_option("--config")->required();
  sub->add_option("--mmsi", args.mmsi, "the vessel's MMSI (overrides service.mmsi)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_flag("--reliable-inputs", args.dds.reliable,
                "RELIABLE INS and rudder readers (pair with sim --publish --reliable)");
}

}  // namespace usvfdi::app
