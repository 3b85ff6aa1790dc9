// CSV reader and writer.
#include <gtest/gtest.h>

#include <chrono>
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

TEST(Csv, ReadsTheOptionalSpeedColumn) {
  // Without a u column the speed is not measured; with one it is read (empty: missing).
  auto plain = reader("t,v,r,delta\n0,0,0,0\n");
  Sample s;
  ASSERT_TRUE(plain->next(&s));
  EXPECT_TRUE(std::isnan(s.u));
  auto with_u = reader("t,u,v,r,delta\n0,2.5,0,0,0\n1,,0,0,0\n");
  ASSERT_TRUE(with_u->next(&s));
  EXPECT_EQ(s.u, 2.5);
  ASSERT_TRUE(with_u->next(&s));
  EXPECT_TRUE(std::isnan(s.u));
  const InputError e = error_of("t,v,r,delta,u\n0,0,0,0,fast\n");
  EXPECT_EQ(e.column(), "u");
  EXPECT_TRUE(contains(e.what(), "fast")) << e.what();
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

TEST(CsvError, NulByteIsRefused) {
  const InputError e = error_of(std::string("t,v,r,delta\n0,0,0,0\n0.1,0\0,0,0\n", 31));
  EXPECT_EQ(e.line(), 3u);
  EXPECT_TRUE(contains(e.what(), "NUL byte")) << e.what();
  EXPECT_TRUE(contains(e.what(), "in_test.csv:3")) << e.what();
}

TEST(CsvError, CrOnlyLineEndsAreNamed) {
  const InputError e = error_of("t,v,r,delta\r0,0,0,0\r0.1,0,0,0\r");
  EXPECT_TRUE(contains(e.what(), "CR")) << e.what();
  EXPECT_FALSE(contains(e.what(), "named twice")) << e.what();
}

TEST(CsvError, HugeHeaderAndHugeLineAreRefusedQuickly) {
  // 100 000 columns (0.9 MB) in the header
  std::string header = "t,v,r,delta";
  for (int i = 0; i < 100000; ++i) header += ",c" + std::to_string(i);
  const auto start = std::chrono::steady_clock::now();
  InputError e = error_of(header + "\n0,0,0,0\n");
  EXPECT_EQ(e.line(), 1u);
  EXPECT_TRUE(contains(e.what(), "longer than")) << e.what();
  // 2000 short columns: within the line limit, beyond the column limit
  std::string wide = "t,v,r,delta";
  for (int i = 0; i < 2000; ++i) wide += ",c" + std::to_string(i);
  e = error_of(wide + "\n");
  EXPECT_TRUE(contains(e.what(), "2004 columns")) << e.what();
  EXPECT_TRUE(contains(e.what(), std::to_string(kCsvMaxColumns))) << e.what();
  // a 32 MB data line (the 300 MB of the issue behave the same): refused after reading
  // kCsvMaxLine bytes of it
  std::string big = "t,v,r,delta\n0,0,0,0\n";
  big.append(32u << 20, '1');
  e = error_of(big);
  EXPECT_EQ(e.line(), 3u);
  EXPECT_TRUE(contains(e.what(), "line longer than " + std::to_string(kCsvMaxLine))) << e.what();
  // a busy machine may be slow, but not by the 22 s of the quadratic header check
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
}

TEST(Csv, LinesUpToTheLimitAreRead) {
  std::string text = "t,v,r,delta\n0,0,0,0\n0.1,0,0,";
  text.append(kCsvMaxLine - 9, ' ');  // exactly kCsvMaxLine bytes
  text += "0\n";
  auto r = reader(text);
  Sample s;
  EXPECT_TRUE(r->next(&s));
  EXPECT_TRUE(r->next(&s));
  EXPECT_EQ(s.t, 0.1);
  EXPECT_FALSE(r->next(&s));
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
