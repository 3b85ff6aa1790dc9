// Units of `usv-fdi bridge` (src/app/bridge_alerts.*): how a latched instance is shown as
// IEC 62923 ALF sentences, the ALC list, and what an ACN from the bridge may do. No DDS.
#include <gtest/gtest.h>

#include "bridge_alerts.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::app {
namespace {

Row row(Sensor s, FaultState st, std::uint64_t seq) {
  Row r;
  r.mmsi = 257000001;
  r.ev.sensor = s;
  r.ev.state = st;
  r.ev.sequence = seq;
  r.ev.kind = FaultKind::kBias;
  r.ev.c_a = 0.03;
  r.ev.c_g = 0.99;
  return r;
}

nmea::Acn acn(long id, nmea::AlertCommand c, const std::string& manufacturer = "UFD",
              long instance = 1) {
  nmea::Acn a;
  a.alert.manufacturer = manufacturer;
  a.alert.id = id;
  a.alert.instance = instance;
  a.command = c;
  return a;
}

TEST(BridgeAlerts, LatchedStatesMapToIec62923States) {
  EXPECT_EQ(alert_state(FaultState::kRaised), nmea::AlertState::kActiveUnacknowledged);
  EXPECT_EQ(alert_state(FaultState::kActiveAcknowledged), nmea::AlertState::kActiveAcknowledged);
  EXPECT_EQ(alert_state(FaultState::kClearedUnacknowledged),
            nmea::AlertState::kRectifiedUnacknowledged);
  EXPECT_EQ(alert_state(FaultState::kAcknowledged), nmea::AlertState::kNormal);
  EXPECT_EQ(alert_state(FaultState::kNormal), nmea::AlertState::kNormal);
}

TEST(BridgeAlerts, RevisionFollowsTheSequenceAndWrapsAfter99) {
  EXPECT_EQ(alert_revision(0), 1);
  EXPECT_EQ(alert_revision(1), 1);
  EXPECT_EQ(alert_revision(2), 2);
  EXPECT_EQ(alert_revision(99), 99);
  EXPECT_EQ(alert_revision(100), 1);
  EXPECT_EQ(alert_revision(101), 2);
}

TEST(BridgeAlerts, AlfSentencesParseBackWithStateRevisionAndIdentity) {
  BridgeAlertConfig c;
  c.alert_ids = {4001, 4002, 4003};
  c.priority = nmea::AlertPriority::kCaution;
  const auto lines = alf_sentences(c, row(Sensor::kGyro, FaultState::kClearedUnacknowledged, 103),
                                   7, nmea::UtcTime{12, 34, 5678});
  ASSERT_EQ(lines.size(), 2u);  // title and description
  const auto s1 = nmea::parse_sentence(lines[0]);
  ASSERT_TRUE(s1.ok()) << lines[0];
  const auto alf = nmea::parse_alf(s1.value());
  ASSERT_TRUE(alf.ok()) << lines[0];
  EXPECT_EQ(alf.value().talker, "II");
  EXPECT_EQ(alf.value().message_id, 7);
  EXPECT_EQ(alf.value().state, nmea::AlertState::kRectifiedUnacknowledged);
  EXPECT_EQ(alf.value().priority, nmea::AlertPriority::kCaution);
  EXPECT_EQ(alf.value().category, nmea::AlertCategory::kB);
  EXPECT_EQ(alf.value().alert.manufacturer, "UFD");
  EXPECT_EQ(alf.value().alert.id, 4002);
  EXPECT_EQ(alf.value().alert.instance, 1);
  EXPECT_EQ(alf.value().revision, 4);  // sequence 103: 1..99, then 1 (100), 2, 3, 4 (103)
  EXPECT_EQ(alf.value().text, "INS gyro fault");
  const auto alf2 = nmea::parse_alf(nmea::parse_sentence(lines[1]).value());
  ASSERT_TRUE(alf2.ok()) << lines[1];
  EXPECT_EQ(alf2.value().sentence_number, 2);
  EXPECT_NE(alf2.value().text.find("bias"), std::string::npos) << alf2.value().text;
  EXPECT_NE(alf2.value().text.find("Cg 0.99"), std::string::npos) << alf2.value().text;
  for (const auto& l : lines) EXPECT_LE(l.size(), 82u) << l;
}

TEST(BridgeAlerts, AlcListsOnlyAlertsThatAreNotNormal) {
  BridgeAlertConfig c;
  const std::vector<Row> rows = {row(Sensor::kGyro, FaultState::kRaised, 3),
                                 row(Sensor::kAccelerometer, FaultState::kAcknowledged, 4),
                                 row(Sensor::kUnknown, FaultState::kActiveAcknowledged, 2)};
  const auto e = alc_entries(c, rows);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].alert.id, 3002);
  EXPECT_EQ(e[0].revision, 3);
  EXPECT_EQ(e[1].alert.id, 3003);
  EXPECT_EQ(e[1].revision, 2);
}

TEST(BridgeAlerts, AcnAcknowledgesTheRevisionInForceOfARaisedOrClearedInstance) {
  BridgeAlertConfig c;
  for (FaultState st : {FaultState::kRaised, FaultState::kClearedUnacknowledged}) {
    const Row r = row(Sensor::kGyro, st, 6);
    const AcnAction a = judge_acn(c, 257000001, acn(3002, nmea::AlertCommand::kAcknowledge), &r);
    EXPECT_EQ(a.what, AcnAction::kAcknowledge) << to_string(st);
    EXPECT_EQ(a.ack.mmsi, 257000001u);
    EXPECT_EQ(a.ack.sensor, Sensor::kGyro);
    EXPECT_EQ(a.ack.sequence, 6u);
  }
}

TEST(BridgeAlerts, AcnWithNothingToAcknowledgeIsRefused) {
  BridgeAlertConfig c;
  for (FaultState st :
       {FaultState::kNormal, FaultState::kActiveAcknowledged, FaultState::kAcknowledged}) {
    const Row r = row(Sensor::kAccelerometer, st, 2);
    const AcnAction a = judge_acn(c, 1, acn(3001, nmea::AlertCommand::kAcknowledge), &r);
    EXPECT_EQ(a.what, AcnAction::kRefuse) << to_string(st);
    EXPECT_NE(a.why.find("nothing to acknowledge"), std::string::npos) << a.why;
  }
  const AcnAction none = judge_acn(c, 1, acn(3001, nmea::AlertCommand::kAcknowledge), nullptr);
  EXPECT_EQ(none.what, AcnAction::kRefuse);
  Row gone = row(Sensor::kAccelerometer, FaultState::kRaised, 2);
  gone.alive = false;
  EXPECT_EQ(judge_acn(c, 1, acn(3001, nmea::AlertCommand::kAcknowledge), &gone).what,
            AcnAction::kRefuse);
}

TEST(BridgeAlerts, SilenceAndResponsibilityTransferAreRefusedRepeatIsAnswered) {
  BridgeAlertConfig c;
  const Row r = row(Sensor::kGyro, FaultState::kRaised, 1);
  EXPECT_EQ(judge_acn(c, 1, acn(3002, nmea::AlertCommand::kSilence), &r).what, AcnAction::kRefuse);
  EXPECT_EQ(judge_acn(c, 1, acn(3002, nmea::AlertCommand::kResponsibilityTransfer), &r).what,
            AcnAction::kRefuse);
  EXPECT_EQ(judge_acn(c, 1, acn(3002, nmea::AlertCommand::kRequestRepeat), &r).what,
            AcnAction::kRepeat);
}

TEST(BridgeAlerts, OtherEquipmentsAlertsAreNotOurs) {
  BridgeAlertConfig c;
  const Row r = row(Sensor::kGyro, FaultState::kRaised, 1);
  EXPECT_EQ(judge_acn(c, 1, acn(3002, nmea::AlertCommand::kAcknowledge, "XYZ"), &r).what,
            AcnAction::kNotOurs);
  EXPECT_EQ(judge_acn(c, 1, acn(9999, nmea::AlertCommand::kAcknowledge), &r).what,
            AcnAction::kNotOurs);
  EXPECT_EQ(judge_acn(c, 1, acn(3002, nmea::AlertCommand::kAcknowledge, "UFD", 2), &r).what,
            AcnAction::kNotOurs);
}

TEST(BridgeAlerts, ConfigurationMistakesAreNamed) {
  BridgeAlertConfig c;
  EXPECT_EQ(check(c), "");
  c.manufacturer = "uf";
  EXPECT_NE(check(c).find("manufacturer"), std::string::npos);
  c = BridgeAlertConfig{};
  c.alert_ids = {1, 1, 2};
  EXPECT_NE(check(c).find("given twice"), std::string::npos);
  c = BridgeAlertConfig{};
  c.instance = 0;
  EXPECT_NE(check(c).find("instance"), std::string::npos);
  c = BridgeAlertConfig{};
  c.talker = "i1";
  EXPECT_NE(check(c).find("talker"), std::string::npos);
}

TEST(BridgeAlerts, UtcTimeOfDay) {
  const nmea::UtcTime t = utc_time_of(86400.0 * 20000 + 3600.0 * 13 + 60.0 * 7 + 9.25);
  EXPECT_EQ(t.hours, 13);
  EXPECT_EQ(t.minutes, 7);
  EXPECT_EQ(t.centiseconds, 925);
}

}  // namespace
}  // namespace usvfdi::app
