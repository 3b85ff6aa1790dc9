// usv-fdi-bench-detection: the detection benchmark of the proving ground (docs/benchmark.md).
// Runs subjects x rates x voyages x faults x seeds and the recorded HSVA KVLCC2 tests through
// the engine, the paper's method and an oracle that knows A; prints one markdown table per
// subject and rate, and writes JSON and markdown files on request.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <thread>

#include "runner.hpp"

#ifndef USV_FDI_SOURCE_DIR
#define USV_FDI_SOURCE_DIR "."
#endif

namespace {

using namespace usvfdi::bench;

/// The command line: the benchmark's options and what only main uses.
struct CommandLine {
  BenchOptions opt;
  std::string json_file, md_file;
  std::string realdata;
  bool no_realdata = false, no_progress = false;
};

void add_options(CLI::App* app, CommandLine* cl) {
  BenchOptions& opt = cl->opt;
  app->add_flag("--quick", opt.quick, "the CI mode (a few minutes on 2 cores)");
  app->add_option("--jobs,-j", opt.jobs, "worker threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app->add_option("--seeds", opt.seeds, "seeds per configuration (default: the mode's)")
      ->check(CLI::Range(1, 1000));
  app->add_option("--json", cl->json_file, "write the tables and every run as JSON");
  app->add_option("--markdown", cl->md_file, "write the tables as markdown");
  app->add_option("--only", opt.only, "run only the tables whose name contains this");
  app->add_option("--config-dir", opt.config_dir, "where default.yaml and paper.yaml are")
      ->capture_default_str();
  app->add_option("--realdata", cl->realdata,
                  "the HSVA KVLCC2 directory (default: shared/realdata/kvlcc2-hsva beside the "
                  "source tree)");
  app->add_flag("--no-realdata", cl->no_realdata, "leave the recorded data out");
  app->add_flag("--no-progress", cl->no_progress, "no progress line on stderr");
  app->add_flag("--speed", opt.speed,
                "give every method the surge speed u (voyages: the simulated log; HSVA: the "
                "data's column u); default: B only");
}

/// The outputs' first line: the command, the mode, the date, the size and time of the run,
/// and why real data were left out.
std::string run_header(int argc, char** argv, const CommandLine& cl, std::size_t runs,
                       double secs) {
  const BenchOptions& opt = cl.opt;
  std::string command = "usv-fdi-bench-detection";
  for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  char head[512];
  std::snprintf(
      head, sizeof head, "`%s` (%s mode%s), %s, %zu runs in %.0f s on %d thread(s).%s%s",
      command.c_str(), opt.quick ? "quick" : "full", opt.speed ? ", with the speed input" : "",
      date, runs, secs, opt.jobs, opt.realdata_dir.empty() ? " Real data left out: " : "",
      opt.realdata_dir.empty() ? (cl.no_realdata ? "--no-realdata" : opt.realdata_note.c_str())
                               : "");
  return head;
}

/// Writes text to path; false (and a message on stderr) when that fails.
bool write_output(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) {
    std::fprintf(stderr, "error: cannot write %s\n", path.c_str());
    return false;
  }
  return true;
}

/// Runs the benchmark and writes its outputs: 0, or 4 when a file cannot be written.
int run(int argc, char** argv, CommandLine* cl) {
  BenchOptions& opt = cl->opt;
  if (!cl->no_realdata) {
    opt.realdata_dir =
        cl->realdata.empty() ? find_realdata(USV_FDI_SOURCE_DIR, &opt.realdata_note) : cl->realdata;
    if (opt.realdata_dir.empty()) std::fprintf(stderr, "note: %s\n", opt.realdata_note.c_str());
  }
  usvfdi::EngineConfig engine_cfg, paper_cfg;
  load_configs(opt.config_dir, &engine_cfg, &paper_cfg);
  const std::vector<Case> cases = make_cases(opt);
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<CaseResult> results = run_all(cases, opt, engine_cfg, paper_cfg);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto tables = summarise(cases, results);

  const std::string head = run_header(argc, argv, *cl, cases.size(), secs);
  const std::string md = to_markdown(tables, head, breakdown(cases, results));
  std::cout << md;
  if (!cl->md_file.empty() && !write_output(cl->md_file, md)) return 4;
  if (!cl->json_file.empty() &&
      !write_output(cl->json_file, to_json(cases, results, tables, head))) {
    return 4;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "usv-fdi detection benchmark: engine, the paper's method and an oracle on the "
      "vessel zoo and the HSVA KVLCC2 tests"};
  CommandLine cl;
  cl.opt.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  cl.opt.config_dir = std::string(USV_FDI_SOURCE_DIR) + "/config";
  add_options(&app, &cl);
  CLI11_PARSE(app, argc, argv);
  cl.opt.progress = !cl.no_progress;

  try {
    return run(argc, argv, &cl);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
