// End-to-end test of `usv-fdi bridge`: the real sidecar, simulator and bridge, each in its own
// process over Fast DDS on loopback; the test plays the bridge alert management system on
// 127.0.0.1 UDP: it reads the IEC 61162-450 datagrams the bridge sends (ALF, ALC, HBT, ARC)
// and sends ACN datagrams, good and bad.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "bam.hpp"
#include "fleet.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using namespace bam_side;  // NOLINT: the BAM side's helpers and alert states

TEST(BridgeEndToEnd, PaperScenarioAlertsFollowTheLifecycleAndAcnAcknowledges) {
  // GIVEN a sidecar and a bridge adapter for one vessel; the test is the bridge's BAM system
  Fleet f;
  const unsigned m = 257100031;
  Udp bam_rx, bam_tx;
  const int acn_in = free_port();
  // Statuses at least every 0.5 s: the bridge calls a vessel silent after 2 s.
  f.start_service("svc", f.write_service_config("svc", m, {"status_uplink: {heartbeat: 0.5}"}), 0);
  f.start("bridge", {"bridge", "--mmsi", std::to_string(m), "--out", bam_rx.endpoint(), "--in",
                     "127.0.0.1:" + std::to_string(acn_in), "--hbt-period", "0.5", "--alc-period",
                     "1", "--ack-timeout", "5", "--silent-after", "2"});
  ASSERT_TRUE(f.wait_for_log("bridge", "running", seconds(20))) << f.log("bridge");
  Bam bam;
  // Heartbeats (status A once the sidecar is heard) and the (empty) alert list come before
  // any fault.
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(20), [&] {
    return !bam.hbt.empty() && bam.hbt.back().normal;
  })) << f.log("bridge");
  ASSERT_FALSE(bam.alc.empty());
  EXPECT_TRUE(bam.alc.front().entries.empty());
  EXPECT_EQ(bam.hbt.front().interval_s, 0.5);
  EXPECT_GT(bam.iec450, 0);

  // WHEN the simulator publishes the paper's scenario (gyro bias 20-40 s, accelerometer 60-80 s)
  f.start("sim", sim_args({"--mmsi", std::to_string(m), "--speed", "20"}));
  // THEN each alert goes active-unacknowledged, then rectified-unacknowledged
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(60),
                            [&] { return bam.state_is(kGyro, U) && bam.state_is(kAccel, U); }))
      << bam.dump() << f.log("bridge") << f.log("svc");
  EXPECT_TRUE(bam.saw(kGyro, V)) << bam.dump();
  EXPECT_TRUE(bam.saw(kAccel, V)) << bam.dump();
  EXPECT_FALSE(bam.saw(kUnknown, V)) << "no unknown-sensor alert\n" << bam.dump();
  EXPECT_TRUE(bam.bad.empty()) << bam.dump();
  // The ALC lists both alerts with their revisions in force.
  const int alc_before = static_cast<int>(bam.alc.size());
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(10),
                            [&] { return static_cast<int>(bam.alc.size()) > alc_before; }));
  ASSERT_EQ(bam.alc.back().entries.size(), 2u) << bam.dump();
  EXPECT_EQ(bam.alc.back().entries[0].alert.id, kAccel);
  EXPECT_EQ(bam.alc.back().entries[0].revision, bam.last(kAccel)->revision);

  // WHEN bad ACNs arrive: a bad checksum, missing fields, an unknown talker's garbage, another
  // equipment's alert, a datagram of another IEC 61162-450 type
  std::string bad_checksum = acn_datagram(kAccel, 'A');
  bad_checksum[bad_checksum.size() - 3] = bad_checksum[bad_checksum.size() - 3] == '0' ? '1' : '0';
  bam_tx.send_to(acn_in, bad_checksum);
  bam_tx.send_to(acn_in, with_checksum("BNACN,,UFD,3001"));  // fields missing
  bam_tx.send_to(acn_in, std::string("RrUdP\0garbage", 13));
  bam_tx.send_to(acn_in, "\x01\x02\x03 not nmea at all\r\n");
  bam_tx.send_to(acn_in, acn_datagram(kAccel, 'A', "XYZ"));
  // and one good ACN that acknowledges the gyro alert
  const int gyro_rev = bam.last(kGyro)->revision;
  bam_tx.send_to(acn_in, acn_datagram(kGyro, 'A'));
  // THEN the gyro alert goes normal with the next revision; the accelerometer's is unchanged
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(20), [&] { return bam.state_is(kGyro, N); }))
      << bam.dump() << f.log("bridge") << f.log("svc");
  EXPECT_EQ(bam.last(kGyro)->revision, nmea::next_revision(gyro_rev));
  EXPECT_TRUE(bam.state_is(kAccel, U)) << bam.dump();
  EXPECT_TRUE(bam.arc.empty()) << "another equipment's alert is not answered\n" << bam.dump();
  EXPECT_TRUE(f.wait_for_log("svc", "by bridge:BN0001", seconds(5))) << f.log("svc");

  // WHEN the gyro alert is acknowledged again, or silenced
  bam_tx.send_to(acn_in, acn_datagram(kGyro, 'A'));
  bam_tx.send_to(acn_in, acn_datagram(kAccel, 'S'));
  // THEN both are refused with ARC
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(10), [&] { return bam.arc.size() >= 2; }))
      << bam.dump() << f.log("bridge");
  EXPECT_EQ(bam.arc[0].alert.id, kGyro);
  EXPECT_EQ(bam.arc[0].refused, nmea::AlertCommand::kAcknowledge);
  EXPECT_EQ(bam.arc[1].alert.id, kAccel);
  EXPECT_EQ(bam.arc[1].refused, nmea::AlertCommand::kSilence);
  // WHEN the accelerometer alert's information is requested, then it is acknowledged
  const std::size_t alf_before = bam.alf.size();
  bam_tx.send_to(acn_in, acn_datagram(kAccel, 'Q'));
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(10), [&] {
    for (std::size_t i = alf_before; i < bam.alf.size(); ++i) {
      if (bam.alf[i].alert.id == kAccel) return true;
    }
    return false;
  })) << bam.dump();
  EXPECT_TRUE(bam.state_is(kAccel, U));
  bam_tx.send_to(acn_in, acn_datagram(kAccel, 'A'));
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(20), [&] { return bam.state_is(kAccel, N); }))
      << bam.dump() << f.log("bridge");

  // WHEN the sidecar stops, THEN the heartbeat says system fail
  f.process("svc").signal(SIGTERM);
  ASSERT_TRUE(f.process("svc").wait_exit(seconds(10)).has_value());
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(20), [&] { return !bam.hbt.back().normal; }))
      << f.log("bridge");

  // THEN, stopped, the bridge has counted what did not act
  f.process("bridge").signal(SIGTERM);
  ASSERT_TRUE(f.process("bridge").wait_exit(seconds(10)).has_value());
  const std::string log = f.log("bridge");
  EXPECT_NE(log.find("1 checksum mismatch"), std::string::npos) << log;
  // Its own two bad headers at least: a datagram of another process on the loopback (a Fast
  // DDS participant of a test running beside it, whose well-known RTPS port can be this
  // run's ephemeral ACN port) is a bad header too, and counted.
  const std::size_t bad = log.find(" bad header", log.find("not acted on:"));
  ASSERT_NE(bad, std::string::npos) << log;
  const std::size_t digits = log.find_last_not_of("0123456789", bad - 1) + 1;
  EXPECT_GE(std::stoul(log.substr(digits, bad - digits)), 2u) << log;
  EXPECT_NE(log.find("bridge input: ACN "), std::string::npos) << "fields missing\n" << log;
  EXPECT_NE(log.find("2 acks sent, 2 ARC"), std::string::npos) << log;
}

TEST(BridgeEndToEnd, AnAcnNoSidecarConfirmsIsAnsweredWithArc) {
  // GIVEN a sidecar that accepts acknowledgements only from "captain", and a bridge
  Fleet f;
  const unsigned m = 257100032;
  Udp bam_rx, bam_tx;
  const int acn_in = free_port();
  f.start_service("svc", f.write_service_config("svc", m, {"authorised_operators: [captain]"}), 0);
  f.start("bridge", {"bridge", "--mmsi", std::to_string(m), "--out", bam_rx.endpoint(), "--in",
                     "127.0.0.1:" + std::to_string(acn_in), "--ack-timeout", "2"});
  ASSERT_TRUE(f.wait_for_log("bridge", "running", seconds(20))) << f.log("bridge");
  f.start("sim", sim_args({"--mmsi", std::to_string(m), "--speed", "20"}));
  Bam bam;
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(60), [&] { return bam.saw(kGyro, V); }))
      << bam.dump() << f.log("bridge");
  // WHEN the bridge acknowledges the gyro alert (as operator bridge:BN0001)
  bam_tx.send_to(acn_in, acn_datagram(kGyro, 'A'));
  // THEN the sidecar refuses it, and the bridge answers ARC once its wait is over
  ASSERT_TRUE(receive_until(bam_rx, &bam, seconds(20), [&] { return !bam.arc.empty(); }))
      << bam.dump() << f.log("bridge") << f.log("svc");
  EXPECT_EQ(bam.arc[0].alert.id, kGyro);
  EXPECT_FALSE(bam.saw(kGyro, nmea::AlertState::kActiveAcknowledged)) << bam.dump();
  EXPECT_TRUE(f.wait_for_log("bridge", "not confirmed by the sidecar", seconds(5)));
}

}  // namespace
}  // namespace usvfdi::dds::test
