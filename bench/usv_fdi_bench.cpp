// Per-sample cost of the FDI engine (Google Benchmark).
//
//   build/bench/usv_fdi_bench                 9 repetitions, medians, summary with ratios
//   build/bench/usv_fdi_bench --benchmark_filter=otter   (any Google Benchmark flag)
//
// Every benchmark processes one sample per iteration of a realistic simulated voyage (a
// shipped vessel under its heading autopilot with its realistic INS noise, configured by
// config/vessels/<vessel>.yaml), in steady state: the estimate has converged, the isolation
// thread is armed and has learned its scales and threshold (a warm-up of the same voyage
// that is not timed). When the measured segment is used up, the state after the warm-up is
// restored (outside the timing) and the segment is replayed, so every iteration sees
// healthy steady-state data.
//
//   baseline        a trivial per-sample filter: one step of a fixed discrete 2x2 model and
//                   its residual (the least any model-based FDI must do per sample)
//   identification  Identifier::update (DREM + Kreisselmeier, the identification thread)
//   isolation       Isolator::update (observers, residual evaluation, sensor checks)
//   engine          FdiEngine::process (both, the identification gate and the latches: the
//                   whole per-sample update; issue 2's target: under 1 us on one core)
//   *_noguard       the same with identification's consistency guard off
//
// Reported: the median over repetitions of the time per sample, and at the end a summary
// with each median as a ratio to the baseline measured in the same run.
//
// csv_bench.cpp adds the replay input's cost on a simulated file (data set csv_otter_50Hz_1h,
// one row a sample): its baseline is a minimal fread + strtod parse of the same file, and the
// summary says whether the whole replay stays within 1.5x of it (issue 14).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "csv_bench.hpp"
#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::bench {
namespace {

/// A voyage split into a warm-up and a measured segment, and every component's state
/// after the warm-up.
struct Dataset {
  std::string name;
  double rate_hz = 0.0;
  std::vector<Sample> steady;
  std::unique_ptr<FdiEngine> engine;  ///< after the warm-up
  std::unique_ptr<Identifier> ident;  ///< after the warm-up, fed every warm-up sample
  std::unique_ptr<Isolator> iso;      ///< after the warm-up, fed the identifier's estimates
  std::string problem;                ///< why the data set is not in steady state
  Mat2 A_true = Mat2::Zero();
  Vec2 B = Vec2::Zero();
};

constexpr double kSteadySeconds = 600.0;

Dataset make_dataset(const std::string& vessel_name, double rate_hz, bool guard) {
  Dataset d;
  d.name = vessel_name + "_" + std::to_string(static_cast<int>(rate_hz)) + "Hz" +
           (guard ? "" : " (guard off)");
  d.rate_hz = rate_hz;
  VesselModel vessel;
  if (!find_vessel(vessel_name, &vessel)) throw std::runtime_error("no vessel " + vessel_name);
  EngineConfig cfg = io::load_engine_config(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/" +
                                            vessel_name + ".yaml");
  cfg.identification.guard = guard;
  d.A_true = vessel.A;
  d.B = cfg.B;
  // The warm-up covers convergence, observer settling and learning (as the scenario
  // scripts assume: faults start after max(300 s, 5 course changes)).
  const double warmup = std::max(300.0, 5.0 * vessel.turn_period);
  SimConfig sim;
  sim.vessel = vessel;
  sim.rate_hz = rate_hz;
  sim.seed = 2024;
  sim.steering = Steering::kAutopilot;
  sim.duration = warmup + kSteadySeconds;
  const std::vector<SimRow> rows = simulate(sim);

  d.engine = std::make_unique<FdiEngine>(cfg);
  d.ident = std::make_unique<Identifier>(cfg.identification, cfg.B);
  d.iso = std::make_unique<Isolator>(cfg.isolation, cfg.B);
  std::vector<FaultEvent> events;
  std::vector<Detection> detections;
  std::size_t warm_events = 0;
  for (const SimRow& row : rows) {
    const Sample s{row.t, row.v, row.r, row.delta};
    if (row.t < warmup) {
      events.clear();
      d.engine->process(s, &events);
      warm_events += events.size();
      detections.clear();
      d.iso->update(s, &detections);
      d.ident->update(s, d.iso->freeze_requested());
      d.iso->set_estimate(d.ident->estimate());
    } else {
      d.steady.push_back(s);
    }
  }
  const IsolatorStatus& st = d.engine->isolation_status();
  const IsolatorStatus& st2 = d.iso->status();
  if (!d.engine->estimate().converged || !d.ident->estimate().converged) {
    d.problem = "identification has not converged after the warm-up";
  } else if (!st.armed || st.learning || st.settling || !st2.armed || st2.learning ||
             st2.settling) {
    d.problem = "isolation is not armed and learned after the warm-up";
  } else if (warm_events != 0) {
    d.problem = std::to_string(warm_events) + " fault events on healthy warm-up data";
  }
  return d;
}

Dataset& dataset(const std::string& vessel, double rate_hz, bool guard = true) {
  static std::map<std::string, std::unique_ptr<Dataset>> cache;
  const std::string key = vessel + "@" + std::to_string(rate_hz) + (guard ? "" : "/noguard");
  auto it = cache.find(key);
  if (it == cache.end()) {
    it = cache.emplace(key, std::make_unique<Dataset>(make_dataset(vessel, rate_hz, guard))).first;
  }
  return *it->second;
}

/// Runs body(sample) once per iteration over the steady segment; calls restore() (untimed)
/// whenever the segment starts again.
template <typename Restore, typename Body>
void run_steady(benchmark::State& state, const Dataset& d, Restore restore, Body body) {
  if (!d.problem.empty()) {
    state.SkipWithError(("data set " + d.name + ": " + d.problem).c_str());
    return;
  }
  restore();
  std::size_t i = 0;
  const std::size_t n = d.steady.size();
  for (auto _ : state) {
    if (i == n) {
      state.PauseTiming();
      restore();
      i = 0;
      state.ResumeTiming();
    }
    body(d.steady[i]);
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

void bm_baseline(benchmark::State& state, const std::string& vessel, double rate_hz) {
  const Dataset& d = dataset(vessel, rate_hz);
  // x+ = Ad x + Bd delta (Euler discretisation of the true model), residual y - x.
  const double h = 1.0 / rate_hz;
  const Mat2 Ad = Mat2::Identity() + h * d.A_true;
  const Vec2 Bd = h * d.B;
  Vec2 x = Vec2::Zero();
  double acc = 0.0;
  run_steady(
      state, d, [&] { x.setZero(); },
      [&](const Sample& s) {
        const Vec2 y(s.v, s.r);
        const Vec2 e = y - x;
        acc += e.squaredNorm();
        x = Ad * x + Bd * s.delta + 0.1 * e;
        benchmark::DoNotOptimize(acc);
      });
}

void bm_identification(benchmark::State& state, const std::string& vessel, double rate_hz,
                       bool guard = true) {
  const Dataset& d = dataset(vessel, rate_hz, guard);
  std::unique_ptr<Identifier> ident;
  run_steady(
      state, d, [&] { ident = std::make_unique<Identifier>(*d.ident); },
      [&](const Sample& s) { benchmark::DoNotOptimize(ident->update(s, false)); });
  if (ident) {
    state.counters["a_rel_err"] = (ident->estimate().A - d.A_true).norm() / d.A_true.norm();
  }
}

void bm_isolation(benchmark::State& state, const std::string& vessel, double rate_hz) {
  const Dataset& d = dataset(vessel, rate_hz);
  std::unique_ptr<Isolator> iso;
  std::vector<Detection> out;
  out.reserve(16);
  double detections = 0;
  run_steady(
      state, d, [&] { iso = std::make_unique<Isolator>(*d.iso); },
      [&](const Sample& s) {
        out.clear();
        benchmark::DoNotOptimize(iso->update(s, &out));
        detections += static_cast<double>(out.size());
      });
  state.counters["detections"] = detections;  // healthy data: 0
}

void bm_engine(benchmark::State& state, const std::string& vessel, double rate_hz,
               bool guard = true) {
  const Dataset& d = dataset(vessel, rate_hz, guard);
  std::unique_ptr<FdiEngine> engine;
  std::vector<FaultEvent> events;
  events.reserve(16);
  double n_events = 0;
  run_steady(
      state, d, [&] { engine = std::make_unique<FdiEngine>(*d.engine); },
      [&](const Sample& s) {
        events.clear();
        benchmark::DoNotOptimize(engine->process(s, &events));
        n_events += static_cast<double>(events.size());
      });
  state.counters["events"] = n_events;  // healthy data: 0
}

/// The console output, plus a summary of the medians and their ratios to the baseline.
class SummaryReporter : public benchmark::ConsoleReporter {
 public:
  SummaryReporter() : ConsoleReporter(OO_Tabular) {}

  void ReportRuns(const std::vector<Run>& reports) override {
    ConsoleReporter::ReportRuns(reports);
    for (const Run& r : reports) {
      if (r.error_occurred) continue;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      const bool single = r.run_type == Run::RT_Iteration && r.repetitions <= 1;
      if (!median && !single) continue;
      const std::string name = r.run_name.function_name;  // "<what>/<data set>"
      if (rows_.find(name) == rows_.end()) order_.push_back(name);
      rows_[name] = {to_ns(r.GetAdjustedCPUTime(), r.time_unit),
                     to_ns(r.GetAdjustedRealTime(), r.time_unit), r.repetitions};
    }
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    if (rows_.empty()) return;
    std::ostream& out = GetOutputStream();
    char line[160];
    out << "\nSummary: medians over repetitions of the time per sample (CPU time of the "
           "benchmark thread;\nwall time in brackets); x baseline = CPU-time ratio to the "
           "baseline of the same data set\nin this run.\n";
    std::snprintf(line, sizeof line, "%-38s %14s %14s %11s %5s\n", "benchmark", "CPU ns/sample",
                  "(wall ns)", "x baseline", "reps");
    out << line;
    for (const std::string& name : order_) {
      const Row& row = rows_[name];
      const std::string set = name.substr(name.find('/') + 1);
      const auto base = rows_.find("baseline/" + set);
      char ratio[32] = "-";
      if (base != rows_.end() && base->second.cpu_ns > 0) {
        std::snprintf(ratio, sizeof ratio, "%.1f", row.cpu_ns / base->second.cpu_ns);
      }
      char wall[32];
      std::snprintf(wall, sizeof wall, "(%.1f)", row.wall_ns);
      std::snprintf(line, sizeof line, "%-38s %14.1f %14s %11s %5lld\n", name.c_str(), row.cpu_ns,
                    wall, ratio, static_cast<long long>(row.reps));
      out << line;
    }
    for (const std::string& name : order_) {
      if (name.rfind("replay/", 0) != 0) continue;
      const auto base = rows_.find("baseline/" + name.substr(name.find('/') + 1));
      if (base == rows_.end() || base->second.cpu_ns <= 0) continue;
      const double ratio = rows_[name].cpu_ns / base->second.cpu_ns;
      std::snprintf(line, sizeof line,
                    "target (issue 14): replay within %.1fx of the minimal parse: %s %.2fx: %s\n",
                    kReplayTargetRatio, name.c_str(), ratio,
                    ratio <= kReplayTargetRatio ? "met" : "NOT met");
      out << line;
    }
    for (const std::string& name : order_) {
      if (name.rfind("engine/", 0) != 0) continue;
      const double ns = rows_[name].cpu_ns;
      std::snprintf(line, sizeof line,
                    "target (issue 2): whole per-sample update under 1000 ns on one core: %s "
                    "%.1f ns: %s\n",
                    name.c_str(), ns, ns < 1000.0 ? "met" : "NOT met");
      out << line;
    }
    out.flush();
  }

 private:
  struct Row {
    double cpu_ns = 0.0, wall_ns = 0.0;
    long long reps = 0;
  };
  static double to_ns(double t, benchmark::TimeUnit unit) {
    switch (unit) {
      case benchmark::kNanosecond:
        return t;
      case benchmark::kMicrosecond:
        return t * 1e3;
      case benchmark::kMillisecond:
        return t * 1e6;
      case benchmark::kSecond:
        return t * 1e9;
    }
    return t;
  }
  std::vector<std::string> order_;
  std::map<std::string, Row> rows_;
};

void register_all() {
  struct Set {
    const char* vessel;
    double rate_hz;
  };
  for (const Set& s : {Set{"otter", 50.0}, Set{"otter", 10.0}, Set{"mariner", 50.0}}) {
    const std::string set =
        std::string(s.vessel) + "_" + std::to_string(static_cast<int>(s.rate_hz)) + "Hz";
    const std::string v = s.vessel;
    const double hz = s.rate_hz;
    benchmark::RegisterBenchmark(("baseline/" + set).c_str(),
                                 [v, hz](benchmark::State& st) { bm_baseline(st, v, hz); });
    benchmark::RegisterBenchmark(("identification/" + set).c_str(),
                                 [v, hz](benchmark::State& st) { bm_identification(st, v, hz); });
    benchmark::RegisterBenchmark(("isolation/" + set).c_str(),
                                 [v, hz](benchmark::State& st) { bm_isolation(st, v, hz); });
    benchmark::RegisterBenchmark(("engine/" + set).c_str(),
                                 [v, hz](benchmark::State& st) { bm_engine(st, v, hz); });
    // The same with identification's consistency guard off (its cost, side by side).
    benchmark::RegisterBenchmark(
        ("identification_noguard/" + set).c_str(),
        [v, hz](benchmark::State& st) { bm_identification(st, v, hz, false); });
    benchmark::RegisterBenchmark(("engine_noguard/" + set).c_str(),
                                 [v, hz](benchmark::State& st) { bm_engine(st, v, hz, false); });
  }
  register_csv();
}

}  // namespace
}  // namespace usvfdi::bench

int main(int argc, char** argv) {
  // Defaults (a later command-line flag overrides them): medians over 9 repetitions.
  std::vector<char*> args;
  args.push_back(argv[0]);
  std::string reps = "--benchmark_repetitions=9";
  std::string aggregates = "--benchmark_report_aggregates_only=true";
  args.push_back(reps.data());
  args.push_back(aggregates.data());
  for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
  int n = static_cast<int>(args.size());
  args.push_back(nullptr);
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  try {
    usvfdi::bench::register_all();
    usvfdi::bench::SummaryReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "usv_fdi_bench: %s\n", e.what());
    return 1;
  }
  benchmark::Shutdown();
  return 0;
}
