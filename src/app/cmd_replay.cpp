// usv-fdi replay --config FILE --input FILE.csv|FILE.nmea [--format csv|nmea] [--output FILE.jsonl]
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "commands.hpp"
#include "open_output.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/io/nmea_log.hpp"
#include "usv_fdi/io/output_file.hpp"
#include "usv_fdi/io/replay.hpp"

namespace usvfdi::app {
namespace {

struct ReplayArgs {
  std::string config;
  std::string input;
  std::string output;                 ///< empty or "-": stdout
  std::string format = "auto";        ///< auto (by the extension), csv or nmea
  std::optional<double> nmea_rate;    ///< NMEA: sentence cycle and sample rate [Hz]
  std::string nmea_hold = "max-age";  ///< NMEA: max-age (zero-order hold) or due
  io::ReplayOptions options;
};

/// Whether the input is an NMEA log: --format nmea, or --format auto and a .nmea extension.
bool is_nmea(const ReplayArgs& a) {
  if (a.format != "auto") return a.format == "nmea";
  const std::string ext = ".nmea";
  return a.input.size() > ext.size() &&
         a.input.compare(a.input.size() - ext.size(), ext.size(), ext) == 0;
}

/// Logs the NMEA lines that could not be used; an error (kExitRejected) when they are most of
/// the lines, or when no sample could be assembled from the log.
int report_nmea_lines(const std::string& file, const io::NmeaLineStats& st, std::size_t samples) {
  std::string first;
  std::size_t first_line = 0;
  for (const auto& [reason, c] : st.reasons) {
    if (first_line == 0 || c.first_line < first_line) {
      first_line = c.first_line;
      first = fmt::format("{}:{}: {}: {}", file, c.first_line, reason, c.first_text);
    }
  }
  const std::string what =
      st.unusable == 0
          ? std::string()
          : fmt::format("{} of {} lines ({:.1f} %) unusable: {}; the first: {}", st.unusable,
                        st.lines, 100.0 * static_cast<double>(st.unusable) / st.lines,
                        st.describe(), first);
  if (2 * st.unusable > st.lines || samples == 0) {
    spdlog::error("{}: {}{}. Detection did not see most of the recording (exit {})", file,
                  what.empty() ? fmt::format("no sample in {} lines", st.lines) : what,
                  samples == 0 && !what.empty() ? " (no sample assembled)" : "",
                  static_cast<int>(kExitRejected));
    return kExitRejected;
  }
  if (!what.empty()) spdlog::warn("{}: {}", file, what);
  spdlog::info(
      "{}: {} lines: {} used (ROT, RSA, VBW, VTG), {} ignored (other sentences), {} "
      "unusable",
      file, st.lines, st.used, st.ignored, st.unusable);
  return kExitOk;
}

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

  const bool nmea = is_nmea(a);
  std::unique_ptr<io::CsvSampleReader> csv;
  std::unique_ptr<io::NmeaSampleReader> log;
  try {
    if (nmea) {
      io::NmeaInputOptions o;
      o.b2 = cfg.B(1);
      if (a.nmea_rate) {
        o.grid_rate_hz = *a.nmea_rate;
        o.cycle_rate_hz = a.nmea_rate;
      }
      o.max_age_s = std::max(1.0, 2.5 / o.grid_rate_hz);
      o.hold_until_due = a.nmea_hold == "due";
      log = std::make_unique<io::NmeaSampleReader>(a.input, o);
    } else {
      csv = std::make_unique<io::CsvSampleReader>(a.input);
    }
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
    sum =
        nmea ? io::replay(cfg, *log, writer, a.options) : io::replay(cfg, *csv, writer, a.options);
  } catch (const io::InputError& e) {
    spdlog::error("{} (the records of the {} rows before it were written)", e.what(),
                  nmea ? log->rows() : csv->rows());
    code = kExitInput;
  }
  try {
    output->commit();  // also after an input error: its records and summary are the output
  } catch (const io::OutputError& e) {
    spdlog::error("{}", e.what());
    return kExitOutput;
  }
  for (const std::string& w : sum.warnings) spdlog::warn("{}: {}", a.input, w);
  if (nmea && log->first_tag_ms()) {
    const std::int64_t ms = *log->first_tag_ms();
    const std::time_t secs = static_cast<std::time_t>(ms / 1000);
    std::tm utc{};
    char when[32] = "?";
    if (::gmtime_r(&secs, &utc) != nullptr) std::strftime(when, sizeof when, "%FT%T", &utc);
    spdlog::info("{}: t = 0 is the first TAG time c: {}.{:03d}Z (UNIX {} ms)", a.input, when,
                 static_cast<int>(ms % 1000), ms);
  }
  if (code == kExitOk && nmea) code = report_nmea_lines(a.input, log->stats(), log->rows());
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
        "{}, unknown {}), estimate {}converged (convergence lost {} times), {} samples frozen",
        a.input, sum.samples, sum.duration_s, sum.rejected, sum.events, sum.raised[0],
        sum.raised[1], sum.raised[2], sum.converged ? "" : "not ", sum.unconvergences,
        sum.frozen_samples);
  }
  return code;
}

}  // namespace

void register_replay_command(CommandRegistry& registry) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* sub = registry.add(
      "replay",
      "Replay a CSV of samples (columns t,v,r,delta) or an NMEA 0183 / IEC 61162-450 log "
      "(ROT, RSA, VBW, VTG; chosen by the .nmea extension or --format nmea) through the FDI "
      "engine and write JSON Lines records (event, estimate, summary). Exit codes: 2 config "
      "error, 3 input error, 4 output error (also: the output is the input or the config "
      "file), 5 most rows rejected (time missing or not increasing) or most NMEA lines "
      "unusable.",
      [args] { return run_replay(*args); });
  sub->add_option("--config", args->config, "engine configuration (YAML)")->required();
  sub->add_option("--input", args->input,
                  "input CSV (header with t,v,r,delta), or NMEA log (*.nmea or --format nmea)")
      ->required();
  sub->add_option("--format", args->format,
                  "input format: auto (nmea for a file name ending in .nmea, else csv), csv, nmea")
      ->check(CLI::IsMember({"auto", "csv", "nmea"}))
      ->capture_default_str();
  sub->add_option("--nmea-rate", args->nmea_rate,
                  "NMEA: rate of the assembled samples [Hz] (default 10), and the sentence rate "
                  "that times a log without TAG block times (c:): one cycle per repeated "
                  "sentence")
      ->check(CLI::PositiveNumber);
  sub->add_option("--nmea-hold", args->nmea_hold,
                  "NMEA: how values are put on the sample grid: max-age (the latest at or before "
                  "the grid time, held up to the max age: zero-order hold) or due (each at the "
                  "grid time nearest it, never twice once its sentence's next is overdue, the "
                  "period learned from the log: a lost sentence is a gap)")
      ->check(CLI::IsMember({"due", "max-age"}))
      ->capture_default_str();
  sub->add_option("--output", args->output, "output JSON Lines file (default: stdout)");
  sub->add_option("--estimate-period", args->options.estimate_period,
                  "data time between estimate records [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--signals", args->options.signal_period,
                  "also write a signal record (J_N per channel, its thresholds, C_a, C_g) every "
                  "S seconds of data time, for usv-fdi plot (default 0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_flag("--auto-ack", args->options.auto_ack,
                "acknowledge every event at once (latches return to normal when clear)");
}

}  // namespace usvfdi::app
