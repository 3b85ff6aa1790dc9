// JSON Lines writer: escaping, numbers, record shapes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "json_lite.hpp"
#include "usv_fdi/io/jsonl.hpp"

namespace usvfdi::io {
namespace {

namespace js = usvfdi::testing_json;

TEST(Jsonl, StringsAreEscaped) {
  EXPECT_EQ(json_string("plain"), "\"plain\"");
  EXPECT_EQ(json_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(json_string("l1\nl2\r\t\b\f"), "\"l1\\nl2\\r\\t\\b\\f\"");
  EXPECT_EQ(json_string(std::string("nul\0x", 5)), "\"nul\\u0000x\"");
  EXPECT_EQ(json_string("\x01\x1f\x7f"), "\"\\u0001\\u001f\\u007f\"");
  EXPECT_EQ(json_string("/"), "\"/\"");
  // valid UTF-8 passes through; invalid bytes become U+FFFD
  EXPECT_EQ(json_string("\xc3\xa9\xe2\x82\xac\xf0\x9f\x9a\xa2"),
            "\"\xc3\xa9\xe2\x82\xac\xf0\x9f\x9a\xa2\"");
  EXPECT_EQ(json_string("\xff"), "\"\\ufffd\"");
  EXPECT_EQ(json_string("\xc3"), "\"\\ufffd\"");                        // truncated sequence
  EXPECT_EQ(json_string("\xc0\xaf"), "\"\\ufffd\\ufffd\"");             // overlong
  EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");  // surrogate
  // and the result always parses back to the input (for valid UTF-8)
  const std::string nasty = "q\"uo\\te\n\t\x02 \xc3\xa9 }{][,:";
  EXPECT_EQ(js::parse(json_string(nasty)).str, nasty);
}

TEST(Jsonl, NumbersUse9DigitsAndNullForNonFinite) {
  EXPECT_EQ(json_number(0.0), "0");
  EXPECT_EQ(json_number(0.1), "0.1");
  EXPECT_EQ(json_number(-1.0 / 3.0), "-0.333333333");
  EXPECT_EQ(json_number(1e-300), "1e-300");
  EXPECT_EQ(json_number(123456789012.0), "1.23456789e+11");
  EXPECT_EQ(json_number(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(json_number(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(json_number(-std::numeric_limits<double>::infinity()), "null");
  for (double x : {1e-300, 123456789012.0, -0.0, 2.5e17}) {
    EXPECT_NO_THROW(js::parse(json_number(x))) << json_number(x);
  }
}

TEST(Jsonl, RecordsAreOneObjectPerLineWithTheirFields) {
  std::ostringstream os;
  JsonlWriter w(os);
  FaultEvent e;
  e.sensor = Sensor::kGyro;
  e.state = FaultState::kClearedUnacknowledged;
  e.kind = FaultKind::kDrift;
  e.c_a = 0.1;
  e.c_g = 0.99;
  e.statistic = 12.5;
  e.threshold = 6.0;
  e.onset_time = 20.25;
  e.detection_time = kNaN;
  e.t = 21.0;
  e.sequence = 3;
  e.A << 1, 2, 3, 4;
  e.message = "residual \"gyro\"\nJ_N > 6";
  w.event(e);
  Estimate est;
  est.A << -1, -2, -3, -4;
  est.converged = true;
  est.excitation = 0.25;
  w.estimate(22.0, est, true);
  RunSummary s;
  s.samples = 100;
  s.rejected = 2;
  s.events = 1;
  s.raised = {0, 1, 0};
  s.final_a = Vec4(-1, -2, -3, -4);
  s.converged = true;
  s.frozen_samples = 7;
  s.unconvergences = 2;
  s.duration_s = 99.0;
  w.summary(s);
  s.complete = false;
  s.error = "in.csv:5: column 'v': not a number: 'x\"'";
  w.summary(s);

  std::istringstream in(os.str());
  std::string line;
  std::vector<js::Value> recs;
  while (std::getline(in, line)) recs.push_back(js::parse(line));
  ASSERT_EQ(recs.size(), 4u);

  const js::Value& ev = recs[0];
  EXPECT_EQ(ev.at("type").str, "event");
  EXPECT_EQ(ev.at("stamp").num, 21.0);
  EXPECT_FALSE(ev.has("t"));  // one name for the event's time, as the journal and monitor
  EXPECT_EQ(ev.at("sensor").str, "gyro");
  EXPECT_EQ(ev.at("state").str, "cleared");
  EXPECT_EQ(ev.at("kind").str, "drift");
  EXPECT_EQ(ev.at("c_g").num, 0.99);
  EXPECT_EQ(ev.at("statistic").num, 12.5);
  EXPECT_EQ(ev.at("threshold").num, 6.0);
  EXPECT_EQ(ev.at("onset_time").num, 20.25);
  EXPECT_EQ(ev.at("detection_time").kind, js::Value::kNull);
  EXPECT_EQ(ev.at("sequence").num, 3.0);
  ASSERT_EQ(ev.at("a").arr.size(), 4u);
  EXPECT_EQ(ev.at("a").arr[1].num, 2.0);  // row-major [a1 a2 a3 a4]
  EXPECT_EQ(ev.at("message").str, e.message);

  const js::Value& es = recs[1];
  EXPECT_EQ(es.at("type").str, "estimate");
  EXPECT_EQ(es.at("t").num, 22.0);
  EXPECT_EQ(es.at("a").arr[2].num, -3.0);
  EXPECT_TRUE(es.at("converged").b);
  EXPECT_EQ(es.at("excitation").num, 0.25);
  EXPECT_TRUE(es.at("armed").b);

  const js::Value& su = recs[2];
  EXPECT_EQ(su.at("type").str, "summary");
  EXPECT_EQ(su.at("samples").num, 100.0);
  EXPECT_EQ(su.at("rejected").num, 2.0);
  EXPECT_EQ(su.at("raised").at("gyro").num, 1.0);
  EXPECT_EQ(su.at("raised").at("accelerometer").num, 0.0);
  EXPECT_EQ(su.at("final_a").arr.size(), 4u);
  EXPECT_EQ(su.at("frozen_samples").num, 7.0);
  EXPECT_EQ(su.at("unconvergences").num, 2.0);
  EXPECT_EQ(su.at("duration_s").num, 99.0);
  EXPECT_TRUE(su.at("complete").b);
  EXPECT_FALSE(su.has("error"));
  EXPECT_FALSE(recs[3].at("complete").b);
  EXPECT_EQ(recs[3].at("error").str, s.error);
}

}  // namespace
}  // namespace usvfdi::io
