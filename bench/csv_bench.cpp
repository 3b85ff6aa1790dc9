// Replay input cost: the CSV reader and the whole replay against a minimal parse of the same
// file, side by side in one run (issue 14, item 6: replay within 1.5x of the minimal parse).
//
// The file: the paper's scenario on the Otter at 50 Hz stretched to one hour (180 001 rows),
// written once by io::SimCsvWriter exactly as `usv-fdi sim` writes it (11 columns, %.17g) to a
// temporary file, removed at exit. It stays in the page cache: "disk speed" here is the speed
// of reading a cached file. One iteration is one row; a batch is one pass over the whole file
// (open, read, parse, close), so the times are per row.
//
//   baseline/csv_otter_50Hz_1h        the minimal parse: fread of the whole file into one reused
//                                     buffer, t, v, r, delta of every row by strtod, summed
//   minimal_from_chars/csv_...        the same with std::from_chars instead of strtod
//   csv_reader/csv_...                io::CsvSampleReader, every row
//   csv_reader_before/csv_...         the reader before it parsed in place
//                                     (tests/support/csv_reference.hpp), every row
//   replay/csv_...                    io::replay (reader, plausibility check, FdiEngine::process
//                                     per row, config/vessels/otter.yaml), its JSON Lines
//                                     output written to /dev/null
//   replay_engine_part/csv_...        FdiEngine::process alone on the same rows, read into
//                                     memory beforehand (the replay's cost besides reading)
//
// Counter x_minimal: the benchmark's CPU time per row over the median of the minimal parse's
// repetitions in the same run (the summary at the end gives the same ratio of medians).
#include "csv_bench.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "support/csv_reference.hpp"
#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/io/replay.hpp"

namespace usvfdi::bench {
namespace {

constexpr const char* kSet = "csv_otter_50Hz_1h";

/// The simulated file, written on first use and removed at exit.
struct CsvFile {
  std::string path;
  std::size_t rows = 0;
  std::size_t bytes = 0;

  CsvFile() {
    path = (std::filesystem::temp_directory_path() /
            ("usv_fdi_bench_" + std::to_string(::getpid()) + ".csv"))
               .string();
    SimConfig c = paper_scenario(otter(), 50.0, 7);
    c.duration = 3600.0;
    Simulator sim(c);
    std::ofstream out(path, std::ios::binary);
    io::SimCsvWriter writer(out);
    SimRow row;
    while (sim.next(&row)) {
      writer.write(row);
      ++rows;
    }
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
    bytes = std::filesystem::file_size(path);
  }
  ~CsvFile() { std::remove(path.c_str()); }
};

const CsvFile& csv_file() {
  static const CsvFile file;
  return file;
}

double thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
}

/// CPU ns per row of each repetition of the minimal parse in this run.
std::vector<double>& minimal_ns() {
  static std::vector<double> ns;
  return ns;
}

/// Runs pass() once per batch of file.rows iterations; records the CPU time per row, as the
/// minimal parse's (is_minimal) or as the counter x_minimal over that parse's median.
template <typename Pass>
void run_passes(benchmark::State& state, bool is_minimal, Pass pass) {
  const CsvFile& file = csv_file();
  const double start = thread_cpu_ns();
  while (state.KeepRunningBatch(static_cast<benchmark::IterationCount>(file.rows))) {
    if (pass(file) != file.rows) {
      state.SkipWithError("a pass did not read every row");
      return;
    }
  }
  const double ns = (thread_cpu_ns() - start) / static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(state.iterations() / static_cast<benchmark::IterationCount>(file.rows) *
                          static_cast<benchmark::IterationCount>(file.bytes));
  std::vector<double>& minimal = minimal_ns();
  if (is_minimal) {
    minimal.push_back(ns);
  } else if (!minimal.empty()) {
    std::vector<double> sorted = minimal;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    state.counters["x_minimal"] = ns / sorted[sorted.size() / 2];
  }
}

/// The minimal parse: the whole file by fread into `buffer`, then per row the first four fields
/// (t, v, r, delta) by parse(first, last, &x) -> end of the number; returns the rows parsed.
template <typename Parse>
std::size_t minimal_pass(const CsvFile& file, std::vector<char>& buffer, Parse parse) {
  std::FILE* f = std::fopen(file.path.c_str(), "rb");
  if (f == nullptr) return 0;
  buffer.resize(file.bytes + 1);
  const std::size_t n = std::fread(buffer.data(), 1, file.bytes, f);
  std::fclose(f);
  buffer[n] = '\0';  // strtod stops here at the latest
  const char* p = buffer.data();
  const char* const end = p + n;
  p = static_cast<const char*>(std::memchr(p, '\n', n)) + 1;  // the header
  std::size_t rows = 0;
  double sum = 0.0;
  while (p < end) {
    for (int k = 0; k < 4; ++k) {
      double x = 0.0;
      p = parse(p, end, &x) + 1;  // past the comma (an empty field parses to nothing)
      sum += x;
    }
    const void* nl = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
    p = nl == nullptr ? end : static_cast<const char*>(nl) + 1;
    ++rows;
  }
  benchmark::DoNotOptimize(sum);
  return rows;
}

/// The minimal parse's buffer: allocated and touched once, outside the timing, so that its
/// passes do not pay the page faults of a fresh buffer the size of the file (29 MB) (which cost as
/// much as the parse on this VM) and stay the yardstick they are meant to be.
std::vector<char>& minimal_buffer() {
  static std::vector<char> buffer(csv_file().bytes + 1, '\0');
  return buffer;
}

void bm_minimal_strtod(benchmark::State& state) {
  std::vector<char>& buffer = minimal_buffer();
  run_passes(state, true, [&](const CsvFile& file) {
    return minimal_pass(file, buffer, [](const char* p, const char*, double* x) {
      char* e = nullptr;
      *x = std::strtod(p, &e);
      return static_cast<const char*>(e);
    });
  });
}

void bm_minimal_from_chars(benchmark::State& state) {
  std::vector<char>& buffer = minimal_buffer();
  run_passes(state, false, [&](const CsvFile& file) {
    return minimal_pass(file, buffer, [](const char* p, const char* end, double* x) {
      return std::from_chars(p, end, *x).ptr;
    });
  });
}

/// Reads every row with `reader`, summing the four fields; returns the rows read.
template <typename Reader>
std::size_t read_all(Reader& reader) {
  Sample s;
  double sum = 0.0;
  std::size_t rows = 0;
  while (reader.next(&s)) {
    sum += s.t + s.v + s.r + s.delta;
    ++rows;
  }
  benchmark::DoNotOptimize(sum);
  return rows;
}

void bm_reader(benchmark::State& state) {
  run_passes(state, false, [](const CsvFile& file) {
    io::CsvSampleReader reader(file.path);
    return read_all(reader);
  });
}

void bm_reader_before(benchmark::State& state) {
  run_passes(state, false, [](const CsvFile& file) {
    reference::CsvSampleReader reader(std::make_unique<std::ifstream>(file.path, std::ios::binary),
                                      file.path);
    return read_all(reader);
  });
}

void bm_replay(benchmark::State& state) {
  const EngineConfig cfg =
      io::load_engine_config(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/otter.yaml");
  std::ofstream null("/dev/null");
  io::JsonlWriter out(null);
  run_passes(state, false, [&](const CsvFile& file) {
    io::CsvSampleReader reader(file.path);
    return static_cast<std::size_t>(io::replay(cfg, reader, out, io::ReplayOptions{}).samples);
  });
}

/// The engine's part of the replay: the same rows, read beforehand (untimed), through a fresh
/// FdiEngine per pass.
void bm_engine_part(benchmark::State& state) {
  const EngineConfig cfg =
      io::load_engine_config(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/otter.yaml");
  std::vector<Sample> samples;
  io::CsvSampleReader reader(csv_file().path);
  for (Sample s; reader.next(&s);) samples.push_back(s);
  std::vector<FaultEvent> events;
  run_passes(state, false, [&](const CsvFile&) {
    FdiEngine engine(cfg);
    for (const Sample& s : samples) {
      events.clear();
      benchmark::DoNotOptimize(engine.process(s, &events));
    }
    return samples.size();
  });
}

}  // namespace

void register_csv() {
  const std::string set = kSet;
  benchmark::RegisterBenchmark(("baseline/" + set).c_str(), bm_minimal_strtod);
  benchmark::RegisterBenchmark(("minimal_from_chars/" + set).c_str(), bm_minimal_from_chars);
  benchmark::RegisterBenchmark(("csv_reader/" + set).c_str(), bm_reader);
  benchmark::RegisterBenchmark(("csv_reader_before/" + set).c_str(), bm_reader_before);
  benchmark::RegisterBenchmark(("replay/" + set).c_str(), bm_replay);
  benchmark::RegisterBenchmark(("replay_engine_part/" + set).c_str(), bm_engine_part);
}

}  // namespace usvfdi::bench
