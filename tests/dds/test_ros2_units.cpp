// Units of `usv-fdi ros2` without DDS (src/app/ros2_adapter.*): REP 103 signs, stamps, topic
// names, the assembly of INS samples, and the diagnostics levels.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "diagnostic_msgsPubSubTypes.h"
#include "geometry_msgsPubSubTypes.h"
#include "nav_msgsPubSubTypes.h"
#include "ros2_adapter.hpp"
#include "sensor_msgsPubSubTypes.h"
#include "std_msgsPubSubTypes.h"
#include "usv_fdi_msgsPubSubTypes.h"

namespace usvfdi::app::ros2 {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Ros2Signs, AVesselTurningToStarboardHasAPositiveYawRate) {
  // GIVEN a vessel turning to starboard (clockwise seen from above): in REP 103 (z up) its
  // angular_velocity.z is negative
  const double angular_z = -0.05;
  // THEN usv-fdi's r (z down) is positive
  EXPECT_DOUBLE_EQ(yaw_rate_from_rep103(angular_z), 0.05);
  EXPECT_DOUBLE_EQ(rep103_angular_z(yaw_rate_from_rep103(angular_z)), angular_z);
}

TEST(Ros2Signs, AVesselDriftingToStarboardHasAPositiveSwayVelocity) {
  // GIVEN a vessel drifting to starboard: in REP 103 (y to port) linear.y is negative
  const double linear_y = -0.2;
  // THEN usv-fdi's v (y to starboard) is positive
  EXPECT_DOUBLE_EQ(sway_from_rep103(linear_y), 0.2);
  EXPECT_DOUBLE_EQ(rep103_linear_y(sway_from_rep103(linear_y)), linear_y);
}

TEST(Ros2Stamps, SecondsAndNanosecondsRoundTrip) {
  EXPECT_DOUBLE_EQ(stamp_seconds(12, 500000000u), 12.5);
  std::int32_t s = 0;
  std::uint32_t ns = 0;
  to_stamp(20.02, &s, &ns);
  EXPECT_EQ(s, 20);
  EXPECT_NEAR(ns, 20000000u, 1u);
  to_stamp(0.9999999999, &s, &ns);  // rounds up to the next second, never nanosec = 1e9
  EXPECT_EQ(s, 1);
  EXPECT_EQ(ns, 0u);
  to_stamp(1.7e9 + 0.25, &s, &ns);
  EXPECT_EQ(s, 1700000000);
  EXPECT_NEAR(ns, 250000000u, 1000u);
}

TEST(Ros2Topics, AbsoluteAndRelativeNamesMapToRt) {
  EXPECT_EQ(dds_topic_of("/imu/data"), "rt/imu/data");
  EXPECT_EQ(dds_topic_of("imu/data"), "rt/imu/data");
  EXPECT_EQ(dds_topic_of("/diagnostics"), "rt/diagnostics");
  EXPECT_EQ(dds_topic_of(""), "");
  EXPECT_EQ(dds_topic_of("/"), "");
  EXPECT_EQ(dds_topic_of("/imu//data"), "");
  EXPECT_EQ(dds_topic_of("/imu/"), "");
  EXPECT_EQ(dds_topic_of("/imu data"), "");
  EXPECT_EQ(dds_topic_of("/2imu"), "");
}

/// An Imu sample written at its stamp (source timestamp = header stamp).
YawSample yaw(double t, double r) {
  YawSample y;
  y.stamp = t;
  y.sent = t;
  y.r = r;
  y.r_valid = true;
  return y;
}

/// An assembler that has the rudder angle 0.1 written at `t` (before the Imu samples after it).
InsAssembler with_rudder(const AssemblyParams& p, double t = 0.0) {
  InsAssembler a(p);
  a.add_rudder(t, 0.1, true);
  return a;
}

// The type names on the wire, written out as a ROS 2 node (rmw_fastrtps) registers them: the
// adapter and the test's probe share the generated types, so only literal names catch a
// generator that names them otherwise (a reader and writer of different type names never
// match).
TEST(Ros2Types, WireTypeNamesAreThoseOfRos2) {
  EXPECT_STREQ(sensor_msgs::msg::ImuPubSubType().getName(), "sensor_msgs::msg::dds_::Imu_");
  EXPECT_STREQ(geometry_msgs::msg::TwistStampedPubSubType().getName(),
               "geometry_msgs::msg::dds_::TwistStamped_");
  EXPECT_STREQ(nav_msgs::msg::OdometryPubSubType().getName(), "nav_msgs::msg::dds_::Odometry_");
  EXPECT_STREQ(std_msgs::msg::Float64PubSubType().getName(), "std_msgs::msg::dds_::Float64_");
  EXPECT_STREQ(diagnostic_msgs::msg::DiagnosticArrayPubSubType().getName(),
               "diagnostic_msgs::msg::dds_::DiagnosticArray_");
  EXPECT_STREQ(usv_fdi_msgs::msg::FaultEventPubSubType().getName(),
               "usv_fdi_msgs::msg::dds_::FaultEvent_");
  EXPECT_STREQ(usv_fdi_msgs::msg::FdiStatusPubSubType().getName(),
               "usv_fdi_msgs::msg::dds_::FdiStatus_");
  // A keyless type: ROS 2 has no keys, and a keyed writer does not match a keyless reader.
  EXPECT_FALSE(usv_fdi_msgs::msg::FaultEventPubSubType().m_isGetKeyDefined);
  EXPECT_FALSE(sensor_msgs::msg::ImuPubSubType().m_isGetKeyDefined);
}

TEST(Ros2Assembly, AnImuSampleWaitsForTheSwaySampleOfItsStamp) {
  InsAssembler a = with_rudder(AssemblyParams{}, 1.00);
  a.add_yaw(yaw(1.00, 0.01), 0.0);
  EXPECT_TRUE(a.release(0.01).empty()) << "no sway sample at or after 1.00 yet";
  a.add_sway(1.00, 0.3);
  const auto out = a.release(0.02);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].stamp, 1.00);
  EXPECT_DOUBLE_EQ(out[0].v, 0.3);
  EXPECT_TRUE(out[0].v_valid);
  EXPECT_DOUBLE_EQ(out[0].r, 0.01);
  EXPECT_TRUE(out[0].rudder);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.1);
}

TEST(Ros2Assembly, BetweenTwoSwaySamplesVIsInterpolated) {
  InsAssembler a = with_rudder(AssemblyParams{}, 1.05);
  a.add_sway(1.0, 0.2);
  a.add_yaw(yaw(1.05, 0.0), 0.0);
  a.add_sway(1.1, 0.4);
  const auto out = a.release(0.0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].v, 0.3, 1e-12);
  EXPECT_TRUE(out[0].v_valid);
}

TEST(Ros2Assembly, AfterThePairWaitTheLatestSwayIsHeldUntilItIsStale) {
  AssemblyParams p;
  p.sway_max_age = 0.2;
  p.pair_wait = 0.1;
  InsAssembler a = with_rudder(p, 1.25);
  a.add_sway(1.0, 0.2);
  a.add_yaw(yaw(1.15, 0.0), 0.0);  // 0.15 s after the last sway sample: held
  a.add_yaw(yaw(1.25, 0.0), 0.0);  // 0.25 s: stale
  EXPECT_TRUE(a.release(0.05).empty()) << "still waiting for the sway stream";
  const auto out = a.release(0.1);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].v_valid);
  EXPECT_DOUBLE_EQ(out[0].v, 0.2);
  EXPECT_FALSE(out[1].v_valid);
  EXPECT_EQ(a.sway_stale(), 1u);
}

TEST(Ros2Assembly, NoSwayAtAllGivesInvalidVButKeepsR) {
  AssemblyParams p;
  p.pair_wait = 0.0;
  InsAssembler a(p);
  a.add_yaw(yaw(3.0, -0.02), 0.0);
  const auto out = a.release(0.0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_FALSE(out[0].v_valid);
  EXPECT_TRUE(out[0].r_valid);
  EXPECT_DOUBLE_EQ(out[0].r, -0.02);
}

TEST(Ros2Assembly, SamplesLeaveInArrivalOrderAndBackwardSwayStampsAreRefused) {
  InsAssembler a = with_rudder(AssemblyParams{}, 0.08);
  for (int k = 0; k < 5; ++k) a.add_yaw(yaw(0.02 * k, 0.001 * k), 0.0);
  for (int k = 0; k < 5; ++k) a.add_sway(0.02 * k, 0.1 * k);
  a.add_sway(0.02, 9.0);  // backward
  a.add_sway(kNaN, 9.0);
  EXPECT_EQ(a.sway_rejected(), 2u);
  const auto out = a.release(0.0);
  ASSERT_EQ(out.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_DOUBLE_EQ(out[k].stamp, 0.02 * k);
    EXPECT_NEAR(out[k].v, 0.1 * k, 1e-12);
  }
}

TEST(Ros2Assembly, TheRudderAngleIsPairedOnTheWritersClockNotInTheOrderOfArrival) {
  // GIVEN an autopilot that writes the rudder angle just before each Imu sample, and readers
  // that deliver a burst of Imu and sway samples before the rudder angles written among them
  // (each topic's reader has its own delivery thread)
  AssemblyParams p;
  InsAssembler a(p);
  a.add_rudder(-0.001, -1.0, true);
  for (int k = 0; k < 5; ++k) {
    a.add_yaw(yaw(0.02 * k, 0.0), 0.0);
    a.add_sway(0.02 * k, 0.0);
  }
  // THEN the Imu samples wait for the rudder stream rather than take the stale angle
  EXPECT_TRUE(a.release(0.01).empty());
  for (int k = 0; k < 5; ++k) a.add_rudder(0.02 * k - 0.001, 0.01 * k, true);
  // (the last one waits for the next angle: one written before 0.08 s may still be on its way)
  auto out = a.release(0.02);
  EXPECT_EQ(out.size(), 4u);
  a.add_rudder(0.099, 0.05, true);
  for (const AssembledSample& s : a.release(0.02)) out.push_back(s);
  // AND each gets the angle written just before it
  ASSERT_EQ(out.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(out[k].rudder);
    EXPECT_TRUE(out[k].delta_valid);
    EXPECT_DOUBLE_EQ(out[k].delta, 0.01 * k) << "Imu sample " << k;
  }
  EXPECT_EQ(a.without_rudder(), 0u);
}

TEST(Ros2Assembly, AnImuSampleWaitsForTheRudderOnlyUpToThePairWait) {
  // GIVEN a rudder angle written at 0 s and nothing since
  AssemblyParams p;
  p.pair_wait = 0.2;
  p.rudder_max_age = 1.0;
  InsAssembler a = with_rudder(p, 0.0);
  a.add_sway(0.5, 0.0);
  a.add_sway(1.5, 0.0);
  a.add_yaw(yaw(0.5, 0.0), 10.0);
  a.add_yaw(yaw(1.5, 0.0), 10.0);
  // THEN they wait for a later angle for pair_wait of wall time
  EXPECT_TRUE(a.release(10.1).empty());
  const auto out = a.release(10.25);
  ASSERT_EQ(out.size(), 2u);
  // AND then go with the last angle while it is at most rudder_max_age older, else without
  EXPECT_TRUE(out[0].rudder);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.1);
  EXPECT_FALSE(out[1].rudder) << "written 1.5 s before the Imu sample";
  EXPECT_EQ(a.without_rudder(), 1u);
}

TEST(Ros2Assembly, AnglesAreKeptForImuSamplesThatArriveSecondsLater) {
  // GIVEN an Imu reader that lags the rudder reader by 2 s (more than rudder_max_age): the
  // angles of 0.5-3.0 s arrive while the last Imu sample added was the one of 0.4 s
  AssemblyParams p;
  p.rudder_max_age = 1.0;
  InsAssembler a(p);
  a.add_rudder(0.399, 0.0, true);
  a.add_sway(0.4, 0.0);
  a.add_yaw(yaw(0.4, 0.0), 0.0);
  a.add_rudder(0.499, 0.05, true);
  ASSERT_EQ(a.release(0.0).size(), 1u);  // none pending now
  for (int k = 6; k <= 30; ++k) a.add_rudder(0.1 * k - 0.001, 0.01 * k, true);
  // WHEN the Imu samples of 0.5 and 0.6 s come
  for (const double t : {0.5, 0.6}) {
    a.add_sway(t, 0.0);
    a.add_yaw(yaw(t, 0.0), 0.0);
  }
  // THEN each gets its own angle (they were not pruned while no Imu sample was pending)
  const auto out = a.release(0.0);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.05);
  EXPECT_DOUBLE_EQ(out[1].delta, 0.06);
  EXPECT_EQ(a.without_rudder(), 0u);
}

TEST(Ros2Clocks, TheSkewOfTheRudderWritersClockIsItsLeastDelayAgainstTheImus) {
  ClockSkew c(10);
  EXPECT_TRUE(std::isnan(c.skew()));
  // GIVEN an Imu writer on the reader's clock and a rudder writer whose clock is 50 ms ahead,
  // both with transport delays of 1-5 ms
  for (int k = 0; k < 10; ++k) {
    const double t = 0.02 * k, delay = 0.001 + 0.004 * ((k * 7) % 10) / 10.0;
    c.add(false, t, t + delay);
    c.add(true, t + 0.050, t + delay);
  }
  // THEN the skew is 50 ms (the least delays of the block)
  EXPECT_NEAR(c.skew(), 0.050, 1e-9);
}

TEST(Ros2Assembly, RudderAnglesOfTwoWritersAreOrderedByTheirSourceTime) {
  InsAssembler a(AssemblyParams{});
  a.add_rudder(0.10, 0.3, true);
  a.add_rudder(0.05, 0.2, true);  // written earlier, arrived later
  a.add_rudder(0.20, kNaN, false);
  a.add_sway(0.07, 0.0);
  a.add_sway(0.20, 0.0);
  a.add_yaw(yaw(0.07, 0.0), 0.0);
  a.add_yaw(yaw(0.20, 0.0), 0.0);
  const auto out = a.release(0.0);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].delta, 0.2);
  EXPECT_TRUE(out[1].rudder) << "a rudder sample goes with it, marked invalid";
  EXPECT_FALSE(out[1].delta_valid);
}

/// The field names of `struct name { ... }` in an IDL file, in order (comments dropped; the
/// IDL escape of a keyword, "_sequence", as the ROS mirror names it: "sequence_number").
std::vector<std::string> idl_fields(const std::string& file, const std::string& name) {
  std::ifstream in(file);
  EXPECT_TRUE(in) << file;
  std::vector<std::string> out;
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find("//"));
    if (!inside) {
      inside = line.find("struct " + name) != std::string::npos &&
               line.find("struct " + name + "_") == std::string::npos;
      continue;
    }
    if (line.find("};") != std::string::npos) break;
    const auto semi = line.find(';');
    if (semi == std::string::npos) continue;
    std::string decl = line.substr(0, semi);
    decl = decl.substr(0, decl.find('['));
    std::string field = decl.substr(decl.find_last_of(" \t") + 1);
    if (field == "_sequence") field = "sequence_number";
    out.push_back(field);
  }
  return out;
}

/// The field names of a ROS 2 .msg file, in order (constants, NAME=value, left out).
std::vector<std::string> msg_fields(const std::string& file) {
  std::ifstream in(file);
  EXPECT_TRUE(in) << file;
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line.substr(0, line.find('#')));
    std::string type, field;
    if (words >> type >> field && field.find('=') == std::string::npos) out.push_back(field);
  }
  return out;
}

TEST(Ros2Mirrors, CarryEveryFieldOfTheKeyedTypesInTheirOrder) {
  // The keyless mirrors (idl/ros2/usv_fdi_msgs.idl) and the ROS 2 interface package a ROS 2
  // host builds (ros2/usv_fdi_msgs/msg) follow fdi::FaultEvent and fdi::FdiStatus field for
  // field: a field added to a keyed type (FdiStatus version 4) must reach ROS 2 tools too.
  const std::string src = USV_FDI_SOURCE_DIR;
  for (const std::string type : {"FaultEvent", "FdiStatus"}) {
    const auto keyed = idl_fields(src + "/idl/usv_fdi.idl", type);
    EXPECT_GE(keyed.size(), 10u) << type;
    EXPECT_EQ(idl_fields(src + "/idl/ros2/usv_fdi_msgs.idl", type), keyed) << type;
    EXPECT_EQ(msg_fields(src + "/ros2/usv_fdi_msgs/msg/" + type + ".msg"), keyed) << type;
  }
}

Row row(Sensor s, FaultState st) {
  Row r;
  r.mmsi = 257000001;
  r.ev.sensor = s;
  r.ev.state = st;
  r.ev.kind = FaultKind::kBias;
  r.ev.c_a = 0.0;
  r.ev.c_g = 1.0;
  r.ev.statistic = 14.08;
  r.ev.threshold = 12.0;
  r.ev.sequence = 3;
  r.ev.message = "residual";
  return r;
}

TEST(Ros2Diagnostics, LevelsFollowTheLatchState) {
  const double heard = 0.5, silent_after = 5.0;
  const Sensor g = Sensor::kGyro;
  const Row raised = row(g, FaultState::kRaised), acked = row(g, FaultState::kActiveAcknowledged),
            cleared = row(g, FaultState::kClearedUnacknowledged),
            done = row(g, FaultState::kAcknowledged), normal = row(g, FaultState::kNormal);
  EXPECT_EQ(diagnostic_level(g, nullptr, heard, silent_after), DiagLevel::kOk);
  EXPECT_EQ(diagnostic_level(g, &normal, heard, silent_after), DiagLevel::kOk);
  EXPECT_EQ(diagnostic_level(g, &raised, heard, silent_after), DiagLevel::kError);
  EXPECT_EQ(diagnostic_level(g, &acked, heard, silent_after), DiagLevel::kWarn);
  EXPECT_EQ(diagnostic_level(g, &cleared, heard, silent_after), DiagLevel::kWarn);
  EXPECT_EQ(diagnostic_level(g, &done, heard, silent_after), DiagLevel::kOk);
  // A fault no sensor could be blamed for is a warning, not an error of a sensor.
  const Row unknown = row(Sensor::kUnknown, FaultState::kRaised);
  EXPECT_EQ(diagnostic_level(Sensor::kUnknown, &unknown, heard, silent_after), DiagLevel::kWarn);
}

TEST(Ros2Diagnostics, ASilentOrNeverHeardSidecarIsStale) {
  const Row raised = row(Sensor::kGyro, FaultState::kRaised);
  EXPECT_EQ(diagnostic_level(Sensor::kGyro, &raised, 6.0, 5.0), DiagLevel::kStale);
  EXPECT_EQ(diagnostic_level(Sensor::kGyro, nullptr, kNaN, 5.0), DiagLevel::kStale);
  EXPECT_EQ(diagnostic_level(Sensor::kGyro, &raised, 5.0, 5.0), DiagLevel::kError);
}

TEST(Ros2Diagnostics, OneStatusPerSensorNamedByVesselWithTheEventsValues) {
  const Row g = row(Sensor::kGyro, FaultState::kRaised);
  const auto st = vessel_diagnostics(
      257000001, [&](Sensor s) { return s == Sensor::kGyro ? &g : nullptr; }, 0.1, 5.0);
  ASSERT_EQ(st.size(), 2u) << "accelerometer and gyro; no unknown-sensor instance";
  EXPECT_EQ(st[0].name, "usv_fdi: 257000001 accelerometer");
  EXPECT_EQ(st[0].level, DiagLevel::kOk);
  EXPECT_TRUE(st[0].values.empty());
  EXPECT_EQ(st[1].name, "usv_fdi: 257000001 gyro");
  EXPECT_EQ(st[1].hardware_id, "257000001");
  EXPECT_EQ(st[1].level, DiagLevel::kError);
  const std::vector<std::pair<std::string, std::string>> want = {
      {"C_a", "0.000"},    {"C_g", "1.000"},  {"J_N", "14.08"}, {"threshold", "12"},
      {"state", "raised"}, {"sequence", "3"}, {"kind", "bias"}};
  EXPECT_EQ(st[1].values, want);
}

TEST(Ros2Diagnostics, AModelMismatchIsAWarningNotAnError) {
  // GIVEN a vessel whose status reports a model mismatch (FdiStatus.isolation_paused)
  const auto none = [](Sensor) -> const Row* { return nullptr; };
  const VesselNotes mismatch = vessel_notes(fdi::PAUSE_MODEL_MISMATCH | fdi::PAUSE_LEARNING);
  EXPECT_TRUE(mismatch.model_mismatch);
  // THEN both sensors are WARN with the reason, and none is an error
  for (const DiagStatus& d : vessel_diagnostics(257000001, none, 0.1, 5.0, mismatch)) {
    EXPECT_EQ(d.level, DiagLevel::kWarn) << d.name;
    EXPECT_NE(d.message.find("model mismatch, not a sensor fault"), std::string::npos) << d.message;
  }
  // AND a raised fault stays ERROR, a silent sidecar STALE
  const Row g = row(Sensor::kGyro, FaultState::kRaised);
  const auto raised = vessel_diagnostics(
      257000001, [&](Sensor s) { return s == Sensor::kGyro ? &g : nullptr; }, 0.1, 5.0, mismatch);
  EXPECT_EQ(raised[0].level, DiagLevel::kWarn);
  EXPECT_EQ(raised[1].level, DiagLevel::kError);
  EXPECT_EQ(vessel_diagnostics(257000001, none, 9.0, 5.0, mismatch)[0].level, DiagLevel::kStale);
  // AND other pause reasons (a frozen identification, learning) are no warning
  const VesselNotes other = vessel_notes(fdi::PAUSE_FAULT | fdi::PAUSE_LEARNING);
  EXPECT_FALSE(other.model_mismatch);
  EXPECT_EQ(vessel_diagnostics(257000001, none, 0.1, 5.0, other)[0].level, DiagLevel::kOk);
}

TEST(Ros2Diagnostics, AResidualAboveItsClearLevelIsASuspicionWarning) {
  const auto none = [](Sensor) -> const Row* { return nullptr; };
  // GIVEN a status whose gyro residual peaked at 4.2, between the level that clears (3) and
  // the one that raises (6), and whose accelerometer residual is low
  const VesselNotes n = vessel_notes(0, 0, {1.0, 4.2}, {6.0, 6.0}, {3.0, 3.0});
  EXPECT_FALSE(n.suspected(0));
  EXPECT_TRUE(n.suspected(1));
  // THEN the gyro is WARN "suspected", with the numbers; the accelerometer OK
  const auto d = vessel_diagnostics(257000001, none, 0.1, 5.0, n);
  EXPECT_EQ(d[0].level, DiagLevel::kOk) << d[0].message;
  EXPECT_EQ(d[1].level, DiagLevel::kWarn);
  EXPECT_NE(d[1].message.find("suspected: the gyro channel's residual J_N 4.2 is above the level "
                              "that clears a fault (3), not at the one that raises it (6)"),
            std::string::npos)
      << d[1].message;
  // AND a raised gyro fault stays ERROR, a silent sidecar STALE, a model mismatch says so
  const Row g = row(Sensor::kGyro, FaultState::kRaised);
  EXPECT_EQ(
      vessel_diagnostics(
          257000001, [&](Sensor s) { return s == Sensor::kGyro ? &g : nullptr; }, 0.1, 5.0, n)[1]
          .level,
      DiagLevel::kError);
  EXPECT_EQ(vessel_diagnostics(257000001, none, 9.0, 5.0, n)[1].level, DiagLevel::kStale);
  const VesselNotes both =
      vessel_notes(fdi::PAUSE_MODEL_MISMATCH, 0, {1.0, 4.2}, {6.0, 6.0}, {3.0, 3.0});
  EXPECT_NE(vessel_diagnostics(257000001, none, 0.1, 5.0, both)[1].message.find("model mismatch"),
            std::string::npos);
  // AND no suspicion without thresholds in force (not armed: 0) or without a statistic (NaN)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(vessel_notes(0, 0, {9.0, 9.0}, {0.0, 0.0}, {0.0, 0.0}).suspected(1));
  EXPECT_FALSE(vessel_notes(0, 0, {nan, nan}, {6.0, 6.0}, {3.0, 3.0}).suspected(1));
}

TEST(Ros2Diagnostics, AStaleInputOfAHeardSidecarIsStaleForTheSensorsItConcerns) {
  const auto none = [](Sensor) -> const Row* { return nullptr; };
  // GIVEN a heard sidecar whose gyro channel is unusable (INPUT_GYRO_UNUSABLE)
  const VesselNotes gyro = vessel_notes(0, fdi::INPUT_GYRO_UNUSABLE | fdi::INPUT_GAPS);
  auto st = vessel_diagnostics(257000001, none, 0.1, 5.0, gyro);
  // THEN the gyro is STALE with the reason, the accelerometer still OK (a gap is no reason)
  ASSERT_EQ(st.size(), 2u);
  EXPECT_EQ(st[0].level, DiagLevel::kOk) << st[0].message;
  EXPECT_EQ(st[1].level, DiagLevel::kStale);
  EXPECT_NE(st[1].message.find("input stale (the gyro channel is stale, invalid or stuck)"),
            std::string::npos)
      << st[1].message;
  // AND a silent INS or a missing rudder angle makes both STALE, with every reason
  const VesselNotes both =
      vessel_notes(fdi::PAUSE_MODEL_MISMATCH, fdi::INPUT_INS_SILENT | fdi::INPUT_RUDDER_MISSING |
                                                  fdi::INPUT_ACCELEROMETER_UNUSABLE);
  st = vessel_diagnostics(257000001, none, 0.1, 5.0, both);
  for (const DiagStatus& d : st) EXPECT_EQ(d.level, DiagLevel::kStale) << d.name;
  EXPECT_NE(st[0].message.find("no INS samples, no usable rudder angle, the accelerometer"),
            std::string::npos)
      << st[0].message;
  // AND a raised fault stays ERROR; a cleared one (WARN) goes STALE, keeping its state
  const Row g = row(Sensor::kGyro, FaultState::kRaised);
  const Row a = row(Sensor::kAccelerometer, FaultState::kClearedUnacknowledged);
  st = vessel_diagnostics(
      257000001,
      [&](Sensor s) -> const Row* {
        return s == Sensor::kGyro ? &g : s == Sensor::kAccelerometer ? &a : nullptr;
      },
      0.1, 5.0, both);
  EXPECT_EQ(st[0].level, DiagLevel::kStale);
  EXPECT_NE(st[0].message.find("cleared"), std::string::npos) << st[0].message;
  EXPECT_EQ(st[1].level, DiagLevel::kError);
}

}  // namespace
}  // namespace usvfdi::app::ros2
