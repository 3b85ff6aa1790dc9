// The sidecar's pipeline and the replay are one engine with two drivers: every golden case
// (cases.txt) run through FdiPipeline, its rows pushed as separate rudder and INS samples,
// must give exactly the committed replay's event records: pushed one by one at the pace
// of the pipeline, and pushed all at once while the identification thread is slowed down
// (the results must not depend on how the threads are scheduled).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi {
namespace {

const std::string kRoot = USV_FDI_SOURCE_DIR;

struct GoldenCase {
  std::string name, config;
  bool auto_ack = false;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::vector<GoldenCase> golden_cases() {
  std::ifstream in(kRoot + "/tests/golden/cases.txt");
  std::vector<GoldenCase> out;
  std::string line;
  while (std::getline(in, line)) {
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    std::array<std::string, 3> f;
    std::istringstream ls(line);
    for (std::string& x : f) std::getline(ls, x, '|');
    GoldenCase c{trim(f[0]), trim(f[1]), false};
    std::istringstream opts(f[2]);
    for (std::string o; opts >> o;) {
      if (o == "--auto-ack") {
        c.auto_ack = true;
      } else {
        ADD_FAILURE() << "cases.txt: case " << c.name << ": replay option " << o
                      << " is not known to this test";
      }
    }
    out.push_back(c);
  }
  return out;
}

/// The event records of a JSON Lines file, per sensor (in each instance's sequence order).
using PerSensor = std::array<std::vector<std::string>, 3>;

int sensor_of(const std::string& record) {
  for (int i = 0; i < 3; ++i) {
    const std::string key = std::string("\"sensor\":\"") + to_string(static_cast<Sensor>(i)) + "\"";
    if (record.find(key) != std::string::npos) return i;
  }
  return -1;
}

PerSensor golden_events(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  PerSensor out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("{\"type\":\"event\"", 0) != 0) continue;
    const int i = sensor_of(line);
    EXPECT_GE(i, 0) << line;
    if (i >= 0) out[i].push_back(line);
  }
  return out;
}

struct Sink {
  std::mutex m;
  std::vector<FaultEvent> events;
  std::size_t size() {
    std::lock_guard<std::mutex> l(m);
    return events.size();
  }
};

/// Waits (without a time limit: a busy machine is slow, not wrong) until the isolation
/// thread has handled `inputs` inputs and the sink holds every event it emitted.
void settle(const pipeline::FdiPipeline& p, Sink* sink, std::uint64_t inputs) {
  while (p.inputs_handled() < inputs || sink->size() < p.events_emitted()) {
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

/// burst: every row is pushed at once (no waiting for the pipeline), and the identification
/// thread sleeps whenever it reports a change of convergence, so that the isolation thread
/// runs far ahead of it unless it waits for its estimates.
PerSensor run_pipeline(const GoldenCase& c, bool burst) {
  const EngineConfig cfg = io::load_engine_config(kRoot + "/" + c.config);
  pipeline::PipelineOptions opt;
  opt.input_timeout = 1e9;  // wall-clock silence must not inject samples on a busy machine
  opt.input_capacity = 1 << 20;
  opt.estimate_wait = 1e3;  // a slowed thread is slow, not wedged
  const auto slow_identification = [](int, const std::string& msg) {
    if (msg.rfind("identification: A ", 0) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(150));
    }
  };
  Sink sink;
  pipeline::FdiPipeline p(
      cfg, opt,
      [&sink](const FaultEvent& e) {
        std::lock_guard<std::mutex> l(sink.m);
        sink.events.push_back(e);
      },
      nullptr, burst ? pipeline::FdiPipeline::LogSink(slow_identification) : nullptr);
  p.start();
  io::CsvSampleReader reader(kRoot + "/tests/golden/" + c.name + ".csv");
  std::uint64_t pushed = 0;
  std::size_t seen = 0;
  Sample s;
  while (reader.next(&s)) {
    p.push_rudder({s.t, s.delta, !std::isnan(s.delta)});
    p.push_ins({s.t, s.v, s.r, !std::isnan(s.v), !std::isnan(s.r)});
    pushed += 2;
    if (burst) continue;
    settle(p, &sink, pushed);
    if (!c.auto_ack) continue;
    // As replay --auto-ack: every raised or cleared event acknowledged at once.
    std::vector<FaultEvent> fresh;
    {
      std::lock_guard<std::mutex> l(sink.m);
      fresh.assign(sink.events.begin() + static_cast<std::ptrdiff_t>(seen), sink.events.end());
      seen = sink.events.size();
    }
    for (const FaultEvent& e : fresh) {
      if (e.state != FaultState::kRaised && e.state != FaultState::kClearedUnacknowledged) {
        continue;
      }
      p.push_ack({e.sensor, e.sequence, "replay --auto-ack"});
      settle(p, &sink, ++pushed);
      std::lock_guard<std::mutex> l(sink.m);
      seen = sink.events.size();  // the ack's own event needs no ack
    }
  }
  p.stop();
  PerSensor out;
  for (const FaultEvent& e : sink.events) {
    std::ostringstream line;
    io::JsonlWriter w(line);
    w.event(e);
    w.flush();
    std::string text = line.str();
    if (!text.empty() && text.back() == '\n') text.pop_back();
    out[static_cast<int>(e.sensor)].push_back(text);
  }
  return out;
}

void expect_replays_events(bool burst) {
  const std::vector<GoldenCase> cases = golden_cases();
  ASSERT_FALSE(cases.empty());
  for (const GoldenCase& c : cases) {
    // Acknowledging at once needs each sample's events before the next sample.
    if (burst && c.auto_ack) continue;
    SCOPED_TRACE("golden case " + c.name);
    const PerSensor want = golden_events(kRoot + "/tests/golden/" + c.name + ".jsonl");
    std::size_t events = 0;
    for (const auto& v : want) events += v.size();
    if (c.auto_ack) {
      EXPECT_GT(events, 0u) << "a case with acknowledgements must have events";
    }
    const PerSensor got = run_pipeline(c, burst);
    for (int i = 0; i < 3; ++i) {
      SCOPED_TRACE(std::string("sensor ") + to_string(static_cast<Sensor>(i)));
      EXPECT_EQ(got[i].size(), want[i].size());
      for (std::size_t k = 0; k < std::min(got[i].size(), want[i].size()); ++k) {
        EXPECT_EQ(got[i][k], want[i][k]) << "event " << k;
      }
    }
  }
}

TEST(GoldenPipeline, ThePipelineGivesTheReplaysEventsOnEveryGoldenCase) {
  expect_replays_events(false);
}

TEST(GoldenPipeline, ASlowIdentificationThreadChangesNoEventOfAnyGoldenCase) {
  expect_replays_events(true);
}

}  // namespace
}  // namespace usvfdi
