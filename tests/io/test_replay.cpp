// Replay loop (library level) and the simulation scripts / fault SPEC syntax.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "json_lite.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/replay.hpp"
#include "usv_fdi/io/scenarios.hpp"

namespace usvfdi::io {
namespace {

namespace js = usvfdi::testing_json;
const std::string kSource = USV_FDI_SOURCE_DIR;

/// A short, quick scenario with an early fault, and a config that arms within it.
SimConfig short_sim() {
  SimConfig c = paper_scenario(otter(), 20.0, 5);
  c.duration = 60.0;
  c.faults = {{Sensor::kGyro, FaultKind::kStale, 40.0, 45.0, 0.0, 2.0}};
  return c;
}

EngineConfig quick_config() {
  return load_engine_config_from_string(
      "model: {B: [0.165394, -2.19400]}\n"
      "isolation: {sigma_v: 0.005, sigma_r: 0.0005, learn_time: 10}\n",
      "quick.yaml");
}

std::string sim_csv(const SimConfig& c) {
  std::ostringstream os;
  SimCsvWriter w(os);
  for (const SimRow& row : simulate(c)) w.write(row);
  return os.str();
}

std::vector<js::Value> parse_lines(const std::string& text) {
  std::vector<js::Value> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) out.push_back(js::parse(line));
  return out;
}

std::string replay_text(const EngineConfig& cfg, const std::string& csv, RunSummary* sum,
                        std::string* error = nullptr) {
  CsvSampleReader r(std::make_unique<std::istringstream>(csv), "mem.csv");
  std::ostringstream os;
  JsonlWriter w(os);
  try {
    *sum = replay(cfg, r, w);
  } catch (const InputError& e) {
    if (error) *error = e.what();
  }
  return os.str();
}

TEST(Replay, CsvReplayGivesTheEventsOfTheInMemoryRun) {
  const SimConfig sim = short_sim();
  const EngineConfig cfg = quick_config();
  // in memory
  FdiEngine engine(cfg);
  std::vector<FaultEvent> want;
  for (const SimRow& row : simulate(sim)) {
    engine.process(Sample{row.t, row.v, row.r, row.delta}, &want);
  }
  // through CSV and JSON Lines
  RunSummary sum;
  const auto recs = parse_lines(replay_text(cfg, sim_csv(sim), &sum));
  std::vector<js::Value> events;
  for (const js::Value& v : recs) {
    if (v.at("type").str == "event") events.push_back(v);
  }
  ASSERT_EQ(events.size(), want.size());
  EXPECT_GT(want.size(), 0u) << "the stale gyro should raise an event";
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(events[i].at("stamp").num, std::stod(json_number(want[i].t)));
    EXPECT_EQ(events[i].at("sensor").str, to_string(want[i].sensor));
    EXPECT_EQ(events[i].at("state").str, to_string(want[i].state));
    EXPECT_EQ(events[i].at("kind").str, to_string(want[i].kind));
    EXPECT_EQ(events[i].at("sequence").num, static_cast<double>(want[i].sequence));
  }
  EXPECT_EQ(sum.events, want.size());
  EXPECT_EQ(to_params(engine.estimate().A), sum.final_a);
  EXPECT_EQ(engine.frozen_samples(), sum.frozen_samples);
  EXPECT_EQ(engine.estimate().unconvergences, sum.unconvergences);
}

TEST(Replay, SummaryCountsRaisesNotRefinements) {
  // GIVEN a gyro scale fault that is raised as a bias and refined to scale a few seconds
  // later (the refinement is published again with state "raised")
  SimConfig sim;
  sim.vessel = otter();
  sim.rate_hz = 10.0;
  sim.duration = 200.0;
  sim.seed = 2;
  sim.faults = {{Sensor::kGyro, FaultKind::kScale, 150.0, 170.0, 0.5, 2.0}};
  const std::string csv = sim_csv(sim);
  const EngineConfig cfg = load_engine_config(kSource + "/tests/golden/faults_otter.yaml");
  // WHEN it is replayed
  RunSummary sum;
  const auto recs = parse_lines(replay_text(cfg, csv, &sum));
  // THEN the summary counts transitions into raised per sensor, not raised records
  std::map<std::string, std::string> state;
  std::map<std::string, double> raises;
  int refinements = 0;
  for (const js::Value& v : recs) {
    if (v.at("type").str != "event") continue;
    const std::string sensor = v.at("sensor").str, st = v.at("state").str;
    if (st == "raised" && state[sensor] != "raised") raises[sensor] += 1;
    if (st == "raised" && state[sensor] == "raised") ++refinements;
    state[sensor] = st;
  }
  EXPECT_GT(refinements, 0) << "the case no longer refines a kind: pick one that does";
  EXPECT_EQ(static_cast<double>(sum.raised[0]), raises["accelerometer"]);
  EXPECT_EQ(static_cast<double>(sum.raised[1]), raises["gyro"]);
  EXPECT_EQ(static_cast<double>(sum.raised[2]), raises["unknown"]);
}

TEST(Replay, EstimateRecordsEverySecondAndSummaryLast) {
  const SimConfig sim = short_sim();
  RunSummary sum;
  const auto recs = parse_lines(replay_text(quick_config(), sim_csv(sim), &sum));
  ASSERT_FALSE(recs.empty());
  EXPECT_EQ(recs.back().at("type").str, "summary");
  EXPECT_TRUE(recs.back().at("complete").b);
  EXPECT_EQ(recs.back().at("samples").num, static_cast<double>(sim.duration * sim.rate_hz + 1));
  EXPECT_EQ(recs.back().at("duration_s").num, sim.duration);
  double last = -1.0;
  int estimates = 0;
  for (const js::Value& v : recs) {
    const std::string type = v.at("type").str;
    ASSERT_TRUE(type == "event" || type == "estimate" || type == "summary") << type;
    if (type != "estimate") continue;
    ++estimates;
    const double t = v.at("t").num;
    if (last >= 0) {
      EXPECT_LE(t - last, 1.0 + 1e-9) << "gap before " << t;
    }
    last = t;
  }
  EXPECT_EQ(last, sim.duration);  // one at the end
  EXPECT_GE(estimates, static_cast<int>(sim.duration));
}

TEST(Replay, InputErrorKeepsEverythingProducedBefore) {
  const SimConfig sim = short_sim();
  const std::string csv = sim_csv(sim);
  RunSummary full_sum;
  const auto full = parse_lines(replay_text(quick_config(), csv, &full_sum));
  // Corrupt the row of t = 50 s (after the stale fault's events).
  std::istringstream in(csv);
  std::string line, bad;
  int n = 0, bad_line = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.rfind("50,", 0) == 0) {
      line = "50,oops,0,0,0,0,0,0,0,,";
      bad_line = n;
    }
    bad += line + "\n";
  }
  ASSERT_GT(bad_line, 0);
  RunSummary sum;
  std::string error;
  const auto part = parse_lines(replay_text(quick_config(), bad, &sum, &error));
  EXPECT_NE(error.find("mem.csv:" + std::to_string(bad_line)), std::string::npos) << error;
  EXPECT_NE(error.find("'oops'"), std::string::npos) << error;
  std::vector<double> want, got;
  for (const js::Value& v : full) {
    if (v.at("type").str == "event" && v.at("stamp").num < 50.0) want.push_back(v.at("stamp").num);
  }
  for (const js::Value& v : part) {
    if (v.at("type").str == "event") got.push_back(v.at("stamp").num);
  }
  EXPECT_FALSE(want.empty());
  EXPECT_EQ(got, want);
  ASSERT_FALSE(part.empty());
  EXPECT_EQ(part.back().at("type").str, "summary");
  EXPECT_FALSE(part.back().at("complete").b);
  EXPECT_EQ(part.back().at("error").str, error);
  EXPECT_EQ(part.back().at("samples").num, static_cast<double>(bad_line - 2));
}

TEST(Scenarios, EveryKindScriptAlternatesSensorsWithHealthyGaps) {
  const auto script = every_kind_script(otter(), 300.0);
  ASSERT_EQ(script.size(), 7u);
  std::set<FaultKind> kinds;
  for (std::size_t i = 0; i < script.size(); ++i) {
    kinds.insert(script[i].kind);
    EXPECT_EQ(script[i].sensor, i % 2 == 0 ? Sensor::kAccelerometer : Sensor::kGyro);
    EXPECT_GT(script[i].t_end, script[i].t_start);
    if (i > 0) {
      EXPECT_GE(script[i].t_start - script[i - 1].t_end, 30.0);
    }
  }
  EXPECT_EQ(kinds.size(), 7u);
  EXPECT_EQ(script.front().t_start, 300.0);
  const SimConfig c = faults_scenario(mariner(), 10.0, 1);
  EXPECT_EQ(c.faults.front().t_start, first_fault_time(mariner()));
  EXPECT_GT(c.duration, c.faults.back().t_end);
  EXPECT_TRUE(healthy_scenario(otter(), 10.0, 1).faults.empty());
}

TEST(Scenarios, FaultSpecParsesAndRejects) {
  FaultInjection f;
  std::string why;
  ASSERT_TRUE(parse_fault_spec("gyro:bias:20:40:0.005", &f, &why)) << why;
  EXPECT_EQ(f.sensor, Sensor::kGyro);
  EXPECT_EQ(f.kind, FaultKind::kBias);
  EXPECT_EQ(f.t_start, 20.0);
  EXPECT_EQ(f.t_end, 40.0);
  EXPECT_EQ(f.magnitude, 0.005);
  ASSERT_TRUE(parse_fault_spec("acc:spikes:1:2:0.1:5", &f, &why)) << why;
  EXPECT_EQ(f.sensor, Sensor::kAccelerometer);
  EXPECT_EQ(f.spike_rate, 5.0);
  ASSERT_TRUE(parse_fault_spec("a:stale:1:2", &f, &why)) << why;
  EXPECT_EQ(format_fault_spec(f), "accelerometer:stale:1:2:0");
  for (const char* bad :
       {"gyro:bias:20", "compass:bias:1:2:3", "gyro:wobble:1:2:3", "gyro:bias:5:4:1",
        "gyro:bias:1:2:x", "gyro:bias:1:2:3:4:5", "gyro:unknown:1:2:3", "gyro:bias:1:nan:3"}) {
    EXPECT_FALSE(parse_fault_spec(bad, &f, &why)) << bad;
    EXPECT_NE(why.find(bad), std::string::npos) << why;
  }
}

TEST(Replay, CountsAndLocatesRejectedRows) {
  const std::string csv =
      "t,v,r,delta\n"
      "0,0,0,0\n"
      "0.1,0,0,0\n"
      "0.1,0.01,0,0\n"  // line 4: repeats the time, with another value
      "nan,0,0,0\n"     // line 5: no time
      "0.05,0,0,0\n"    // line 6: goes back
      "0.2,0,0,0\n"
      "0.2,0,0,0\n";  // line 8: the previous row once more (dropped, not rejected)
  RunSummary sum;
  replay_text(quick_config(), csv, &sum);
  EXPECT_EQ(sum.samples, 7u);
  EXPECT_EQ(sum.rejected, 3u);
  EXPECT_EQ(sum.duplicates, 1u);
  EXPECT_EQ(sum.first_duplicate_line, 8u);
  EXPECT_EQ(sum.rejected_no_time, 1u);
  EXPECT_EQ(sum.first_rejected_line, 4u);
  EXPECT_EQ(sum.first_rejected_t, 0.1);
  EXPECT_EQ(sum.first_rejected_after, 0.1);
}

}  // namespace
}  // namespace usvfdi::io
