// CSV reader and writer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/csv.hpp"

namespace usvfdi::io {
namespace {

std::unique_ptr<CsvSampleReader> reader(const std::string& text) {
  return std::make_unique<CsvSampleReader>(std::make_unique<std::istringstream>(text),
                                           "in_test.csv");
}

/// The InputError of reading all of `text` (fails the test if there is none).
InputError error_of(const std::string& text) {
  try {
    auto r = reader(text);
    Sample s;
    while (r->next(&s)) {
    }
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return InputError("", 0, "", "", "");
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(Csv, ReadsRequiredColumnsInAnyOrderAndIgnoresOthers) {
  auto r = reader("delta,extra,r,t,v\n0.1,x,0.02,1.5,-0.3\n0.2,y,0.03,1.6,-0.4\n");
  Sample s;
  ASSERT_TRUE(r->next(&s));
  EXPECT_EQ(s.t, 1.5);
  EXPECT_EQ(s.v, -0.3);
  EXPECT_EQ(s.r, 0.02);
  EXPECT_EQ(s.delta, 0.1);
  ASSERT_TRUE(r->next(&s));
  EXPECT_EQ(s.t, 1.6);
  EXPECT_FALSE(r->next(&s));
  EXPECT_EQ(r->rows(), 2u);
}

TEST(Csv, MissingValuesAreNaN) {
  auto r = reader("t,v,r,delta\n0,nan,NaN,\n1, ,1e-3,0\n");
  Sample s;
  ASSERT_TRUE(r->next(&s));
  EXPECT_EQ(s.t, 0.0);
  EXPECT_TRUE(std::isnan(s.v));
  EXPECT_TRUE(std::isnan(s.r));
  EXPECT_TRUE(std::isnan(s.delta));
  ASSERT_TRUE(r->next(&s));
  EXPECT_TRUE(std::isnan(s.v));
  EXPECT_EQ(s.r, 1e-3);
}

TEST(Csv, AcceptsCrlfCommentsBlankLinesAndInfinity) {
  auto r = reader("\xEF\xBB\xBFt,v,r,delta\r\n# comment\r\n\r\n0,inf,-inf,0.5\r\n");
  Sample s;
  ASSERT_TRUE(r->next(&s));
  EXPECT_TRUE(std::isinf(s.v));
  EXPECT_TRUE(std::isinf(s.r));
  EXPECT_EQ(s.delta, 0.5);
  EXPECT_EQ(r->line(), 4u);
}

TEST(CsvError, MissingColumnNamesFileAndColumn) {
  const InputError e = error_of("t,v,rr,delta\n0,0,0,0\n");
  EXPECT_EQ(e.column(), "r");
  EXPECT_EQ(e.line(), 1u);
  EXPECT_TRUE(contains(e.what(), "in_test.csv:1")) << e.what();
  EXPECT_TRUE(contains(e.what(), "'r'")) << e.what();
  EXPECT_TRUE(contains(e.what(), "t,v,rr,delta")) << e.what();
}

TEST(CsvError, BadNumberNamesFileLineColumnAndText) {
  const InputError e = error_of("t,v,r,delta\n0,0,0,0\n# note\n0.1,0.5x,0,0\n");
  EXPECT_EQ(e.line(), 4u);
  EXPECT_EQ(e.column(), "v");
  EXPECT_EQ(e.text(), "0.5x");
  EXPECT_TRUE(contains(e.what(), "in_test.csv:4")) << e.what();
  EXPECT_TRUE(contains(e.what(), "column 'v'")) << e.what();
  EXPECT_TRUE(contains(e.what(), "'0.5x'")) << e.what();
  EXPECT_EQ(error_of("t,v,r,delta\n0,0,0,abc\n").column(), "delta");
  EXPECT_EQ(error_of("t,v,r,delta\n1 2,0,0,0\n").column(), "t");
}

TEST(CsvError, RaggedRowNamesFileLineAndRow) {
  const InputError e = error_of("t,v,r,delta\n0,0,0,0\n0.1,0,0\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_TRUE(contains(e.what(), "in_test.csv:3")) << e.what();
  EXPECT_TRUE(contains(e.what(), "got 3")) << e.what();
  EXPECT_TRUE(contains(e.what(), "'0.1,0,0'")) << e.what();
  EXPECT_EQ(error_of("t,v,r,delta\n0,0,0,0,0\n").line(), 2u);
}

TEST(CsvError, EmptyFileAndMissingFile) {
  EXPECT_TRUE(contains(error_of("").what(), "in_test.csv")) << error_of("").what();
  EXPECT_TRUE(contains(error_of("\n# only a comment\n").what(), "empty"));
  try {
    CsvSampleReader r("/nonexistent/input.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "/nonexistent/input.csv")) << e.what();
  }
}

TEST(CsvError, DuplicateColumn) {
  const InputError e = error_of("t,v,r,delta,v\n0,0,0,0,0\n");
  EXPECT_EQ(e.column(), "v");
}

TEST(Csv, SimulatorRowsRoundTripBitForBit) {
  // %.17g: a CSV replay sees exactly the doubles of the in-memory simulation.
  SimConfig c = paper_scenario(otter(), 50.0, 3);
  c.duration = 10.0;
  c.faults.push_back({Sensor::kAccelerometer, FaultKind::kStale, 2.0, 3.0, 0.0, 2.0});
  c.faults.push_back({Sensor::kGyro, FaultKind::kInvalid, 4.0, 4.5, 0.0, 2.0});
  c.faults.push_back({Sensor::kGyro, FaultKind::kBias, 5.0, 6.0, 0.01, 2.0});
  const std::vector<SimRow> rows = simulate(c);
  auto text = std::make_unique<std::stringstream>();
  {
    SimCsvWriter w(*text);
    for (const SimRow& row : rows) w.write(row);
  }
  const std::string csv = text->str();
  CsvSampleReader r(std::move(text), "sim.csv");
  Sample s;
  std::size_t i = 0;
  int nans = 0, infs = 0;
  while (r.next(&s)) {
    ASSERT_LT(i, rows.size());
    const SimRow& w = rows[i++];
    const double got[4] = {s.t, s.v, s.r, s.delta};
    const double want[4] = {w.t, w.v, w.r, w.delta};
    for (int k = 0; k < 4; ++k) {
      if (std::isnan(want[k])) {
        EXPECT_TRUE(std::isnan(got[k]));
        ++nans;
      } else {
        if (std::isinf(want[k])) ++infs;
        EXPECT_EQ(std::memcmp(&got[k], &want[k], sizeof(double)), 0)
            << "row " << i << " col " << k << ": " << got[k] << " vs " << want[k];
      }
    }
  }
  EXPECT_EQ(i, rows.size());
  EXPECT_GT(nans, 0);
  EXPECT_GT(infs, 0);
  // fault columns hold the kind names
  EXPECT_TRUE(contains(csv, ",stale,")) << "accelerometer stale column";
  EXPECT_TRUE(contains(csv, ",bias\n"));
  EXPECT_TRUE(contains(csv, ",invalid\n"));
}

}  // namespace
}  // namespace usvfdi::io
