// The monitor's units without DDS (issue 9, item 7): the ack protocol and the formatting. (The
// fleet view's logic is InstanceOwners and VesselLiveness, tested in their own files.)
#include <gtest/gtest.h>

#include <string>

#include "ack_protocol.hpp"
#include "io/json_lite.hpp"
#include "monitor_format.hpp"

namespace usvfdi::app {
namespace {

namespace js = usvfdi::testing_json;

Row row(FaultState state, std::uint64_t seq, const std::string& message = "residual") {
  Row r;
  r.mmsi = 257000001;
  r.ev.sensor = Sensor::kGyro;
  r.ev.state = state;
  r.ev.kind = FaultKind::kBias;
  r.ev.sequence = seq;
  r.ev.c_g = 1.0;
  r.ev.t = 41.4;
  r.ev.message = message;
  r.written = 1000.0;
  r.writer = "w1";
  return r;
}

TEST(AckProtocol, ParsesTheSpecAndNamesWhatIsWrong) {
  AckRequest a;
  std::string why;
  ASSERT_TRUE(parse_ack("257000001:gyro:3", &a, &why)) << why;
  EXPECT_EQ(a.mmsi, 257000001u);
  EXPECT_EQ(a.sensor, Sensor::kGyro);
  EXPECT_EQ(a.sequence, 3u);
  EXPECT_FALSE(parse_ack("257000001:gyro", &a, &why));
  EXPECT_NE(why.find("expected MMSI:SENSOR:SEQUENCE"), std::string::npos) << why;
  EXPECT_FALSE(parse_ack("257000001:compass:3", &a, &why));
  EXPECT_NE(why.find("sensor 'compass'"), std::string::npos) << why;
  EXPECT_FALSE(parse_ack("257000001:gyro:0", &a, &why));
  EXPECT_FALSE(parse_ack("1000000000:gyro:1", &a, &why));
  EXPECT_FALSE(parse_ack("25700000x:gyro:1", &a, &why));
  EXPECT_NE(why.find("must be integers"), std::string::npos) << why;
}

TEST(AckProtocol, ConfirmedOnlyWhenTheInstanceMovesPastToAnAcknowledgedState) {
  AckRequest a{257000001, Sensor::kGyro, 2};
  const Row cleared = row(FaultState::kClearedUnacknowledged, 2);
  const Row acked = row(FaultState::kAcknowledged, 3);
  const Row raised_again = row(FaultState::kRaised, 3);
  EXPECT_FALSE(ack_confirmed(a, nullptr));
  EXPECT_FALSE(ack_confirmed(a, &cleared));
  EXPECT_TRUE(ack_confirmed(a, &acked));
  EXPECT_FALSE(ack_confirmed(a, &raised_again));
  EXPECT_TRUE(ack_already_past(a, &raised_again));
  EXPECT_FALSE(ack_already_past(a, &cleared));
}

TEST(AckProtocol, TheRefusalReasonFromTheLatchedState) {
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 2}, nullptr),
            "no such fault instance is latched on this domain/partition");
  const Row r = row(FaultState::kClearedUnacknowledged, 3);
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 2}, &r), "stale sequence (current #3, cleared)");
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 4}, &r), "unknown sequence (current #3, cleared)");
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 3}, &r),
            "no confirmation from the sidecar (current #3, cleared)");
  const Row n = row(FaultState::kNormal, 3);
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 3}, &n),
            "nothing to acknowledge (current #3, normal)");
}

TEST(AckProtocol, AnAckIsWrittenIntoItsVesselsPartitionOnly) {
  EXPECT_EQ(ack_partitions({"vessel-*"}, 257000002), std::vector<std::string>{"vessel-257000002"});
  EXPECT_EQ(ack_partitions({"t_12_vessel-*"}, 7), std::vector<std::string>{"t_12_vessel-7"});
  EXPECT_EQ(ack_partitions({"fleet"}, 7), std::vector<std::string>{"fleet"});
  EXPECT_EQ(ack_partitions({}, 7), std::vector<std::string>{});
}

TEST(MonitorFormat, AFaultRowAsJson) {
  const js::Value v =
      js::Parser(json_row(row(FaultState::kRaised, 1, "J_N \x1b[2J 14 > 12"), 0.5, 1002.0))
          .parse_document();
  EXPECT_EQ(v.at("type").str, "fault");
  EXPECT_EQ(v.at("mmsi").num, 257000001);
  EXPECT_EQ(v.at("sensor").str, "gyro");
  EXPECT_EQ(v.at("state").str, "raised");
  EXPECT_EQ(v.at("sequence").num, 1);
  EXPECT_EQ(v.at("age_s").num, 2.0);
  EXPECT_EQ(v.at("heard_age_s").num, 0.5);
  EXPECT_TRUE(v.at("alive").b);
  EXPECT_EQ(v.at("message").str, "J_N \\x1b[2J 14 > 12");
}

TEST(MonitorFormat, TheTableEscapesMessagesAndMarksGoneSidecarsAndConflicts) {
  InstanceOwners<RowKey, Row> rows;
  Row r = row(FaultState::kRaised, 1, "all clear\r\x1b[31m");
  r.alive = false;
  rows.offer({r.mmsi, 1}, r.mmsi, WriterRef{"w1", 0}, 1, r);
  VesselLiveness live(5.0);
  VesselLiveness::Change c;
  live.heard(257000001, 10.0, &c);
  const std::string t = format_table(rows, nullptr, live, 2, 1003.0, 11.0);
  EXPECT_EQ(t.find('\x1b'), std::string::npos) << t;
  EXPECT_EQ(t.find('\r'), std::string::npos) << t;
  EXPECT_NE(t.find("all clear\\r\\x1b[31m"), std::string::npos) << t;
  EXPECT_NE(t.find("raised?"), std::string::npos) << t;
  EXPECT_NE(t.find("'?': sidecar gone"), std::string::npos) << t;
  EXPECT_NE(t.find("!! 2 conflicting writer(s)"), std::string::npos) << t;
  EXPECT_NE(t.find("vessel 257000001 (sidecar gone): last heard 1.0 s ago"), std::string::npos)
      << t;
}

TEST(MonitorFormat, AConflictAsJson) {
  OwnerDecision d;
  d.verdict = OwnerDecision::Verdict::kRefused;
  d.why = OwnerDecision::Why::kForeignVessel;
  d.owner = WriterRef{"owner-guid", 7};
  d.owner_sequence = 1;
  const js::Value v =
      js::Parser(json_conflict(d, 7, "gyro", "forger-guid", 100, "normal")).parse_document();
  EXPECT_EQ(v.at("type").str, "conflict");
  EXPECT_EQ(v.at("verdict").str, "refused");
  EXPECT_EQ(v.at("why").str, "writer confined to another vessel");
  EXPECT_EQ(v.at("writer").str, "forger-guid");
  EXPECT_EQ(v.at("owner").str, "owner-guid");
  EXPECT_EQ(v.at("sequence").num, 100);
  EXPECT_EQ(v.at("owner_sequence").num, 1);
}

TEST(MonitorFormat, SilenceChanges) {
  EXPECT_EQ(change_line({257000001, true, 5.1, 0.0}, 5.0),
            "vessel 257000001 silent: nothing heard for 5.1 s (> 5 s)");
  EXPECT_EQ(change_line({257000001, false, 0.0, 9.8}, 5.0),
            "vessel 257000001 heard again after 9.8 s of silence");
  const js::Value v = js::Parser(json_change({257000001, false, 0.0, 9.8}, 5.0)).parse_document();
  EXPECT_EQ(v.at("type").str, "vessel");
  EXPECT_FALSE(v.at("silent").b);
  EXPECT_EQ(v.at("gap_s").num, 9.8);
}

}  // namespace
}  // namespace usvfdi::app
