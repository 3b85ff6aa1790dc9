// IEC 61162-450 datagrams and TAG blocks (include/usv_fdi/nmea/datagram.hpp).
#include <gtest/gtest.h>

#include <string>

#include "support.hpp"
#include "usv_fdi/nmea/datagram.hpp"

namespace usvfdi::nmea {
namespace {

using namespace std::string_literals;

// python3: XOR of "s:GP0001,n:12,c:1700000000" is 0x57.
const std::string kTag = "\\s:GP0001,n:12,c:1700000000*57\\";
const std::string kHeader = "UdPbC\0"s;

TEST(Datagram, Iec450WithTagBlock) {
  const std::string bytes = kHeader + kTag + "$GPHDT,72.14,T*35\r\n";
  auto d = parse_datagram(bytes);
  ASSERT_TRUE(d.ok()) << d.rejection().text;
  EXPECT_TRUE(d.value().iec450);
  ASSERT_EQ(d.value().lines.size(), 1u);
  const auto& line = d.value().lines[0];
  ASSERT_TRUE(line.ok()) << line.rejection().text;
  ASSERT_TRUE(line.value().tag.has_value());
  const TagBlock& t = *line.value().tag;
  EXPECT_EQ(t.source, "GP0001");
  EXPECT_EQ(t.line_count, 12);
  EXPECT_EQ(t.unix_time_ms, 1700000000000);  // c: in seconds
  EXPECT_FALSE(t.destination.has_value());
  EXPECT_EQ(line.value().sentence.formatter, "HDT");
}

TEST(Datagram, TagTimeInMillisecondsWhenElevenDigitsOrMore) {
  auto t = parse_tag_block("c:1700000000123*" + std::string("00"));
  // wrong checksum first: refused
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.rejection().reason, Reason::kBadTagBlock);
  auto ok = parse_tag_block(test::with_checksum("c:1700000000123").substr(1));
  ASSERT_TRUE(ok.ok()) << ok.rejection().text;
  EXPECT_EQ(ok.value().unix_time_ms, 1700000000123);
}

TEST(Datagram, TagTimeRoundTripsInSecondsAndMilliseconds) {
  for (std::int64_t ms : {std::int64_t{0}, std::int64_t{1700000000000}, std::int64_t{1700000000001},
                          std::int64_t{10000000000}, std::int64_t{10000000000000}}) {
    TagBlock t;
    t.unix_time_ms = ms;
    auto f = format_tag_block(t);
    ASSERT_TRUE(f.ok()) << ms << ": " << f.rejection().text;
    auto back = parse_tag_block(f.value().substr(1, f.value().size() - 2));
    ASSERT_TRUE(back.ok()) << f.value();
    EXPECT_EQ(back.value().unix_time_ms, ms) << f.value();
  }
  TagBlock colon;
  colon.source = "a:b";  // the value is what follows the first ':'
  auto f = format_tag_block(colon);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(parse_tag_block(f.value().substr(1, f.value().size() - 2)).value(), colon);
}

TEST(Datagram, TagDestinationGroupRelativeText) {
  TagBlock t;
  t.source = "II0003";
  t.destination = "BN0001";
  t.group = TagGroup{1, 2, 17};
  t.relative_time = 42;
  t.text = "hello world";
  t.unix_time_ms = 1700000000250;
  t.line_count = 999;
  auto f = format_tag_block(t);
  ASSERT_TRUE(f.ok()) << f.rejection().text;
  EXPECT_EQ(f.value().front(), '\\');
  EXPECT_EQ(f.value().back(), '\\');
  auto back = parse_tag_block(f.value().substr(1, f.value().size() - 2));
  ASSERT_TRUE(back.ok()) << back.rejection().text;
  EXPECT_EQ(back.value(), t);
}

TEST(Datagram, SeveralSentencesEachParsedOnItsOwn) {
  const std::string bytes =
      kHeader + kTag + "$GPHDT,72.14,T*35\r\n" + "$GPHDT,72.14,T*36\r\n" + "$HEROT,-12.4,A*31\r\n";
  auto d = parse_datagram(bytes);
  ASSERT_TRUE(d.ok());
  ASSERT_EQ(d.value().lines.size(), 3u);
  EXPECT_TRUE(d.value().lines[0].ok());
  ASSERT_FALSE(d.value().lines[1].ok());
  EXPECT_EQ(d.value().lines[1].rejection().reason, Reason::kChecksumMismatch);
  ASSERT_TRUE(d.value().lines[2].ok());
  EXPECT_FALSE(d.value().lines[2].value().tag.has_value());
}

TEST(Datagram, PlainNmeaOverUdp) {
  auto d = parse_datagram("$GPHDT,72.14,T*35\r\n$HEROT,-12.4,A*31\n$GPHDT,72.14,T*35");
  ASSERT_TRUE(d.ok());
  EXPECT_FALSE(d.value().iec450);
  ASSERT_EQ(d.value().lines.size(), 3u);
  for (const auto& l : d.value().lines) EXPECT_TRUE(l.ok());
  auto tagged = parse_datagram(kTag + "$GPHDT,72.14,T*35\r\n");
  ASSERT_TRUE(tagged.ok());
  ASSERT_TRUE(tagged.value().lines[0].ok());
  EXPECT_TRUE(tagged.value().lines[0].value().tag.has_value());
}

TEST(Datagram, ConsecutiveTagBlocksMerge) {
  // python3: XOR of "g:1-2-5" is 0x?? computed by checksum() (equal to the formatter's).
  TagBlock g;
  g.group = TagGroup{1, 2, 5};
  auto block = format_tag_block(g);
  ASSERT_TRUE(block.ok());
  auto r = parse_tagged_sentence(kTag + block.value() + "$GPHDT,72.14,T*35");
  ASSERT_TRUE(r.ok()) << r.rejection().text;
  EXPECT_EQ(r.value().tag->source, "GP0001");
  EXPECT_EQ(r.value().tag->group, (TagGroup{1, 2, 5}));
}

Reason line_reason(const std::string& line) {
  auto r = parse_tagged_sentence(line);
  EXPECT_FALSE(r.ok()) << line;
  return r.rejection().reason;
}

TEST(Datagram, RejectsBadTagBlocks) {
  EXPECT_EQ(line_reason("\\s:GP0001,n:12,c:1700000000*58\\$GPHDT,72.14,T*35"),
            Reason::kBadTagBlock);  // checksum
  EXPECT_EQ(line_reason("\\s:GP0001,n:12,c:1700000000*57$GPHDT,72.14,T*35"),
            Reason::kBadTagBlock);                                                // unterminated
  EXPECT_EQ(line_reason("\\s:GP0001\\$GPHDT,72.14,T*35"), Reason::kBadTagBlock);  // no checksum
  EXPECT_EQ(line_reason("\\s:GP0001*5\\$GPHDT,72.14,T*35"), Reason::kBadTagBlock);
  const auto with_sum = [](const std::string& params) {
    // with_checksum's "$" replaced: the TAG block's checksum is the same XOR.
    return "\\" + test::with_checksum(params).substr(1) + "\\$GPHDT,72.14,T*35";
  };
  EXPECT_TRUE(parse_tagged_sentence(with_sum("s:GP0001,x:whatever")).ok());  // unknown code
  EXPECT_EQ(line_reason(with_sum("s")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("ss:GP")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("n:1x")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("n:-1")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("c:")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("r:1.5")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("g:1-2")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("g:1-2-x")), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("s:" + std::string(80, 'A'))), Reason::kTooLong);
  EXPECT_EQ(line_reason("\\s:A\x01*00\\$GPHDT,72.14,T*35"), Reason::kBadTagBlock);
  EXPECT_EQ(line_reason(with_sum("s:A$B")), Reason::kBadTagBlock);  // reserved character
  EXPECT_EQ(line_reason(with_sum("t:A~B")), Reason::kBadTagBlock);
  // A good TAG block does not save a bad sentence.
  EXPECT_EQ(line_reason(kTag + "$GPHDT,72.14,T*36"), Reason::kChecksumMismatch);
}

TEST(Datagram, RejectsWholeDatagrams) {
  EXPECT_EQ(parse_datagram("").rejection().reason, Reason::kEmpty);
  EXPECT_EQ(parse_datagram(kHeader).rejection().reason, Reason::kEmpty);
  EXPECT_EQ(parse_datagram(kHeader + "\r\n\r\n").rejection().reason, Reason::kEmpty);
  EXPECT_EQ(parse_datagram("UdPbC$GPHDT,72.14,T*35").rejection().reason, Reason::kBadHeader);
  EXPECT_EQ(parse_datagram("RaUdP\0\x01\x02"s).rejection().reason, Reason::kBadHeader);
  const auto r = parse_datagram("\x01\x02garbage");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.rejection().reason, Reason::kBadHeader);
  EXPECT_NE(r.rejection().text.find("\\x01"), std::string::npos) << r.rejection().text;
  EXPECT_EQ(parse_datagram(std::string(kMaxDatagramLength + 1, '$')).rejection().reason,
            Reason::kTooLong);
}

TEST(Datagram, FormatsIec450) {
  TagBlock t;
  t.source = "GP0001";
  t.line_count = 12;
  t.unix_time_ms = 1700000000000;
  auto d = format_iec450_datagram(t, {"$GPHDT,72.14,T*35\r\n"});
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d.value(), kHeader + kTag + "$GPHDT,72.14,T*35\r\n");
}

TEST(Datagram, FormatRefusesBadTagValues) {
  TagBlock t;
  t.source = "GP,01";
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kBadTagBlock);
  t.source = "GP$01";
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kBadTagBlock);
  t.source.reset();
  t.unix_time_ms = 1500;  // a fraction of a second before 1970-04-26: would read back as s
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kBadTagBlock);
  t.unix_time_ms = -1000;
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kBadTagBlock);
  t.unix_time_ms.reset();
  t.source.reset();
  t.line_count = -1;
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kBadTagBlock);
  t.line_count.reset();
  t.text = std::string(90, 'a');
  EXPECT_EQ(format_tag_block(t).rejection().reason, Reason::kTooLong);
}

}  // namespace
}  // namespace usvfdi::nmea
