// The detection benchmark: its run list (subjects x rates x voyages x faults x seeds, and the
// recorded HSVA KVLCC2 tests), the three detectors run on the same data (the engine with
// default settings, the paper's estimator and decision as written, an oracle that is given
// A), and the aggregation into one table per subject and rate. docs/benchmark.md.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers.hpp"
#include "scoring.hpp"
#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::bench {

/// A voyage of the proving ground for a hull, without rate, length, seed or faults:
/// "course/calm" (+-10 deg course changes, ideal sensors) or "voyage/sea3/mems" (every
/// manoeuvre, sea state 3, wind, current, MEMS-grade sensors). Throws std::invalid_argument on
/// another name.
sim::VoyageConfig voyage_config(const sim::Hull& hull, const std::string& voyage);

/// The data of one run: what the detectors see, and the faults put into it.
struct Stream {
  std::vector<Sample> samples;
  std::vector<InjectedFault> faults;
};

/// One run of the benchmark. Everything a detector may use is here: B (what a user gives)
/// for the engine and the paper's method, A_ref in addition for the oracle.
struct Case {
  std::string table;    ///< table it belongs to ("mariner @ 10 Hz")
  std::string note;     ///< what the table's runs share (noise, voyages), for its heading
  std::string subject;  ///< hull or data set
  std::string voyage;   ///< scenario name
  double rate_hz = 0.0;
  std::uint64_t seed = 0;
  bool faulty = false;
  InjectedFault fault;     ///< when faulty
  double magnitude = 0.0;  ///< the injection's magnitude (channel unit, or relative for scale)
  double duration = 0.0;   ///< [s] of data
  Vec2 B = Vec2::Zero();
  Mat2 A_ref = Mat2::Zero();     ///< true or linearised A (the oracle's; the error reference)
  std::function<Stream()> make;  ///< builds the data (deterministic)
};

enum Method : int { kEngine = 0, kPaper = 1, kOracle = 2, kMethods = 3 };
const char* method_name(int m);

struct CaseResult {
  std::size_t index = 0;
  std::array<MethodResult, kMethods> m;
  std::size_t samples = 0;
  double t_first = kNaN, t_last = kNaN;
};

struct BenchOptions {
  bool quick = false;
  int jobs = 1;
  int seeds = -1;            ///< < 0: the mode's default
  std::string config_dir;    ///< the repository's config/ (default.yaml, paper.yaml)
  std::string realdata_dir;  ///< empty: no real data (say why in realdata_note)
  std::string realdata_note;
  std::string only;  ///< run only the tables whose name contains this
  bool progress = true;
  /// Give the engine the surge speed (Sample::u: the voyage's, the HSVA data's column u);
  /// false: B only, u dropped.
  bool speed = false;
  ScoreParams score;
};

/// The standard fault set on one channel, sigma the channel's noise: bias 10 sigma, stuck,
/// drift 10 sigma per 30 s, noise x8 (extra std sqrt(63) sigma), scale +50 %.
struct FaultSpec {
  FaultKind kind;
  double magnitude;
};
std::vector<FaultSpec> standard_faults(double sigma);

/// Adds a fault to recorded samples (bias, drift, noise, scale on the recorded value,
/// stuck at the value at the onset). Noise draws from seed.
void apply_fault(std::vector<Sample>* samples, const InjectedFault& f, double magnitude,
                 std::uint64_t seed);

/// The HSVA KVLCC2 tests (README in the directory): the runs, in file-name order.
struct RecordedRun {
  std::string name;
  std::vector<Sample> samples;
};
std::vector<RecordedRun> load_hsva(const std::string& dir);
/// What the detectors are given for the HSVA runs. B comes from dir/kvlcc2_model.yaml, read
/// by the engine's own loader (io::load_engine_config) exactly as a user's `--config` would
/// be; A_ref is the oracle's A: the MMG linearisation that the directory's README.md gives
/// beside that B (Yasukawa & Yoshimura 2015 at model scale, A ~ [[-0.103, -0.412],
/// [-0.090, -0.394]]).
struct HsvaModel {
  Vec2 B = Vec2::Zero();
  Mat2 A_ref = Mat2::Zero();
};
/// Throws io::ConfigError, naming the file, when dir/kvlcc2_model.yaml is missing or is not
/// a valid engine configuration.
HsvaModel load_hsva_model(const std::string& dir);
/// The runs one after another: each starts gap seconds after the previous one's last sample.
std::vector<Sample> concatenate(const std::vector<RecordedRun>& runs, double gap,
                                std::vector<double>* run_starts = nullptr);
/// The engine's floors of the residual scales (IsolationParams::sigma_floor_v, _r): a fault
/// in units of a recorded channel's sigma is sized with max(recorded_noise, floor).
Vec2 fault_sigma_floor();
/// Healthy noise of a recorded channel: 1.4826 MAD of the second difference / sqrt(6) (white
/// noise: Var(y[k+1] - 2 y[k] + y[k-1]) = 6 sigma^2; the motion's own second difference at
/// 20 Hz is far below it), pooled over the runs (within runs only).
Vec2 recorded_noise(const std::vector<RecordedRun>& runs);

/// Finds ../shared/realdata/kvlcc2-hsva from the source dir upwards; empty (and *why set)
/// when not found.
std::string find_realdata(const std::string& source_dir, std::string* why);

/// The run list of a mode.
std::vector<Case> make_cases(const BenchOptions& opt);

/// Runs the three detectors on one case.
CaseResult run_case(const Case& c, std::size_t index, const EngineConfig& engine_cfg,
                    const EngineConfig& paper_cfg, const ScoreParams& score);

/// Aggregate of one method over one table.
struct MethodSummary {
  int faults = 0, detected = 0, isolated = 0, armed_at_onset = 0, detected_armed = 0;
  int recovered = 0;
  int held = 0;  ///< faults raised on their sensor until their end (FaultScore::held)
  int false_alarms = 0;
  double healthy_hours = 0.0, healthy_armed_hours = 0.0;
  double delay_median = kNaN, delay_p95 = kNaN;
  double recovery_median = kNaN, recovery_p95 = kNaN;
  int runs = 0, armed_runs = 0;
  double arming_median = kNaN, arming_max = kNaN;    ///< over the runs that armed [s]
  double a_error_median = kNaN, a_error_p95 = kNaN;  ///< ||A^ - A||_F / ||A||_F at the end
  std::vector<std::array<int, 3>> per_kind;  ///< faults, detected, isolated per standard kind
  int false_alarms_armed = 0;                ///< those raised while detection was live
  /// The runs without a fault: their hours, the model-mismatch verdicts given on them, and
  /// the share of their samples on which identification was frozen (NaN: no identification).
  double healthy_run_hours = 0.0;
  int healthy_run_mismatches = 0;
  std::size_t healthy_run_samples = 0, healthy_run_frozen = 0;
  bool has_identification = false;
  double frozen_share() const {
    return has_identification && healthy_run_samples > 0
               ? static_cast<double>(healthy_run_frozen) / healthy_run_samples
               : kNaN;
  }
  double mismatches_per_hour() const {
    return healthy_run_hours > 0 ? healthy_run_mismatches / healthy_run_hours : kNaN;
  }
  double fa_per_hour() const { return healthy_hours > 0 ? false_alarms / healthy_hours : kNaN; }
  double fa_per_armed_hour() const {
    return healthy_armed_hours > 0 ? false_alarms_armed / healthy_armed_hours : kNaN;
  }
};

struct TableSummary {
  std::string name;
  std::string note;
  std::size_t runs = 0;
  double hours = 0.0;  ///< data [h]
  std::array<MethodSummary, kMethods> m;
};

/// The standard kinds in table order.
const std::vector<FaultKind>& standard_kinds();

std::vector<TableSummary> summarise(const std::vector<Case>& cases,
                                    const std::vector<CaseResult>& results);

/// The engine's configuration (config_dir/default.yaml) and the paper's (config_dir/paper.yaml),
/// as a user would load them; run_case puts each case's B into both. Throws io::ConfigError.
void load_configs(const std::string& config_dir, EngineConfig* engine, EngineConfig* paper);

/// Runs every case on opt.jobs threads (a progress line on stderr unless opt.progress is
/// false). Rethrows the first error of a case, naming it.
std::vector<CaseResult> run_all(const std::vector<Case>& cases, const BenchOptions& opt,
                                const EngineConfig& engine_cfg, const EngineConfig& paper_cfg);

/// Outputs. The overview: one row per table with each method's key figures.
std::string to_overview(const std::vector<TableSummary>& tables);
/// Where the faults are found and missed, over every table: one row per kind of data
/// (`data_class`), faulty sensor and standard kind.
struct BreakdownRow {
  std::string data;  ///< data_class of the runs
  Sensor sensor = Sensor::kUnknown;
  FaultKind kind = FaultKind::kUnknown;
  int faults = 0;
  /// Per method: detected, isolated, detected within kEarly of the onset, raised on the
  /// faulty sensor until the fault's end (FaultScore::held).
  std::array<std::array<int, 4>, kMethods> m{};
  static constexpr double kEarly = 15.0;  ///< [s]: a 10 sigma / 30 s ramp is at 5 sigma
};
/// The kind of data a case is: "calm" (course/calm), "sea 3, MEMS" (voyage/sea3/mems), or
/// "HSVA recorded" (the real data), else its voyage's name.
std::string data_class(const Case& c);
/// The rows ordered by data class (as first seen), sensor, kind (table order); standard kinds
/// only. Markdown only (the JSON has every run).
std::vector<BreakdownRow> breakdown(const std::vector<Case>& cases,
                                    const std::vector<CaseResult>& results);
/// The header, the overview, where the faults are missed (when rows are given), then every
/// table with its per-kind breakdown.
std::string to_markdown(const std::vector<TableSummary>& tables, const std::string& header,
                        const std::vector<BreakdownRow>& rows = {});
std::string to_json(const std::vector<Case>& cases, const std::vector<CaseResult>& results,
                    const std::vector<TableSummary>& tables, const std::string& header);

}  // namespace usvfdi::bench
