// Bridge alert management sentences: ALF, ALC, HBT, ARC, ACN (include/usv_fdi/nmea/alert.hpp).
#include <gtest/gtest.h>

#include <string>

#include "support.hpp"
#include "usv_fdi/nmea/alert.hpp"

namespace usvfdi::nmea {
namespace {

using test::reason;
using test::sentence;

Alf gyro_alert() {
  Alf a;
  a.message_id = 3;
  a.time = UtcTime{8, 15, 250};  // 08:15:02.5
  a.category = AlertCategory::kB;
  a.priority = AlertPriority::kWarning;
  a.state = AlertState::kActiveUnacknowledged;
  a.alert = AlertIdentity{"FDI", 3001, 2};
  a.revision = 7;
  a.escalation = 0;
  a.text = "INS gyro fault";
  return a;
}

// Expected sentences' checksums computed with python3 (functools.reduce over the XOR).
TEST(Alf, FormatsAndParsesBack) {
  auto f = format_alf(gyro_alert());
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value(), "$IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,INS gyro fault*43\r\n");
  auto back = parse_alf(parse_sentence(f.value()).value());
  ASSERT_TRUE(back.ok()) << back.rejection().text;
  EXPECT_EQ(back.value(), gyro_alert());
}

TEST(Alf, EveryStateAndPriorityRoundTrips) {
  for (char st : std::string("VSAOUN")) {
    for (char pr : std::string("EAWC")) {
      Alf a = gyro_alert();
      a.state = static_cast<AlertState>(st);
      a.priority = static_cast<AlertPriority>(pr);
      auto f = format_alf(a);
      ASSERT_TRUE(f.ok()) << st << pr;
      EXPECT_EQ(parse_alf(parse_sentence(f.value()).value()).value(), a) << f.value();
    }
  }
}

TEST(Alf, TextTruncatedToFitAndEscaped) {
  Alf a = gyro_alert();
  a.text = std::string(100, 'x');
  auto f = format_alf(a);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value().size(), kMaxSentenceLength);
  auto back = parse_alf(parse_sentence(f.value()).value());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value().text, std::string(back.value().text.size(), 'x'));
  EXPECT_LT(back.value().text.size(), 100u);

  a.text = "a,b*c^d$!\\~";
  f = format_alf(a);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_NE(f.value().find(",a^2Cb^2Ac^5Ed^24^21^5C^7E*"), std::string::npos) << f.value();
  EXPECT_EQ(parse_alf(parse_sentence(f.value()).value()).value().text, a.text);

  // An escape is never cut in half by the truncation.
  a.text = std::string(40, ',');
  f = format_alf(a);
  ASSERT_TRUE(f.ok());
  const auto parsed = parse_alf(parse_sentence(f.value()).value());
  ASSERT_TRUE(parsed.ok()) << parsed.rejection().text;
  EXPECT_EQ(parsed.value().text, std::string(parsed.value().text.size(), ','));
}

TEST(Alf, MessageOfTitleAndDescription) {
  Alf a = gyro_alert();
  a.total_sentences = 2;  // ignored: set from the description
  auto one = format_alf_message(a, "");
  ASSERT_TRUE(one.ok()) << one.rejection().text;
  ASSERT_EQ(one.value().size(), 1u);
  EXPECT_EQ(one.value()[0], "$IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,INS gyro fault*43\r\n");

  auto two = format_alf_message(a, "Yaw rate biased; check the gyro then ack");
  ASSERT_TRUE(two.ok()) << two.rejection().text;
  ASSERT_EQ(two.value().size(), 2u);
  const auto s1 = parse_alf(parse_sentence(two.value()[0]).value());
  const auto s2 = parse_alf(parse_sentence(two.value()[1]).value());
  ASSERT_TRUE(s1.ok() && s2.ok());
  EXPECT_EQ(s1.value().total_sentences, 2);
  EXPECT_EQ(s1.value().sentence_number, 1);
  EXPECT_EQ(s1.value().text, "INS gyro fault");
  EXPECT_EQ(s1.value().state, AlertState::kActiveUnacknowledged);
  EXPECT_EQ(s2.value().sentence_number, 2);
  EXPECT_FALSE(s2.value().time || s2.value().category || s2.value().priority || s2.value().state);
  EXPECT_EQ(s2.value().alert, a.alert);
  EXPECT_EQ(s2.value().revision, a.revision);
  EXPECT_EQ(s2.value().message_id, a.message_id);
  EXPECT_EQ(s2.value().text, "Yaw rate biased; check the gyro then ack");

  a.revision = 0;
  EXPECT_EQ(format_alf_message(a, "x").rejection().reason, Reason::kOutOfRange);
}

TEST(Alf, SecondSentenceMayOmitCategoryPriorityState) {
  auto r = parse_alf(sentence("IIALF,2,2,3,,,,,FDI,3001,2,7,0,Check the gyro"));
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_FALSE(r.value().state.has_value());
  EXPECT_EQ(r.value().sentence_number, 2);
}

TEST(Alf, Rejections) {
  const std::string good = "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,text";
  ASSERT_TRUE(parse_alf(sentence(good)).ok());
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0"),
            Reason::kFieldCount);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALC,1,1,3,0"), Reason::kWrongSentence);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,3,1,3,081502.5,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);  // total
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,2,3,081502.5,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);  // number > total
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,,1,3,081502.5,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // missing total
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,10,081502.5,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);  // message id
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,0815,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // time
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,241502,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,086002,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081561,B,W,V,FDI,3001,2,7,0,t"),
            Reason::kOutOfRange);
  EXPECT_TRUE(parse_alf(sentence("IIALF,1,1,3,235960.99,B,W,V,FDI,3001,2,7,0,t")).ok());
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,D,W,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // category
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,X,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // priority
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,Z,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // state
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,,FDI,3001,2,7,0,t"),
            Reason::kBadField);  // state missing in sentence 1
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,,W,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,,V,FDI,3001,2,7,0,t"),
            Reason::kBadField);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FD,3001,2,7,0,t"),
            Reason::kBadField);  // mnemonic
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,fdi,3001,2,7,0,t"),
            Reason::kBadField);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,,2,7,0,t"),
            Reason::kBadField);  // alert id missing
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,10000000,2,7,0,t"),
            Reason::kOutOfRange);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,0,7,0,t"),
            Reason::kOutOfRange);  // instance
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,1000000,7,0,t"),
            Reason::kOutOfRange);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,0,0,t"),
            Reason::kOutOfRange);  // revision
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,100,0,t"),
            Reason::kOutOfRange);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,10,t"),
            Reason::kOutOfRange);  // escalation
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,a^2"),
            Reason::kBadField);  // truncated escape
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,a^ZZ"),
            Reason::kBadField);
  EXPECT_EQ(reason<Alf>(parse_alf, "IIALF,1,1,3,081502.5,B,W,V,FDI,3001,2,7,0,a^0D"),
            Reason::kBadField);  // escape of a control character
}

TEST(Alf, RevisionCounterWraps) {
  EXPECT_EQ(next_revision(1), 2);
  EXPECT_EQ(next_revision(98), 99);
  EXPECT_EQ(next_revision(99), 1);
  EXPECT_EQ(next_revision(0), 1);
}

TEST(Alf, FormatterRefusesInvalidValues) {
  Alf a = gyro_alert();
  a.revision = 100;
  EXPECT_EQ(format_alf(a).rejection().reason, Reason::kOutOfRange);
  a = gyro_alert();
  a.alert.manufacturer = "F,I";
  EXPECT_EQ(format_alf(a).rejection().reason, Reason::kReservedCharacter);
  a = gyro_alert();
  a.time = UtcTime{24, 0, 0};
  EXPECT_EQ(format_alf(a).rejection().reason, Reason::kOutOfRange);
  a = gyro_alert();
  a.state.reset();
  EXPECT_EQ(format_alf(a).rejection().reason, Reason::kBadField);
  a = gyro_alert();
  a.time = UtcTime{123, 0, 0};  // would be written "23": refused, not wrapped
  EXPECT_EQ(format_alf(a).rejection().reason, Reason::kOutOfRange);
  a = gyro_alert();
  a.time = UtcTime{8, 15, -1};
  EXPECT_FALSE(format_alf(a).ok());
}

TEST(Alc, FormatsAndParsesBack) {
  Alc l;
  l.message_id = 5;
  l.entries = {AlcEntry{AlertIdentity{"FDI", 3001, 1}, 7},
               AlcEntry{AlertIdentity{"FDI", 3002, 1}, 3}};
  auto f = format_alc(l);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value(), "$IIALC,1,1,5,2,FDI,3001,1,7,FDI,3002,1,3*4E\r\n");
  EXPECT_EQ(parse_alc(parse_sentence(f.value()).value()).value(), l);
  Alc empty;
  auto e = format_alc(empty);
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(parse_alc(parse_sentence(e.value()).value()).value(), empty);
}

TEST(Alc, ListSplitsIntoSentencesWithoutSplittingEntries) {
  std::vector<AlcEntry> entries;
  for (long k = 0; k < 12; ++k)
    entries.push_back(AlcEntry{AlertIdentity{"FDI", 3001 + k, 1 + k}, 1});
  auto list = format_alc_list("II", 42, entries);
  ASSERT_TRUE(list.ok()) << list.rejection().text;
  ASSERT_GT(list.value().size(), 1u);
  std::vector<AlcEntry> seen;
  for (std::size_t k = 0; k < list.value().size(); ++k) {
    EXPECT_LE(list.value()[k].size(), kMaxSentenceLength);
    auto p = parse_alc(parse_sentence(list.value()[k]).value());
    ASSERT_TRUE(p.ok()) << p.rejection().text;
    EXPECT_EQ(p.value().total_sentences, static_cast<int>(list.value().size()));
    EXPECT_EQ(p.value().sentence_number, static_cast<int>(k + 1));
    EXPECT_EQ(p.value().message_id, 42);
    seen.insert(seen.end(), p.value().entries.begin(), p.value().entries.end());
  }
  EXPECT_EQ(seen, entries);
  auto none = format_alc_list("II", 1, {});
  ASSERT_TRUE(none.ok());
  ASSERT_EQ(none.value().size(), 1u);
  EXPECT_NE(none.value()[0].find(",1,1,1,0*"), std::string::npos) << none.value()[0];
  EXPECT_FALSE(format_alc_list("II", 100, entries).ok());
  // Three of these entries fill a sentence to 82 characters with the head "1,1,0", to 83 with
  // "10,10,99": the packing must measure the widest head (the message id's too), or the
  // tenth sentence of message 99 would be refused.
  std::vector<AlcEntry> tight;
  for (int k = 0; k < 10; ++k) {
    for (long instance : {1234L, 1234L, 12345L}) {
      tight.push_back(AlcEntry{AlertIdentity{"FDI", 1234567, instance}, 99});
    }
  }
  for (int id : {0, 9, 99}) {
    const auto l = format_alc_list("II", id, tight);
    ASSERT_TRUE(l.ok()) << id << ": " << l.rejection().text;
    EXPECT_GE(l.value().size(), 10u);
  }
}

TEST(Alc, Rejections) {
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5"), Reason::kFieldCount);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1"), Reason::kFieldCount);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1,FDI,3001,1,7,FDI"), Reason::kFieldCount);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,x"), Reason::kBadField);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,100"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,2,5,0"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,0,0,5,0"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,100,0"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1,FDI,3001,1,0"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1,FDI,3001,1,"), Reason::kBadField);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1,FDIX,3001,1,7"), Reason::kBadField);
  EXPECT_EQ(reason<Alc>(parse_alc, "IIALC,1,1,5,1,FDI,-3,1,7"), Reason::kBadField);
  EXPECT_TRUE(parse_alc(sentence("IIALC,01,01,05,1,,3001,,7")).ok());  // null mnemonic, instance
}

TEST(Hbt, FormatsAndParsesBack) {
  Hbt h;
  h.interval_s = 1.0;
  h.sequence = 4;
  auto f = format_hbt(h);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.value(), "$IIHBT,1,A,4*36\r\n");
  EXPECT_EQ(parse_hbt(parse_sentence(f.value()).value()).value(), h);
  h.normal = false;
  h.interval_s.reset();
  EXPECT_EQ(parse_hbt(parse_sentence(format_hbt(h).value()).value()).value(), h);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1,A"), Reason::kFieldCount);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1000,A,4"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,-1,A,4"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1,X,4"), Reason::kBadField);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1,,4"), Reason::kBadField);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1,A,10"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Hbt>(parse_hbt, "IIHBT,1,A,"), Reason::kBadField);
}

TEST(Arc, FormatsAndParsesBack) {
  Arc a;
  a.time = UtcTime{8, 15, 1025};
  a.alert = AlertIdentity{"FDI", 3001, 2};
  a.refused = AlertCommand::kAcknowledge;
  auto f = format_arc(a);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value(), "$IIARC,081510.25,FDI,3001,2,A*62\r\n");
  EXPECT_EQ(parse_arc(parse_sentence(f.value()).value()).value(), a);
  EXPECT_EQ(reason<Arc>(parse_arc, "IIARC,081510.25,FDI,3001,2,X"), Reason::kBadField);
  EXPECT_EQ(reason<Arc>(parse_arc, "IIARC,081510.25,FDI,3001,2,"), Reason::kBadField);
  EXPECT_EQ(reason<Arc>(parse_arc, "IIARC,081510.25,FDI,3001,2"), Reason::kFieldCount);
}

TEST(Acn, ParsesBridgeCommands) {
  // python3: checksum of "BNACN,081510.25,FDI,3001,2,A,C" is 0x1D.
  auto r = parse_acn(parse_sentence("$BNACN,081510.25,FDI,3001,2,A,C*1D\r\n").value());
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_EQ(r.value().talker, "BN");
  EXPECT_EQ(r.value().time, (UtcTime{8, 15, 1025}));
  EXPECT_EQ(r.value().alert, (AlertIdentity{"FDI", 3001, 2}));
  EXPECT_EQ(r.value().command, AlertCommand::kAcknowledge);
  // python3: checksum of "BNACN,,,3001,,S,C" is 0x52: null time, mnemonic and instance.
  auto silence = parse_acn(parse_sentence("$BNACN,,,3001,,S,C*52").value());
  ASSERT_TRUE(silence.ok()) << silence.rejection().text;
  EXPECT_EQ(silence.value().command, AlertCommand::kSilence);
  EXPECT_FALSE(silence.value().alert.instance.has_value());
  for (char c : std::string("AQOS")) {
    Acn a;
    a.alert = AlertIdentity{"FDI", 3002, 1};
    a.command = static_cast<AlertCommand>(c);
    EXPECT_EQ(parse_acn(parse_sentence(format_acn(a).value()).value()).value(), a);
  }
}

TEST(Acn, Rejections) {
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,2,A,"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,2,A,X"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,2,X,C"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,2,,C"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,,2,A,C"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,0,A,C"), Reason::kOutOfRange);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,0815,FDI,3001,2,A,C"), Reason::kBadField);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNACN,081510.25,FDI,3001,2,A"), Reason::kFieldCount);
  EXPECT_EQ(reason<Acn>(parse_acn, "BNARC,081510.25,FDI,3001,2,A"), Reason::kWrongSentence);
}

}  // namespace
}  // namespace usvfdi::nmea
