// The sentence layer: split, checksum, limits, formatter (include/usv_fdi/nmea/sentence.hpp).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "support.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea {
namespace {

using test::with_checksum;

Reason reason_of(std::string_view line) {
  const auto r = parse_sentence(line);
  EXPECT_FALSE(r.ok()) << line;
  return r.rejection().reason;
}

// Sentences copied from a research vessel's recorded log (NOAA, RV Ronald H. Brown, 2020) and
// a VBW format note (NOAA NCEI); their checksums were also recomputed with python3.
TEST(Sentence, ParsesRecordedSentences) {
  auto hdt = parse_sentence("$GPHDT,72.14,T*35\r\n");
  ASSERT_TRUE(hdt.ok()) << hdt.rejection().text;
  EXPECT_EQ(hdt.value().start, '$');
  EXPECT_EQ(hdt.value().talker, "GP");
  EXPECT_EQ(hdt.value().formatter, "HDT");
  EXPECT_FALSE(hdt.value().proprietary);
  EXPECT_EQ(hdt.value().fields, (std::vector<std::string>{"72.14", "T"}));

  auto vtg = parse_sentence("$GPVTG,70.52,T,87.27,M,10.17,N,18.83,K,D*29");
  ASSERT_TRUE(vtg.ok()) << vtg.rejection().text;
  EXPECT_EQ(vtg.value().fields.size(), 9u);

  auto vbw = parse_sentence("$VDVBW,-00.06,-00.02,A,-00.06,-00.02,V,-00.02,V,000.00,V*59");
  ASSERT_TRUE(vbw.ok()) << vbw.rejection().text;
  EXPECT_EQ(vbw.value().talker, "VD");
  EXPECT_EQ(vbw.value().fields.size(), 10u);
}

TEST(Sentence, ChecksumIsXorBetweenStartAndStar) {
  // python3: functools.reduce(lambda a, c: a ^ ord(c), "HEROT,-12.4,A", 0) == 0x31
  EXPECT_EQ(checksum("HEROT,-12.4,A"), 0x31);
  EXPECT_TRUE(parse_sentence("$HEROT,-12.4,A*31").ok());
  EXPECT_TRUE(parse_sentence("$HEROT,-12.4,A*31\n").ok());
  EXPECT_TRUE(parse_sentence("$GPHDT,72.14,T*35").ok());
}

TEST(Sentence, LowerCaseChecksumAccepted) {
  EXPECT_TRUE(parse_sentence("$HETHS,123.4,A*29").ok());
  EXPECT_TRUE(parse_sentence("$AGRSA,5.2,A,,V*78").ok());
  // python3: the checksum of "IIHDT,359.0,T" is 0x2D.
  EXPECT_EQ(checksum("IIHDT,359.0,T"), 0x2D);
  EXPECT_TRUE(parse_sentence("$IIHDT,359.0,T*2D").ok());
  EXPECT_TRUE(parse_sentence("$IIHDT,359.0,T*2d").ok());
}

TEST(Sentence, EmptyFieldsKept) {
  auto r = parse_sentence("$AGRSA,5.2,A,,V*78");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.value().fields, (std::vector<std::string>{"5.2", "A", "", "V"}));
}

TEST(Sentence, EncapsulatedStartAndAnyTalker) {
  auto r = parse_sentence(with_checksum("AIVDM,1,1,,A,13aEOK?P00PD2wVMdLDRhgvL289?,0,0", '!'));
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_EQ(r.value().start, '!');
  EXPECT_EQ(r.value().talker, "AI");
  EXPECT_EQ(r.value().formatter, "VDM");
  auto user = parse_sentence(with_checksum("U1ROT,1.0,A"));
  ASSERT_TRUE(user.ok()) << user.rejection().text;
  EXPECT_EQ(user.value().talker, "U1");
}

TEST(Sentence, Proprietary) {
  // python3: checksum of "PSAT,HPR,120000.00,45.0,1.0,2.0,N" is 0x23
  auto r = parse_sentence("$PSAT,HPR,120000.00,45.0,1.0,2.0,N*23");
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_TRUE(r.value().proprietary);
  EXPECT_EQ(r.value().talker, "P");
  EXPECT_EQ(r.value().formatter, "SAT");
  EXPECT_EQ(r.value().fields.front(), "HPR");
  auto f = format_sentence(r.value());
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.value(), "$PSAT,HPR,120000.00,45.0,1.0,2.0,N*23\r\n");
}

TEST(Sentence, RejectsWithReasons) {
  EXPECT_EQ(reason_of(""), Reason::kEmpty);
  EXPECT_EQ(reason_of("\r\n"), Reason::kEmpty);
  EXPECT_EQ(reason_of("GPHDT,72.14,T*35"), Reason::kNoStart);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T"), Reason::kNoChecksum);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T*3"), Reason::kBadChecksumSyntax);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T*3G"), Reason::kBadChecksumSyntax);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T*355"), Reason::kBadChecksumSyntax);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T*36"), Reason::kChecksumMismatch);
  EXPECT_EQ(reason_of("$GPHDT,72.15,T*35"), Reason::kChecksumMismatch);
  // A manual's example with a misprinted checksum (the characters give 0x01).
  EXPECT_EQ(reason_of("$GPROT,35.6,A*4E"), Reason::kChecksumMismatch);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T\t*35"), Reason::kNonPrintable);
  EXPECT_EQ(reason_of(std::string("$GPHDT,72.1\0,T*35", 17)), Reason::kNonPrintable);
  EXPECT_EQ(reason_of("$GPHDT,72.14,T*35\r"), Reason::kNonPrintable);
  EXPECT_EQ(reason_of("$GPHDT,72.14\r,T*35"), Reason::kNonPrintable);
  EXPECT_EQ(reason_of("$GPHDT,72\x80,T*35"), Reason::kNonPrintable);
  EXPECT_EQ(reason_of("$GPHDT,7$2,T*35"), Reason::kReservedCharacter);
  EXPECT_EQ(reason_of("$GPHDT,7\\2,T*35"), Reason::kReservedCharacter);
  EXPECT_EQ(reason_of("$GPHDT,7~2,T*35"), Reason::kReservedCharacter);
  EXPECT_EQ(reason_of("$GPHDT,7!2,T*35"), Reason::kReservedCharacter);
}

TEST(Sentence, RejectsBadAddresses) {
  EXPECT_EQ(reason_of(with_checksum("GPHD,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("GPHDTX,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("gpHDT,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("GPhdt,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("GP1DT,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum(",1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("PAB,1")), Reason::kBadAddress);
  EXPECT_EQ(reason_of(with_checksum("G-HDT,1")), Reason::kBadAddress);
}

TEST(Sentence, LengthLimitIs82WithCrLf) {
  // "$" + body + "*hh" = 80 characters: the longest accepted.
  const std::string head = "GPTXT,";
  std::string body = head + std::string(80 - 4 - head.size(), 'A');
  ASSERT_EQ(with_checksum(body).size(), 80u);
  EXPECT_TRUE(parse_sentence(with_checksum(body)).ok());
  EXPECT_TRUE(parse_sentence(with_checksum(body) + "\r\n").ok());
  const auto r = parse_sentence(with_checksum(body + "A"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.rejection().reason, Reason::kTooLong);
  EXPECT_NE(r.rejection().text.find("81"), std::string::npos) << r.rejection().text;
}

TEST(Sentence, RejectionTextNamesTheProblem) {
  const auto r = parse_sentence("$GPHDT,72.14,T*36");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.rejection().text, "checksum 36, characters give 35");
  EXPECT_STREQ(to_string(r.rejection().reason), "checksum mismatch");
}

TEST(Sentence, FormatterAddsChecksumAndCrLf) {
  Sentence s;
  s.talker = "HE";
  s.formatter = "ROT";
  s.fields = {"-12.4", "A"};
  auto f = format_sentence(s);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value(), "$HEROT,-12.4,A*31\r\n");
  auto back = parse_sentence(f.value());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value(), s);
}

TEST(Sentence, FormatterRefusesWhatTheParserWould) {
  Sentence s;
  s.talker = "HE";
  s.formatter = "ROT";
  s.fields = {"1,2", "A"};
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kReservedCharacter);
  s.fields = {"1*2", "A"};
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kReservedCharacter);
  s.fields = {"1\n2", "A"};
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kNonPrintable);
  s.fields = {std::string(80, '1')};
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kTooLong);
  s.fields = {"1"};
  s.talker = "H";
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kBadAddress);
  s.talker = "PA";  // would read back as a proprietary sentence
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kBadAddress);
  s.talker = "HE";
  s.start = '#';
  EXPECT_EQ(format_sentence(s).rejection().reason, Reason::kNoStart);
}

}  // namespace
}  // namespace usvfdi::nmea
