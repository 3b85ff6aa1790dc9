// Typed navigation sentences: ROT, RSA, HDT, THS, VBW, VTG (include/usv_fdi/nmea/navigation.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "support.hpp"
#include "usv_fdi/nmea/navigation.hpp"

namespace usvfdi::nmea {
namespace {

using test::reason;
using test::sentence;

TEST(Rot, ParsesSignAndStatus) {
  // python3: checksum of "HEROT,-12.4,A" is 0x31.
  auto s = parse_sentence("$HEROT,-12.4,A*31\r\n");
  ASSERT_TRUE(s.ok());
  auto r = parse_rot(s.value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_EQ(r.value().talker, "HE");
  EXPECT_DOUBLE_EQ(*r.value().rate_deg_per_min, -12.4);
  EXPECT_EQ(r.value().status, Status::kValid);
  EXPECT_TRUE(r.value().valid());

  auto invalid = parse_rot(sentence("TIROT,3.0,V"));
  ASSERT_TRUE(invalid.ok());
  EXPECT_FALSE(invalid.value().valid());
  auto empty = parse_rot(sentence("TIROT,,A"));
  ASSERT_TRUE(empty.ok());
  EXPECT_FALSE(empty.value().rate_deg_per_min.has_value());
  EXPECT_FALSE(empty.value().valid());
  auto plus = parse_rot(sentence("TIROT,+0003.5,A"));
  ASSERT_TRUE(plus.ok());
  EXPECT_DOUBLE_EQ(*plus.value().rate_deg_per_min, 3.5);
}

TEST(Rot, Rejections) {
  EXPECT_EQ(reason<Rot>(parse_rot, "HEHDT,1.0,T"), Reason::kWrongSentence);
  EXPECT_EQ(reason<Rot>(parse_rot, "PROT,1.0,A"), Reason::kWrongSentence);  // proprietary
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1.0"), Reason::kFieldCount);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1.0,A,"), Reason::kFieldCount);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1.0.0,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1e3,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,nan,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,inf,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,-,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,.,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT, 1.0,A"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,10000.1,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,-10001,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT," + std::string(60, '9') + ",A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1.0,X"), Reason::kBadField);
  EXPECT_EQ(reason<Rot>(parse_rot, "HEROT,1.0,AA"), Reason::kBadField);
  EXPECT_TRUE(parse_rot(sentence("HEROT,10000,A")).ok());
  const auto r = parse_rot(sentence("HEROT,12x,A"));
  EXPECT_EQ(r.rejection().text, "field 1 (rate of turn): not a number: '12x'");
}

TEST(Rsa, StarboardAndOptionalPort) {
  // python3: checksum of "AGRSA,5.2,A,,V" is 0x78.
  auto s = parse_sentence("$AGRSA,5.2,A,,V*78");
  ASSERT_TRUE(s.ok());
  auto r = parse_rsa(s.value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_DOUBLE_EQ(*r.value().starboard_deg, 5.2);
  EXPECT_TRUE(r.value().starboard_valid());
  EXPECT_FALSE(r.value().port_deg.has_value());
  EXPECT_FALSE(r.value().port_valid());
  auto twin = parse_rsa(sentence("AGRSA,-3.0,A,-2.5,A"));
  ASSERT_TRUE(twin.ok());
  EXPECT_DOUBLE_EQ(*twin.value().port_deg, -2.5);
  EXPECT_TRUE(twin.value().port_valid());
  EXPECT_FALSE(parse_rsa(sentence("AGRSA,3.0,V,,")).value().starboard_valid());
}

TEST(Rsa, Rejections) {
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGROT,1.0,A"), Reason::kWrongSentence);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,1.0,A"), Reason::kFieldCount);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,90.5,A,,V"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,1.0,A,-91,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,1.0,B,,V"), Reason::kBadField);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,1.0,A,x,V"), Reason::kBadField);
  EXPECT_EQ(reason<Rsa>(parse_rsa, "AGRSA,1.0,A,,Q"), Reason::kBadField);
  EXPECT_TRUE(parse_rsa(sentence("AGRSA,-90,A,90,A")).ok());
}

TEST(Heading, HdtAndThs) {
  auto hdt = parse_hdt(parse_sentence("$GPHDT,72.14,T*35").value());  // recorded log
  ASSERT_TRUE(hdt.ok()) << hdt.rejection().text;
  EXPECT_DOUBLE_EQ(*hdt.value().heading_deg, 72.14);
  EXPECT_TRUE(hdt.value().valid());
  // python3: checksum of "HETHS,123.4,A" is 0x29.
  auto ths = parse_ths(parse_sentence("$HETHS,123.4,A*29").value());
  ASSERT_TRUE(ths.ok()) << ths.rejection().text;
  EXPECT_DOUBLE_EQ(*ths.value().heading_deg, 123.4);
  EXPECT_EQ(ths.value().mode, HeadingMode::kAutonomous);
  EXPECT_TRUE(ths.value().valid());
  for (const char* m : {"E", "M", "S", "V"}) {
    auto t = parse_ths(sentence(std::string("HETHS,10.0,") + m));
    ASSERT_TRUE(t.ok()) << m;
    EXPECT_FALSE(t.value().valid()) << m;
  }
  EXPECT_FALSE(parse_ths(sentence("HETHS,10.0,")).value().valid());
}

TEST(Heading, Rejections) {
  EXPECT_EQ(reason<Hdt>(parse_hdt, "HEHDT,360.1,T"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Hdt>(parse_hdt, "HEHDT,-0.1,T"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Hdt>(parse_hdt, "HEHDT,10.0,M"), Reason::kBadField);
  EXPECT_EQ(reason<Hdt>(parse_hdt, "HEHDT,10.0"), Reason::kFieldCount);
  EXPECT_EQ(reason<Hdt>(parse_hdt, "HETHS,10.0,A"), Reason::kWrongSentence);
  EXPECT_EQ(reason<Ths>(parse_ths, "HETHS,10.0,X"), Reason::kBadField);
  EXPECT_EQ(reason<Ths>(parse_ths, "HETHS,400,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Ths>(parse_ths, "HETHS,10.0,A,A"), Reason::kFieldCount);
  EXPECT_TRUE(parse_hdt(sentence("HEHDT,,")).ok());
  EXPECT_TRUE(parse_hdt(sentence("HEHDT,360,T")).ok());
}

TEST(Vbw, RecordedTenFieldSentence) {
  auto s = parse_sentence("$VDVBW,-00.06,-00.02,A,-00.06,-00.02,V,-00.02,V,000.00,V*59");
  ASSERT_TRUE(s.ok());
  auto r = parse_vbw(s.value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  const Vbw& v = r.value();
  EXPECT_DOUBLE_EQ(*v.water_longitudinal_kn, -0.06);
  EXPECT_DOUBLE_EQ(*v.water_transverse_kn, -0.02);
  EXPECT_TRUE(v.water_valid());
  EXPECT_FALSE(v.ground_valid());
  EXPECT_DOUBLE_EQ(*v.stern_water_transverse_kn, -0.02);
  EXPECT_EQ(v.stern_ground_status, Status::kInvalid);
  EXPECT_TRUE(v.has_stern());
}

TEST(Vbw, SixFieldsAndRejections) {
  // python3: checksum of "IIVBW,7.5,-0.3,A,7.6,-0.2,A" is 0x41.
  auto r = parse_vbw(parse_sentence("$IIVBW,7.5,-0.3,A,7.6,-0.2,A*41").value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_DOUBLE_EQ(*r.value().water_transverse_kn, -0.3);
  EXPECT_FALSE(r.value().has_stern());
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,1"), Reason::kFieldCount);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2"), Reason::kFieldCount);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,100.5,-0.3,A,7.6,-0.2,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-101,A,7.6,-0.2,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,200,A,0,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,0,A,0,X"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,Y,7.6,-0.2,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,Z"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,q,-0.2,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7,-0.2q,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,0,A,w,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,w,A,0,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,7.5,-0.3,A,7.6,-0.2,A,0,W,0,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vbw>(parse_vbw, "IIVBW,z,-0.3,A,7.6,-0.2,A"), Reason::kBadField);
}

TEST(Vtg, RecordedSentenceAndMode) {
  auto r = parse_vtg(parse_sentence("$GPVTG,70.52,T,87.27,M,10.17,N,18.83,K,D*29").value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_DOUBLE_EQ(*r.value().course_true_deg, 70.52);
  EXPECT_DOUBLE_EQ(*r.value().course_magnetic_deg, 87.27);
  EXPECT_DOUBLE_EQ(*r.value().speed_kn, 10.17);
  EXPECT_DOUBLE_EQ(*r.value().speed_kmh, 18.83);
  EXPECT_EQ(r.value().mode, PositioningMode::kDifferential);
  EXPECT_TRUE(r.value().valid());
  auto old = parse_vtg(sentence("GPVTG,70.5,T,,M,10.2,N,18.9,K"));  // before NMEA 2.3
  ASSERT_TRUE(old.ok()) << old.rejection().text;
  EXPECT_EQ(old.value().mode, PositioningMode::kAbsent);
  EXPECT_TRUE(old.value().valid());
  for (const char* m : {"N", "E", "M", "S"}) {
    auto t = parse_vtg(sentence(std::string("GPVTG,70.5,T,,M,10.2,N,18.9,K,") + m));
    ASSERT_TRUE(t.ok()) << m;
    EXPECT_FALSE(t.value().valid()) << m;
  }
}

TEST(Vtg, Rejections) {
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,10.2,N,18.9"), Reason::kFieldCount);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,X,,M,10.2,N,18.9,K,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,X,10.2,N,18.9,K,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,10.2,X,18.9,K,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,10.2,N,18.9,X,A"), Reason::kBadField);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,10.2,N,18.9,K,Q"), Reason::kBadField);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,361,T,,M,10.2,N,18.9,K,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,-1,M,10.2,N,18.9,K,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,-0.1,N,18.9,K,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,100.1,N,18.9,K,A"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Vtg>(parse_vtg, "GPVTG,70.5,T,,M,10.2,N,185.3,K,A"), Reason::kOutOfRange);
}

TEST(Navigation, FormattersRoundTrip) {
  Rot rot;
  rot.rate_deg_per_min = -12.4;
  rot.status = Status::kValid;
  ASSERT_TRUE(format_rot(rot).ok());
  EXPECT_EQ(format_rot(rot).value(), "$HEROT,-12.4,A*31\r\n");
  EXPECT_EQ(parse_rot(parse_sentence(format_rot(rot).value()).value()).value(), rot);

  Rsa rsa;
  rsa.starboard_deg = 5.2;
  rsa.starboard_status = Status::kValid;
  rsa.port_status = Status::kInvalid;
  EXPECT_EQ(format_rsa(rsa).value(), "$AGRSA,5.2,A,,V*78\r\n");

  Hdt hdt;
  hdt.talker = "GP";
  hdt.heading_deg = 72.14;
  EXPECT_EQ(format_hdt(hdt).value(), "$GPHDT,72.14,T*35\r\n");

  Ths ths;
  ths.heading_deg = 123.4;
  ths.mode = HeadingMode::kAutonomous;
  EXPECT_EQ(format_ths(ths).value(), "$HETHS,123.4,A*29\r\n");

  Vbw vbw;
  vbw.talker = "II";
  vbw.water_longitudinal_kn = 7.5;
  vbw.water_transverse_kn = -0.3;
  vbw.water_status = Status::kValid;
  vbw.ground_longitudinal_kn = 7.6;
  vbw.ground_transverse_kn = -0.2;
  vbw.ground_status = Status::kValid;
  EXPECT_EQ(format_vbw(vbw).value(), "$IIVBW,7.5,-0.3,A,7.6,-0.2,A*41\r\n");
  vbw.stern_ground_status = Status::kInvalid;
  auto ten = parse_vbw(parse_sentence(format_vbw(vbw).value()).value());
  ASSERT_TRUE(ten.ok());
  EXPECT_EQ(ten.value(), vbw);

  Vtg vtg;
  vtg.course_true_deg = 70.52;
  vtg.course_magnetic_deg = 87.27;
  vtg.speed_kn = 10.17;
  vtg.speed_kmh = 18.83;
  vtg.mode = PositioningMode::kDifferential;
  EXPECT_EQ(format_vtg(vtg).value(), "$GPVTG,70.52,T,87.27,M,10.17,N,18.83,K,D*29\r\n");
}

TEST(Navigation, FormattersRefuseWhatParsersRefuse) {
  Rot rot;
  rot.rate_deg_per_min = std::nan("");
  EXPECT_EQ(format_rot(rot).rejection().reason, Reason::kBadField);
  rot.rate_deg_per_min = 1e6;
  EXPECT_EQ(format_rot(rot).rejection().reason, Reason::kOutOfRange);
  Rsa rsa;
  rsa.starboard_deg = HUGE_VAL;
  EXPECT_FALSE(format_rsa(rsa).ok());
  Vtg vtg;
  vtg.speed_kn = -1.0;
  EXPECT_EQ(format_vtg(vtg).rejection().reason, Reason::kOutOfRange);
  Hdt hdt;
  hdt.talker = "G";
  EXPECT_EQ(format_hdt(hdt).rejection().reason, Reason::kBadAddress);
}

// The signs the sidecar will rely on (issue 12): ROT and VBW keep the project's sign, RSA is
// opposite to delta on the shipped vessels (delta > 0 turns the bow to port: b2 < 0).
TEST(Navigation, ConversionsToProjectConventions) {
  EXPECT_NEAR(yaw_rate_from_rot(60.0), kPi / 180.0, 1e-15);  // 60 deg/min = 1 deg/s starboard
  EXPECT_LT(yaw_rate_from_rot(-30.0), 0.0);                  // bow to port: r < 0
  const RudderSign shipped = rudder_sign_from_b2(-2.19400);  // config/vessels/otter.yaml
  EXPECT_EQ(shipped, RudderSign::kPositiveToPort);
  EXPECT_EQ(rudder_sign_from_b2(-3.74282e-3), RudderSign::kPositiveToPort);  // mariner.yaml
  EXPECT_NEAR(delta_from_rsa(10.0, shipped), -10.0 * kPi / 180.0, 1e-15);    // RSA > 0: starboard
  EXPECT_GT(delta_from_rsa(-5.0, shipped), 0.0);  // RSA "-" = bow to port = delta > 0
  EXPECT_EQ(rudder_sign_from_b2(0.5), RudderSign::kPositiveToStarboard);  // container, kvlcc2
  EXPECT_GT(delta_from_rsa(10.0, RudderSign::kPositiveToStarboard), 0.0);
  EXPECT_NEAR(speed_from_knots(1.0), 0.514444, 1e-6);
  EXPECT_LT(speed_from_knots(-0.3), 0.0);  // VBW transverse "-" = port: v < 0
}

}  // namespace
}  // namespace usvfdi::nmea
