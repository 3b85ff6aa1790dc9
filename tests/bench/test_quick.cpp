// The detection benchmark's quick mode (what CI runs): the harness works and its numbers
// are sane. It asserts that the ORACLE (given the true A) detects and isolates the injected
// faults on the simulated hulls and that every count and hour adds up; it asserts nothing
// about the engine or the paper's method, whose figures are the benchmark's output.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "runner.hpp"

namespace usvfdi::bench {
namespace {

TEST(BenchQuick, HarnessWorksAndTheOracleDetectsTheFaults) {
  BenchOptions opt;
  opt.quick = true;
  opt.jobs = 2;
  opt.progress = false;
  opt.config_dir = std::string(USV_FDI_SOURCE_DIR) + "/config";
  opt.realdata_dir = find_realdata(USV_FDI_SOURCE_DIR, &opt.realdata_note);
  if (opt.realdata_dir.empty()) {
    std::printf("real data left out of this run: %s\n", opt.realdata_note.c_str());
  }
  EngineConfig engine_cfg, paper_cfg;
  load_configs(opt.config_dir, &engine_cfg, &paper_cfg);
  ASSERT_EQ(paper_cfg.identification.method, IdentMethod::kPaper);
  const std::vector<Case> cases = make_cases(opt);
  const std::vector<CaseResult> results = run_all(cases, opt, engine_cfg, paper_cfg);
  ASSERT_EQ(results.size(), cases.size());
  const auto tables = summarise(cases, results);
  std::printf("%s", to_markdown(tables, "quick mode").c_str());

  // Every subject at both rates, and the real data when present.
  std::map<std::string, int> faulty, total;
  std::map<std::string, double> hours, windows;
  for (const Case& c : cases) {
    ++total[c.table];
    if (c.faulty) {
      ++faulty[c.table];
      windows[c.table] += (c.fault.t_end + opt.score.detect_grace - c.fault.t_start) / 3600.0;
    }
    hours[c.table] += c.duration / 3600.0;
  }
  // Every hull of the zoo (at least 8) at both rates: 5 kinds x 2 sensors and a healthy run.
  int sim_tables = 0;
  for (const auto& [name, n] : total) {
    if (name.rfind("kvlcc2-hsva", 0) == 0) continue;
    ++sim_tables;
    EXPECT_EQ(faulty[name], 10) << name;
    EXPECT_EQ(n, 11) << name;
  }
  EXPECT_GE(sim_tables, 16);
  EXPECT_EQ(total.count("mariner @ 10 Hz") + total.count("mariner @ 50 Hz"), 2u);
  if (!opt.realdata_dir.empty()) {
    EXPECT_EQ(total["kvlcc2-hsva single runs @ 20 Hz"], 13);
    EXPECT_EQ(faulty["kvlcc2-hsva concatenated @ 20 Hz"], 10);
  }

  for (const TableSummary& t : tables) {
    SCOPED_TRACE(t.name);
    EXPECT_EQ(static_cast<int>(t.runs), total[t.name]);
    // Data hours: the recorded span of every run (one sample interval short of the duration).
    EXPECT_NEAR(t.hours, hours[t.name], 1e-3);
    for (int k = 0; k < kMethods; ++k) {
      SCOPED_TRACE(method_name(k));
      const MethodSummary& m = t.m[k];
      EXPECT_EQ(m.runs, total[t.name]);
      EXPECT_EQ(m.faults, faulty[t.name]);
      EXPECT_LE(m.detected, m.faults);
      EXPECT_LE(m.isolated, m.detected);
      EXPECT_LE(m.recovered, m.detected);
      EXPECT_LE(m.detected_armed, m.armed_at_onset);
      EXPECT_LE(m.armed_runs, m.runs);
      int kf = 0, kd = 0, ki = 0;
      for (const auto& pk : m.per_kind) {
        kf += pk[0];
        kd += pk[1];
        ki += pk[2];
      }
      EXPECT_EQ(kf, m.faults);
      EXPECT_EQ(kd, m.detected);
      EXPECT_EQ(ki, m.isolated);
      // Healthy hours are the data hours minus the detection windows, whatever the method.
      EXPECT_NEAR(m.healthy_hours, t.hours - windows[t.name], 1e-3);
      EXPECT_NEAR(m.healthy_hours, t.m[kOracle].healthy_hours, 1e-9);
      EXPECT_LE(m.healthy_armed_hours, m.healthy_hours + 1e-9);
      if (m.detected > 0) {
        EXPECT_GE(m.delay_median, 0.0);
        EXPECT_LE(m.delay_median, m.delay_p95);
        EXPECT_LE(m.delay_p95, 60.0 + opt.score.detect_grace);
      }
      if (m.armed_runs > 0) {
        EXPECT_LE(m.arming_median, m.arming_max);
      }
      // The healthy runs' suspicion measures: their hours are the healthy runs' spans; the
      // share of frozen samples exists for the methods that identify, within [0, 1].
      double healthy_run_hours = 0.0;
      std::size_t samples = 0, frozen = 0, verdicts = 0;
      for (const CaseResult& r : results) {
        const Case& c = cases[r.index];
        if (c.table != t.name || c.faulty) continue;
        healthy_run_hours += (r.t_last - r.t_first) / 3600.0;
        samples += r.m[k].samples;
        frozen += r.m[k].frozen_samples;
        verdicts += r.m[k].mismatches.size();
        EXPECT_EQ(r.m[k].samples, r.samples);
      }
      EXPECT_NEAR(m.healthy_run_hours, healthy_run_hours, 1e-9);
      EXPECT_EQ(m.healthy_run_samples, samples);
      EXPECT_EQ(static_cast<std::size_t>(m.healthy_run_mismatches), verdicts);
      if (k == kOracle) {
        EXPECT_FALSE(m.has_identification);
        EXPECT_TRUE(std::isnan(m.frozen_share()));
      } else {
        EXPECT_TRUE(m.has_identification);
        EXPECT_GE(m.frozen_share(), 0.0);
        EXPECT_LE(m.frozen_share(), 1.0);
        EXPECT_EQ(m.healthy_run_frozen, frozen);
      }
    }
    // The oracle knows A: zero error, armed on every run (after settling and learning).
    const MethodSummary& o = t.m[kOracle];
    EXPECT_NEAR(o.a_error_median, 0.0, 1e-12);
    if (t.name.rfind("kvlcc2-hsva single", 0) == 0) {
      // Two of the tests (66 and 67 s) end before settling (6 s) and learning (60 s) are over.
      EXPECT_GE(o.armed_runs, o.runs - 2);
    } else {
      EXPECT_EQ(o.armed_runs, o.runs);
    }
    // Learning pauses while a suspicion is held (healthy thresholds are learned from healthy
    // data only): on the open-loop unstable otter3dof at 50 Hz the jump check suspects some of
    // the autopilot's fast rudder reversals in the first minute, and learning ends after up to
    // 137 s instead of 67 s. Three minutes bounds that with room; a learning that never ends
    // would fail it.
    EXPECT_LT(o.arming_max, 180.0);
  }

  // The oracle, given the true (linearised) A, detects the injected faults: every bias,
  // stuck, drift and noise fault on each hull whose linearisation holds (no false alarm of
  // the oracle), and most of them everywhere. Scale faults are reported, not asserted: a
  // +50 % gain error is as large as the signal, and the oracle itself misses some of them
  // when a +-10 deg course change moves the channel by a few sigma only.
  // The linearisation of the open-loop unstable 3-DOF Otter does not hold: the oracle's gyro
  // J_N pegs at clip^2 at every course change, its bar grows past clip^2 and it misses the gyro
  // bias and drift. Named here rather than inferred from an oracle false alarm, which a change
  // elsewhere can remove (tried at stop 44: the check then failed on those misses).
  const auto linearisation_holds = [](const std::string& name) {
    return name.rfind("otter3dof", 0) != 0;
  };
  const auto& kinds = standard_kinds();
  int sim_faults = 0, sim_detected = 0;
  for (const TableSummary& t : tables) {
    if (t.name.rfind("kvlcc2-hsva", 0) == 0) continue;
    SCOPED_TRACE(t.name);
    const MethodSummary& o = t.m[kOracle];
    EXPECT_EQ(o.armed_at_onset, o.faults);
    for (std::size_t i = 0; i < kinds.size(); ++i) {
      if (kinds[i] == FaultKind::kScale) continue;
      sim_faults += o.per_kind[i][0];
      sim_detected += o.per_kind[i][1];
      if (o.false_alarms == 0 && linearisation_holds(t.name)) {
        EXPECT_EQ(o.per_kind[i][1], o.per_kind[i][0]) << to_string(kinds[i]);
        EXPECT_EQ(o.per_kind[i][2], o.per_kind[i][0]) << to_string(kinds[i]);
      }
    }
  }
  EXPECT_GE(sim_detected, 0.9 * sim_faults);

  // Where the faults are missed: the rows cover every fault of every table once, per data
  // class, sensor and kind, and add up to each method's totals; early detections are a part
  // of the detected, isolated ones too.
  const std::vector<BreakdownRow> rows = breakdown(cases, results);
  std::map<std::string, int> class_faults;
  for (const Case& c : cases) {
    if (c.faulty) ++class_faults[data_class(c)];
  }
  EXPECT_EQ(class_faults.count("calm"), 1u);  // the quick mode's only voyage
  EXPECT_EQ(class_faults.count("HSVA recorded"), opt.realdata_dir.empty() ? 0u : 1u);
  std::map<std::string, int> row_faults;
  std::array<std::array<int, 2>, kMethods> sums{};
  for (const BreakdownRow& r : rows) {
    SCOPED_TRACE(r.data + " " + to_string(r.sensor) + " " + to_string(r.kind));
    EXPECT_NE(r.sensor, Sensor::kUnknown);
    row_faults[r.data] += r.faults;
    for (int k = 0; k < kMethods; ++k) {
      EXPECT_LE(r.m[k][0], r.faults);
      EXPECT_LE(r.m[k][1], r.m[k][0]);
      EXPECT_LE(r.m[k][2], r.m[k][0]);
      EXPECT_LE(r.m[k][3], r.m[k][1]);  // held: isolated, and raised until the end
      sums[k][0] += r.m[k][0];
      sums[k][1] += r.m[k][1];
    }
  }
  EXPECT_EQ(row_faults, class_faults);
  for (int k = 0; k < kMethods; ++k) {
    int detected = 0, isolated = 0, early = 0, rows_early = 0;
    for (const TableSummary& t : tables) {
      detected += t.m[k].detected;
      isolated += t.m[k].isolated;
    }
    for (const CaseResult& r : results) {
      for (const FaultScore& f : r.m[k].score.faults) {
        early += f.detected && f.delay <= BreakdownRow::kEarly ? 1 : 0;
      }
    }
    for (const BreakdownRow& r : rows) rows_early += r.m[k][2];
    EXPECT_EQ(sums[k][0], detected) << method_name(k);
    EXPECT_EQ(sums[k][1], isolated) << method_name(k);
    EXPECT_EQ(rows_early, early) << method_name(k);
  }
  const std::string md = to_markdown(tables, "quick", rows);
  EXPECT_NE(md.find("| calm | gyro | bias | " + std::to_string(class_faults["calm"] / 10) + " |"),
            std::string::npos);

  // Per run, too: the JSON names every run.
  const std::string json = to_json(cases, results, tables, "quick");
  EXPECT_NE(json.find("\"oracle\""), std::string::npos);
}

}  // namespace
}  // namespace usvfdi::bench
