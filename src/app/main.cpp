// usv-fdi: command-line entry point. Subcommands register themselves in CommandRegistry;
// logging goes to stderr through spdlog, data to files or stdout.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include <exception>
#include <string>

#include "commands.hpp"

int main(int argc, char** argv) {
  using namespace usvfdi::app;
  CLI::App app{
      "usv-fdi: fault detection and isolation of a USV's INS (sway-velocity channel and "
      "gyro) with an unknown sway-yaw matrix A"};
  app.require_subcommand(1);
  app.fallthrough();  // global options may follow the subcommand
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "stderr log level")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();

  CommandRegistry registry(app);
  register_replay_command(registry);
  register_sim_command(registry);
  register_vessels_command(registry);
  register_plot_command(registry);
#ifdef USV_FDI_APP_WITH_DDS  // defined by src/app/CMakeLists.txt once the DDS commands exist
  register_run_command(registry);
  register_monitor_command(registry);
  register_health_command(registry);
  register_bridge_command(registry);
  register_emulate_command(registry);
  register_ros2_command(registry);
  register_dashboard_command(registry);
#endif

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  auto logger = spdlog::stderr_color_mt("usv-fdi");
  logger->set_pattern("usv-fdi: %^%l%$: %v");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::from_str(log_level));

  try {
    return registry.run_selected();
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return kExitFailure;
  }
}
