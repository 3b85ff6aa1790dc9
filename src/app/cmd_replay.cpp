// usv-fdi replay --config FILE --input FILE.csv [--output FILE.jsonl]
#include <spdlog/spdlog.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/io/replay.hpp"

namespace usvfdi::app {
namespace {

struct ReplayArgs {
  std::string config;
  std::string input;
  std::string output;  ///< empty or "-": stdout
  io::ReplayOptions options;
};

int run_replay(const ReplayArgs& a) {
  EngineConfig cfg;
  try {
    cfg = io::load_engine_config(a.config);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }

  std::unique_ptr<io::CsvSampleReader> input;
  try {
    input = std::make_unique<io::CsvSampleReader>(a.input);
  } catch (const io::InputError& e) {
    spdlog::error("{}", e.what());
    return kExitInput;
  }

  std::ofstream file;
  const bool to_stdout = a.output.empty() || a.output == "-";
  if (!to_stdout) {
    file.open(a.output, std::ios::binary | std::ios::trunc);
    if (!file) {
      spdlog::error("{}: cannot open for writing", a.output);
      return kExitOutput;
    }
  }
  std::ostream& os = to_stdout ? std::cout : file;
  io::JsonlWriter writer(os);

  int code = kExitOk;
  io::RunSummary sum;
  try {
    sum = io::replay(cfg, *input, writer, a.options);
  } catch (const io::InputError& e) {
    spdlog::error("{} (the records of the {} rows before it were written)", e.what(),
                  input->rows());
    code = kExitInput;
  }
  os.flush();
  if (!os) {
    spdlog::error("{}: write failed", to_stdout ? std::string("stdout") : a.output);
    return kExitOutput;
  }
  if (code == kExitOk) {
    spdlog::info(
        "{}: {} samples over {:.1f} s ({} rejected), {} events (raised: accelerometer {}, gyro "
        "{}, unknown {}), estimate {}converged, {} samples frozen",
        a.input, sum.samples, sum.duration_s, sum.rejected, sum.events, sum.raised[0],
        sum.raised[1], sum.raised[2], sum.converged ? "" : "not ", sum.frozen_samples);
  }
  return code;
}

}  // namespace

void register_replay_command(CommandRegistry& registry) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* sub = registry.add(
      "replay",
      "Replay a CSV of samples (columns t,v,r,delta) through the FDI engine and write JSON "
      "Lines records (event, estimate, summary). Exit codes: 2 config error, 3 input error, "
      "4 output error.",
      [args] { return run_replay(*args); });
  sub->add_option("--config", args->config, "engine configuration (YAML)")->required();
  sub->add_option("--input", args->input, "input CSV (header with t,v,r,delta)")->required();
  sub->add_option("--output", args->output, "output JSON Lines file (default: stdout)");
  sub->add_option("--estimate-period", args->options.estimate_period,
                  "data time between estimate records [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--auto-ack", args->options.auto_ack,
                "acknowledge every event at once (latches return to normal when clear)");
}

}  // namespace usvfdi::app
