// The NMEA 0183 / IEC 61162-450 UDP adapter (src/nmea_udp): datagrams sent on the loopback
// interface are received and assembled; bad lines are counted by reason; plain NMEA 0183 lines
// are accepted; gaps in the TAG line counts are counted; the sign conventions of ROT, RSA and
// VBW. Every wait is bounded by a generous deadline (never a timing limit that only an idle
// machine meets).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "support.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea/navigation.hpp"
#include "usv_fdi/nmea_udp/udp.hpp"

namespace usvfdi::nmea_udp {
namespace {

using nmea::test::with_checksum;

constexpr std::int64_t kEpochMs = 1767225600000;  // 2026-01-01T00:00:00Z

/// "\s:HE0001,n:N,c:MS*hh\" + "$" + body + "*hh\r\n".
std::string tagged(const std::string& body, std::int64_t n, std::int64_t ms) {
  nmea::TagBlock tag;
  tag.source = "HE0001";
  tag.line_count = n;
  tag.unix_time_ms = ms;
  return nmea::format_tag_block(tag).value() + with_checksum(body) + "\r\n";
}

std::string iec450(const std::string& lines) { return std::string(nmea::kIec450Header) + lines; }

/// Polls until `done()` or 10 s (a backstop: loopback delivers within microseconds).
template <class Done>
bool poll_until(NmeaUdpReceiver* rx, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    if (rx->poll(100) < 0) return false;
  }
  return true;
}

ReceiverConfig loopback(const std::string& address) {
  ReceiverConfig c;
  c.endpoint.address = address;
  c.endpoint.port = 0;  // the kernel's choice: no clash between tests run in parallel
  c.interface_address = "127.0.0.1";
  c.assembler.rate_hz = 10.0;
  c.assembler.max_age_s = 1.0;
  return c;
}

TEST(NmeaUdp, ParsesEndpoints) {
  const Endpoint e = parse_endpoint("239.192.0.1:60001");
  EXPECT_EQ(e.address, "239.192.0.1");
  EXPECT_EQ(e.port, 60001);
  EXPECT_TRUE(is_multicast("239.192.0.1"));
  EXPECT_FALSE(is_multicast("127.0.0.1"));
  EXPECT_THROW(parse_endpoint("239.192.0.1"), std::invalid_argument);
  EXPECT_THROW(parse_endpoint("239.192.0.1:70000"), std::invalid_argument);
  EXPECT_THROW(parse_endpoint("vessel:60001"), std::invalid_argument);
}

TEST(NmeaUdp, MulticastDatagramOnLoopbackIsReceivedAndAssembled) {
  // GIVEN a receiver joined to an IEC 61162-450 style group on the loopback interface
  NmeaUdpReceiver rx(loopback("239.192.0.1"));
  ASSERT_TRUE(rx.multicast());
  ASSERT_GT(rx.port(), 0);
  NmeaUdpSender tx(Endpoint{"239.192.0.1", rx.port()}, "127.0.0.1", 0);
  // WHEN three 61162-450 datagrams of ROT, RSA and VBW arrive, 0.1 s apart in TAG time
  std::int64_t n = 0;
  for (int k = 0; k < 3; ++k) {
    const std::int64_t ms = kEpochMs + 100 * k;
    ASSERT_TRUE(tx.send(iec450(tagged("HEROT,-60.000,A", n + 1, ms) +
                               tagged("AGRSA,5.000,A,,V", n + 2, ms) +
                               tagged("VDVBW,3.8877,0.1944,A,,,V", n + 3, ms))));
    n += 3;
  }
  ASSERT_TRUE(poll_until(&rx, [&] { return rx.decoder().stats().datagrams >= 3; }));
  // THEN every line is used, on the TAG time base, and the samples hold the values
  const DecoderStats& st = rx.decoder().stats();
  EXPECT_EQ(st.used, 9u);
  EXPECT_EQ(st.bad, 0u) << st.describe();
  EXPECT_EQ(st.lost_lines, 0u);
  const auto samples = rx.decoder().take();
  ASSERT_EQ(samples.size(), 2u);  // the third grid time is emitted by the next input
  EXPECT_EQ(rx.decoder().first_tag_ms(), kEpochMs);  // t = 0 at the first c:
  EXPECT_NEAR(samples[0].t, 0.0, 1e-12);
  EXPECT_NEAR(samples[1].t, 0.1, 1e-12);
  EXPECT_NEAR(samples[0].r, -60.0 * nmea::kPi / 10800.0, 1e-12);
  EXPECT_NEAR(samples[0].delta, -5.0 * nmea::kPi / 180.0, 1e-12);  // b2 < 0: sign flipped
  EXPECT_NEAR(samples[0].v, 0.1944 * 1852.0 / 3600.0, 1e-12);
}

TEST(NmeaUdp, BadChecksumIsCountedAndTheOtherLinesUsed) {
  // GIVEN a unicast receiver on 127.0.0.1
  NmeaUdpReceiver rx(loopback("127.0.0.1"));
  ASSERT_FALSE(rx.multicast());
  NmeaUdpSender tx(Endpoint{"127.0.0.1", rx.port()}, "", 1);
  // WHEN a datagram holds a line with a wrong checksum between two good ones, and another
  // datagram has a foreign IEC 61162-450 header
  std::string bad = tagged("HEROT,1.000,A", 2, kEpochMs);
  bad[bad.size() - 3] = bad[bad.size() - 3] == '0' ? '1' : '0';  // the checksum's last digit
  ASSERT_TRUE(tx.send(iec450(tagged("AGRSA,1.000,A,,V", 1, kEpochMs) + bad +
                             tagged("VDVBW,3.8877,0.1944,A,,,V", 3, kEpochMs))));
  ASSERT_TRUE(tx.send(std::string("RrUdP\0xyz", 9)));
  ASSERT_TRUE(poll_until(&rx, [&] { return rx.decoder().stats().datagrams >= 2; }));
  // THEN each is counted under its reason, the good lines are used, nothing throws
  const DecoderStats& st = rx.decoder().stats();
  EXPECT_EQ(st.used, 2u);
  EXPECT_EQ(st.bad, 2u);
  EXPECT_EQ(st.reasons.at("checksum mismatch"), 1u) << st.describe();
  EXPECT_EQ(st.reasons.at("bad header"), 1u) << st.describe();
  EXPECT_EQ(rx.decoder().take_examples().size(), 2u);
}

TEST(NmeaUdp, PlainNmeaLinesAreAcceptedOnTheReceiveClock) {
  // GIVEN a unicast receiver
  NmeaUdpReceiver rx(loopback("127.0.0.1"));
  NmeaUdpSender tx(Endpoint{"127.0.0.1", rx.port()}, "", 1);
  // WHEN plain NMEA 0183 arrives: two lines in one datagram (LF and CR LF), any talker, then
  // a single line without a line end
  ASSERT_TRUE(
      tx.send(with_checksum("TIROT,30.0,A") + "\n" + with_checksum("RIRSA,-2.0,A,,V") + "\r\n"));
  ASSERT_TRUE(tx.send(with_checksum("IIVBW,1.0,-0.5,A,,,V")));
  ASSERT_TRUE(poll_until(&rx, [&] { return rx.decoder().stats().datagrams >= 2; }));
  // THEN the three are used, timed by the monotonic receive clock (t = 0 at the first)
  const DecoderStats& st = rx.decoder().stats();
  EXPECT_EQ(st.used, 3u) << st.describe();
  EXPECT_EQ(st.bad, 0u);
  EXPECT_EQ(rx.decoder().first_tag_ms(), -1);
  EXPECT_GE(rx.decoder().latest_time(), 0.0);
  EXPECT_LT(rx.decoder().latest_time(), 10.0);
}

TEST(NmeaUdp, GapsInTheLineCountsAreCountedNotInvented) {
  DatagramDecoder d(loopback("127.0.0.1").assembler);
  // GIVEN lines numbered 997, 999 (one lost), 2 (over the wrap: one lost), 2 again (a
  // repeat), 1 (a step back: a restarted sender), 4 (two lost)
  const std::int64_t numbers[] = {997, 999, 2, 2, 1, 4};
  for (int k = 0; k < 6; ++k) {
    d.add(iec450(tagged("HEROT,1.0,A", numbers[k], kEpochMs + 100 * k)), 0.0);
  }
  // THEN four lines are counted lost, and every line is still used
  EXPECT_EQ(d.stats().lost_lines, 4u);
  EXPECT_EQ(d.stats().used, 6u);
}

TEST(NmeaUdp, AStoppedSentenceIsNamedStale) {
  DatagramDecoder d(loopback("127.0.0.1").assembler);
  // GIVEN ROT, RSA and VBW every 0.1 s for 1 s, then ROT and VBW alone for 2 s
  std::int64_t n = 0;
  for (int k = 0; k <= 30; ++k) {
    const std::int64_t ms = kEpochMs + 100 * k;
    std::string lines = tagged("HEROT,1.0,A", n + 1, ms) + tagged("VDVBW,1.0,0.1,A,,,V", n + 2, ms);
    n += 2;
    if (k <= 10) lines += tagged("AGRSA,1.0,A,,V", ++n, ms);
    d.add(iec450(lines), 0.0);
  }
  // THEN RSA (delta) is stale by 2 s, the others are not, and the samples lack delta
  const auto stale = d.stale();
  ASSERT_EQ(stale.size(), 1u);
  EXPECT_EQ(stale[0].sentence, "RSA");
  EXPECT_EQ(stale[0].quantity, "delta");
  EXPECT_NEAR(stale[0].age_s, 2.0, 1e-6);
  const auto samples = d.take();
  ASSERT_FALSE(samples.empty());
  EXPECT_TRUE(std::isnan(samples.back().delta));
  EXPECT_FALSE(std::isnan(samples.back().r));
}

// Sign conventions (docs/integration.md): ROT "-" = bow to port -> r < 0; RSA "-" = bow to
// port, the opposite of the project's delta for b2 < 0 (Otter, Mariner); VBW transverse water
// speed "-" = to port -> v < 0.
TEST(NmeaUdp, SignConventionsOfRotRsaAndVbw) {
  nmea::AssemblerConfig c = loopback("127.0.0.1").assembler;
  for (const nmea::RudderSign sign :
       {nmea::RudderSign::kPositiveToPort, nmea::RudderSign::kPositiveToStarboard}) {
    c.rudder_sign = sign;
    DatagramDecoder d(c);
    d.add(iec450(tagged("HEROT,-6.0,A", 1, kEpochMs) + tagged("AGRSA,-10.0,A,,V", 2, kEpochMs) +
                 tagged("VDVBW,2.0,-1.0,A,,,V", 3, kEpochMs)),
          0.0);
    d.add(iec450(tagged("HEROT,-6.0,A", 4, kEpochMs + 100)), 0.0);
    const auto s = d.take();
    ASSERT_EQ(s.size(), 1u);
    EXPECT_LT(s[0].r, 0.0);  // bow to port
    EXPECT_NEAR(s[0].r, -6.0 / 60.0 * nmea::kPi / 180.0, 1e-15);
    EXPECT_LT(s[0].v, 0.0);  // to port
    EXPECT_NEAR(s[0].v, -1.0 * 1852.0 / 3600.0, 1e-15);
    if (sign == nmea::RudderSign::kPositiveToPort) {
      EXPECT_NEAR(s[0].delta, 10.0 * nmea::kPi / 180.0, 1e-15);  // RSA to port: delta > 0
    } else {
      EXPECT_NEAR(s[0].delta, -10.0 * nmea::kPi / 180.0, 1e-15);
    }
  }
}

}  // namespace
}  // namespace usvfdi::nmea_udp
