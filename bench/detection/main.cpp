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

int main(int argc, char** argv) {
  using namespace usvfdi::bench;
  CLI::App app{
      "usv-fdi detection benchmark: engine, the paper's method and an oracle on the "
      "vessel zoo and the HSVA KVLCC2 tests"};
  BenchOptions opt;
  opt.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string json_file, md_file;
  opt.config_dir = std::string(USV_FDI_SOURCE_DIR) + "/config";
  bool no_realdata = false, no_progress = false;
  std::string realdata;
  app.add_flag("--quick", opt.quick, "the CI mode (a few minutes on 2 cores)");
  app.add_option("--jobs,-j", opt.jobs, "worker threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app.add_option("--seeds", opt.seeds, "seeds per configuration (default: the mode's)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--json", json_file, "write the tables and every run as JSON");
  app.add_option("--markdown", md_file, "write the tables as markdown");
  app.add_option("--only", opt.only, "run only the tables whose name contains this");
  app.add_option("--config-dir", opt.config_dir, "where default.yaml and paper.yaml are")
      ->capture_default_str();
  app.add_option("--realdata", realdata,
                 "the HSVA KVLCC2 directory (default: shared/realdata/kvlcc2-hsva beside the "
                 "source tree)");
  app.add_flag("--no-realdata", no_realdata, "leave the recorded data out");
  app.add_flag("--no-progress", no_progress, "no progress line on stderr");
  app.add_flag("--speed", opt.speed,
               "give every method the surge speed u (voyages: the simulated log; HSVA: the data's "
               "column u); default: B only");
  CLI11_PARSE(app, argc, argv);
  opt.progress = !no_progress;

  try {
    if (!no_realdata) {
      opt.realdata_dir =
          realdata.empty() ? find_realdata(USV_FDI_SOURCE_DIR, &opt.realdata_note) : realdata;
      if (opt.realdata_dir.empty()) std::fprintf(stderr, "note: %s\n", opt.realdata_note.c_str());
    }
    usvfdi::EngineConfig engine_cfg, paper_cfg;
    load_configs(opt.config_dir, &engine_cfg, &paper_cfg);
    const std::vector<Case> cases = make_cases(opt);
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<CaseResult> results = run_all(cases, opt, engine_cfg, paper_cfg);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto tables = summarise(cases, results);

    std::string command = "usv-fdi-bench-detection";
    for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    char head[512];
    std::snprintf(
        head, sizeof head, "`%s` (%s mode%s), %s, %zu runs in %.0f s on %d thread(s).%s%s",
        command.c_str(), opt.quick ? "quick" : "full", opt.speed ? ", with the speed input" : "",
        date, cases.size(), secs, opt.jobs, opt.realdata_dir.empty() ? " Real data left out: " : "",
        opt.realdata_dir.empty() ? (no_realdata ? "--no-realdata" : opt.realdata_note.c_str())
                                 : "");
    const std::string md = to_markdown(tables, head);
    std::cout << md;
    if (!md_file.empty()) {
      std::ofstream f(md_file);
      f << md;
      if (!f) {
        std::fprintf(stderr, "error: cannot write %s\n", md_file.c_str());
        return 4;
      }
    }
    if (!json_file.empty()) {
      std::ofstream f(json_file);
      f << to_json(cases, results, tables, head);
      if (!f) {
        std::fprintf(stderr, "error: cannot write %s\n", json_file.c_str());
        return 4;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
