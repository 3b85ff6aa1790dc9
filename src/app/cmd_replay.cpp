// usv-fdi replay --config FILE --input FILE.csv [--output FILE.jsonl]
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "commands.hpp"
#include "open_output.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/io/output_file.hpp"
#include "usv_fdi/io/replay.hpp"

namespace usvfdi::app {
namespace {

struct ReplayArgs {
  std::string config;
  std::string input;
  std::string output;  ///< empty or "-": stdout
  io::ReplayOptions options;
};

/// An error message when the output would overwrite an input, else empty.
std::string output_conflict(const ReplayArgs& a) {
  const bool to_stdout = a.output.empty() || a.output == "-";
  const std::pair<const char*, const std::string*> inputs[] = {{"input", &a.input},
                                                               {"configuration", &a.config}};
  for (const auto& [role, p] : inputs) {
    if (to_stdout ? io::same_file(STDOUT_FILENO, *p) : io::same_file(a.output, *p)) {
      return (to_stdout ? std::string("stdout") : a.output) + ": is the same file as the " + role +
             " " + *p + " (refusing to overwrite it; choose another --output)";
    }
  }
  return {};
}

/// Warns about rejected rows; an error (kExitRejected) when they are most of the input.
int report_rejections(const std::string& file, const io::RunSummary& sum) {
  if (sum.duplicates > 0) {
    spdlog::warn(
        "{}: {} of {} rows repeat the previous row exactly (a sample recorded twice): dropped; "
        "the first: {}:{}",
        file, sum.duplicates, sum.samples, file, sum.first_duplicate_line);
  }
  if (sum.rejected == 0) return kExitOk;
  std::string first = fmt::format("{}:{}", file, sum.first_rejected_line);
  if (std::isfinite(sum.first_rejected_t)) {
    first += fmt::format(" has t = {:.17g}", sum.first_rejected_t);
    if (std::isfinite(sum.first_rejected_after)) {
      first += fmt::format(", not after t = {:.17g}", sum.first_rejected_after);
    }
  } else {
    first += " has no valid time";
  }
  const std::string what = fmt::format(
      "{} of {} rows ({:.1f} %) rejected (time not after the previous row's: {}, no valid time: "
      "{}); the first: {}",
      sum.rejected, sum.samples, 100.0 * static_cast<double>(sum.rejected) / sum.samples,
      sum.rejected - sum.rejected_no_time, sum.rejected_no_time, first);
  if (2 * sum.rejected > sum.samples) {
    spdlog::error("{}: {}. Detection did not see most of the recording (exit {})", file, what,
                  static_cast<int>(kExitRejected));
    return kExitRejected;
  }
  spdlog::warn("{}: {}", file, what);
  return kExitOk;
}

int run_replay(const ReplayArgs& a) {
  if (const std::string conflict = output_conflict(a); !conflict.empty()) {
    spdlog::error("{}", conflict);
    return kExitOutput;
  }
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

  const std::unique_ptr<io::OutputFile> output = open_output(a.output);
  if (output == nullptr) return kExitOutput;
  io::JsonlWriter writer(output->stream());

  int code = kExitOk;
  io::RunSummary sum;
  try {
    sum = io::replay(cfg, *input, writer, a.options);
  } catch (const io::InputError& e) {
    spdlog::error("{} (the records of the {} rows before it were written)", e.what(),
                  input->rows());
    code = kExitInput;
  }
  try {
    output->commit();  // also after an input error: its records and summary are the output
  } catch (const io::OutputError& e) {
    spdlog::error("{}", e.what());
    return kExitOutput;
  }
  for (const std::string& w : sum.warnings) spdlog::warn("{}: {}", a.input, w);
  if (code == kExitOk) code = report_rejections(a.input, sum);
  if ((code == kExitOk || code == kExitRejected) && !sum.not_converged.empty()) {
    spdlog::warn(
        "{}: after {:.1f} s of data the estimate of A has {} (detection is armed only "
        "after convergence)",
        a.input, sum.duration_s, sum.not_converged);
  }
  if (code == kExitOk || code == kExitRejected) {
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
      "4 output error (also: the output is the input or the config file), 5 most rows "
      "rejected (time missing or not increasing).",
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
