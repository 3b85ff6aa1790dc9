// Command-line options shared by the DDS subcommands (run, monitor, sim --publish). No Fast DDS
// in this header: DdsConfig is only declared (include usv_fdi/dds/dds_context.hpp to use it).
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace usvfdi::dds {
struct DdsConfig;
}  // namespace usvfdi::dds

namespace usvfdi::app {

struct DdsCli {
  std::string config;  ///< service YAML (its service: section), optional
  std::optional<std::uint32_t> domain;
  std::string qos;
  std::string participant_profile;
  std::vector<std::string> partitions;
  bool reliable = false;
};

/// Adds --config, --domain, --qos, --participant-profile, --partition.
void add_dds_options(CLI::App* sub, DdsCli* cli, bool with_config = true);

/// The DDS settings: from --config's service section if given, then the explicit options.
/// Throws usvfdi::io::ConfigError for a bad config file.
usvfdi::dds::DdsConfig make_dds_config(const DdsCli& cli, bool* reliable_inputs = nullptr);

/// Blocks SIGINT and SIGTERM in the calling thread and every thread it creates afterwards,
/// so that wait_for_stop_signal() can receive them with sigtimedwait (no handler, no I/O in
/// signal context). Call first thing, before any thread exists.
void block_stop_signals();
/// Waits up to timeout_s for SIGINT/SIGTERM; returns the signal number, or 0 on timeout.
int wait_for_stop_signal(double timeout_s);

/// Routes Fast DDS's own log (by default printed to stdout, where it would corrupt
/// `monitor --json`) to spdlog on stderr: Error -> error, Warning -> warn, Info -> debug.
void route_fastdds_log_to_spdlog();

}  // namespace usvfdi::app
