// Plausibility warnings on a replay's input (unit mistakes, empty columns) and the
// non-converged summary.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/plausibility.hpp"
#include "usv_fdi/io/replay.hpp"

namespace usvfdi::io {
namespace {

/// 120 s of the paper scenario on the Otter at 10 Hz, each sample passed through `change`.
std::vector<Sample> voyage(const std::function<void(Sample*)>& change = {},
                           bool with_faults = true) {
  SimConfig c = paper_scenario(otter(), 10.0, 3);
  c.duration = 120.0;
  if (!with_faults) c.faults.clear();
  std::vector<Sample> out;
  for (const SimRow& row : simulate(c)) {
    Sample s{row.t, row.v, row.r, row.delta};
    if (change) change(&s);
    out.push_back(s);
  }
  return out;
}

std::vector<std::string> warnings_of(const std::vector<Sample>& samples) {
  PlausibilityCheck check;
  for (const Sample& s : samples) check.add(s);
  return check.warnings();
}

std::string joined(const std::vector<std::string>& w) {
  std::string s;
  for (const std::string& x : w) s += x + "\n";
  return s;
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(Plausibility, AHealthyVoyageGivesNoWarning) { EXPECT_EQ(joined(warnings_of(voyage())), ""); }

TEST(Plausibility, RudderInDegreesIsNamed) {
  const auto w = warnings_of(voyage([](Sample* s) { s->delta *= 180.0 / M_PI; }));
  ASSERT_EQ(w.size(), 1u) << joined(w);
  EXPECT_TRUE(has(w[0], "column 'delta'")) << w[0];
  EXPECT_TRUE(has(w[0], "probably in degrees")) << w[0];
  // a few wild values are the isolation's business, not a unit mistake
  int n = 0;
  EXPECT_EQ(joined(warnings_of(voyage([&n](Sample* s) {
              if (++n == 500) s->delta = 30.0;
            }))),
            "");
}

TEST(Plausibility, YawRateInDegreesPerSecondIsNamed) {
  const auto w = warnings_of(voyage([](Sample* s) { s->r *= 180.0 / M_PI * 20.0; }));
  ASSERT_EQ(w.size(), 1u) << joined(w);
  EXPECT_TRUE(has(w[0], "column 'r'")) << w[0];
  EXPECT_TRUE(has(w[0], "degrees per second")) << w[0];
}

TEST(Plausibility, TimeInMillisecondsIsNamed) {
  const auto w = warnings_of(voyage([](Sample* s) { s->t *= 1000.0; }));
  ASSERT_EQ(w.size(), 1u) << joined(w);
  EXPECT_TRUE(has(w[0], "column 't'")) << w[0];
  EXPECT_TRUE(has(w[0], "100 s")) << w[0];
  EXPECT_TRUE(has(w[0], "probably in milliseconds (100 ms = 10 Hz)")) << w[0];
  const auto us = warnings_of(voyage([](Sample* s) { s->t *= 1e6; }));
  ASSERT_EQ(us.size(), 1u) << joined(us);
  EXPECT_TRUE(has(us[0], "microseconds")) << us[0];
}

TEST(Plausibility, EmptyAndMostlyMissingColumnsAreNamed) {
  auto w = warnings_of(voyage([](Sample* s) { s->delta = kNaN; }));
  ASSERT_EQ(w.size(), 1u) << joined(w);
  EXPECT_TRUE(has(w[0], "column 'delta': no value in any of the 1201 rows")) << w[0];
  int n = 0;
  w = warnings_of(voyage([&n](Sample* s) {
    if (++n % 3 != 0) s->v = kNaN;
  }));
  ASSERT_EQ(w.size(), 1u) << joined(w);
  EXPECT_TRUE(has(w[0], "column 'v': 801 of 1201 values")) << w[0];
}

TEST(Plausibility, ConvergenceReportSaysWhy) {
  const EngineConfig cfg =
      load_engine_config(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/otter.yaml");
  const auto run = [&cfg](const std::vector<Sample>& samples) {
    FdiEngine engine(cfg);
    std::vector<FaultEvent> events;
    for (const Sample& s : samples) engine.process(s, &events);
    return engine.estimate();
  };
  // (the paper's faults left out: the jump check raises them, and identification rightly
  // does not learn from the 20 + 20 s they last and the 10 s after each)
  const Estimate good = run(voyage({}, false));
  ASSERT_TRUE(good.converged);
  EXPECT_EQ(convergence_report(good, cfg.identification), "");

  // A rudder that never moves excites nothing.
  const std::string still =
      convergence_report(run(voyage([](Sample* s) { s->delta = 0.0; })), cfg.identification);
  EXPECT_TRUE(has(still, "not converged")) << still;
  EXPECT_TRUE(has(still, "below identification.min_excitation")) << still;

  // 8 s of data: the filters are still warming up.
  std::vector<Sample> short_run = voyage();
  short_run.resize(80);
  const std::string early = convergence_report(run(short_run), cfg.identification);
  EXPECT_TRUE(has(early, "warmup_time")) << early;

  // A converged estimate whose uncertainty grew (Identifier's own test makes one).
  Estimate lost = good;
  lost.converged = false;
  lost.status = IdentStatus::kUncertain;
  lost.unconvergences = 2;
  lost.uncertainty = 0.3;
  const std::string grew = convergence_report(lost, cfg.identification);
  EXPECT_TRUE(has(grew, "uncertainty grew after convergence")) << grew;
  EXPECT_TRUE(has(grew, "lost convergence 2 time(s)")) << grew;
  EXPECT_TRUE(has(grew, "identification.uncertain_ratio")) << grew;
}

TEST(Plausibility, ReplaySummaryCarriesTheFindings) {
  std::ostringstream csv;
  csv << "t,v,r,delta\n";
  for (const Sample& s : voyage([](Sample* x) { x->delta *= 180.0 / M_PI; })) {
    csv << s.t << "," << s.v << "," << s.r << "," << s.delta << "\n";
  }
  CsvSampleReader reader(std::make_unique<std::istringstream>(csv.str()), "deg.csv");
  std::ostringstream out;
  JsonlWriter writer(out);
  const EngineConfig cfg =
      load_engine_config(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/otter.yaml");
  const RunSummary sum = replay(cfg, reader, writer);
  ASSERT_EQ(sum.warnings.size(), 1u);
  EXPECT_TRUE(has(sum.warnings[0], "degrees"));
  EXPECT_FALSE(sum.converged);
  EXPECT_TRUE(has(sum.not_converged, "not converged")) << sum.not_converged;
}

}  // namespace
}  // namespace usvfdi::io
