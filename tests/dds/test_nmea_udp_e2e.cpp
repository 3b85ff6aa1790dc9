// End-to-end tests of the live NMEA input (issue 12, section 2): the real `usv-fdi` executable
// as sidecar (`run` with service.input: nmea), as NMEA sender (`sim --nmea --udp`) and as shore
// monitor (`monitor`), each in its own process. The sentences travel as IEC 61162-450 datagrams
// over UDP multicast on the loopback interface (group 239.192.0.1, joined on 127.0.0.1, a port
// private to the test); FaultEvent and FdiStatus still go over Fast DDS (UDPv4 on 127.0.0.1, a
// private domain and partition). Every wait is bounded; the times asserted are source (TAG)
// times, never wall-clock limits.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bam.hpp"  // the bridge alert management system's side of the bridge
#include "fleet.hpp"
#include "support.hpp"  // tests/nmea: sentences with checksums
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea_udp/udp.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr const char* kGroup = "239.192.0.1";

/// A UDP port private to this test process and test (ctest -j runs several at once).
unsigned test_port(unsigned index) {
  return 20000u + (static_cast<unsigned>(::getpid()) % 10000u) * 4u + index;
}

/// The service lines of a sidecar reading NMEA on group:port (loopback); max_age: the
/// nmea.max_age line's value ("" : none, the default 1 s). Every sentence comes at the grid
/// rate with its TAG time on the grid: a lost datagram is a gap in the samples either way
/// (held until due, or max_age below one grid period; docs/integration.md, "Lost datagrams").
std::vector<std::string> nmea_service(unsigned port, const std::vector<std::string>& extra = {},
                                      const std::string& max_age = "0.05") {
  std::vector<std::string> lines = {"input: nmea",
                                    "nmea:",
                                    std::string("  address: ") + kGroup,
                                    "  port: " + std::to_string(port),
                                    "  interface: 127.0.0.1",
                                    "  rate: 10"};
  if (!max_age.empty()) lines.push_back("  max_age: " + max_age);
  lines.insert(lines.end(), extra.begin(), extra.end());
  return lines;
}

std::string dump(const std::vector<MonitorEvent>& all) {
  std::string s;
  for (const auto& e : all) {
    s += e.sensor + " #" + std::to_string(e.sequence) + " " + e.state + " " + e.kind +
         " t=" + std::to_string(e.stamp) + " C_a=" + std::to_string(e.c_a) +
         " C_g=" + std::to_string(e.c_g) + "\n";
  }
  return s;
}

/// Writes the noise-free paper scenario (Otter, 10 Hz) as the simulator's NMEA log into the
/// fleet's folder; *path its file.
void write_paper_nmea(Fleet& f, std::string* path) {
  *path = f.dir() + "paper.nmea";
  ASSERT_EQ(f.run_to_end("simlog",
                         {"sim", "--vessel", "otter", "--scenario", "paper", "--rate", "10",
                          "--noise-scale", "0", "--nmea", "--output", *path},
                         seconds(60), nullptr, false),
            0);
}

/// The lines of that log (ROT, RSA, VBW per sample, each after its TAG block), each ending in
/// CR LF.
void paper_nmea_lines(Fleet& f, std::vector<std::string>* lines) {
  std::string log_file;
  ASSERT_NO_FATAL_FAILURE(write_paper_nmea(f, &log_file));
  std::ifstream in(log_file);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty()) lines->push_back(line + "\r\n");
  }
  ASSERT_EQ(lines->size(), 3u * 1001u);
}

/// The first event of `sensor` in state `state` stamped in [t0, t1), or nullptr.
const MonitorEvent* first(const std::vector<MonitorEvent>& all, const std::string& sensor,
                          const std::string& state, double t0, double t1) {
  for (const auto& e : all) {
    if (e.sensor == sensor && e.state == state && e.stamp >= t0 && e.stamp < t1) return &e;
  }
  return nullptr;
}

/// The number after "key": in a JSON line (NaN if absent).
double number_of(const std::string& line, const std::string& key) {
  const auto at = line.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(line.c_str() + at + key.size() + 3, nullptr);
}

TEST(NmeaUdpEndToEnd, PaperScenarioOverMulticastRaisesAndIsolatesBothFaults) {
  // GIVEN a monitor and a sidecar whose input is NMEA over UDP multicast (loopback)
  Fleet f;
  const unsigned m = 257300001;
  const unsigned port = test_port(0);
  const std::string cfg = f.write_service_config("svc", m, nmea_service(port));
  ChildProcess& monitor = f.start("monitor", {"monitor", "--json", "--status"});
  f.start_service("svc", cfg, 1);
  ASSERT_TRUE(f.wait_for_log("svc", "NMEA input: multicast group", seconds(10))) << f.log("svc");
  // WHEN the simulator sends the paper's scenario (Otter, noise-free, 10 Hz) as IEC 61162-450
  // datagrams, ten times faster than real time
  ChildProcess& sim = f.start(
      "sim",
      {"sim", "--vessel", "otter", "--scenario", "paper", "--rate", "10", "--noise-scale", "0",
       "--nmea", "--udp", std::string(kGroup) + ":" + std::to_string(port), "--speed", "10"},
      {}, false);
  std::vector<MonitorEvent> ev;
  std::vector<MonitorStatus> st;
  std::string err;
  const bool complete = read_monitor_until(
      monitor, &ev, &st, seconds(60),
      [&](const std::vector<MonitorEvent>& e) {
        return first(e, "gyro", "cleared", 40.0, 100.0) != nullptr &&
               first(e, "accelerometer", "cleared", 80.0, 100.0) != nullptr;
      },
      &err);
  ASSERT_TRUE(complete) << err << "\n" << dump(ev) << f.log("svc") << f.log("sim");
  const auto sim_exit = sim.wait_exit(seconds(30));
  ASSERT_TRUE(sim_exit.has_value());
  EXPECT_EQ(*sim_exit, 0) << f.log("sim");

  // THEN each fault was raised within 3 s of its onset (TAG time, t = 0 at the first
  // datagram), isolated to its sensor, and cleared after its end
  const MonitorEvent* gyro = first(ev, "gyro", "raised", 0.0, 100.0);
  ASSERT_NE(gyro, nullptr) << dump(ev);
  EXPECT_GE(gyro->stamp, 20.0) << dump(ev);
  EXPECT_LE(gyro->stamp, 23.0) << dump(ev);
  EXPECT_GE(gyro->c_g, 0.8) << dump(ev);
  EXPECT_LE(gyro->c_a, 0.2) << dump(ev);
  const MonitorEvent* acc = first(ev, "accelerometer", "raised", 0.0, 100.0);
  ASSERT_NE(acc, nullptr) << dump(ev);
  EXPECT_GE(acc->stamp, 60.0) << dump(ev);
  EXPECT_LE(acc->stamp, 63.0) << dump(ev);
  EXPECT_GE(acc->c_a, 0.8) << dump(ev);
  EXPECT_LE(acc->c_g, 0.2) << dump(ev);
  // AND no other fault was raised during the voyage (a lost datagram is a gap, not a fault)
  for (const auto& e : ev) {
    if (e.stamp >= 100.0 || e.state != "raised") continue;
    EXPECT_TRUE((e.sensor == "gyro" && e.stamp >= 20.0 && e.stamp < 40.0) ||
                (e.sensor == "accelerometer" && e.stamp >= 60.0 && e.stamp < 80.0))
        << dump(ev);
  }
  // AND the status saw the voyage's samples (100 s at 10 Hz) and a converged, armed detector
  unsigned long long most = 0;
  bool armed = false;
  const auto until = std::chrono::steady_clock::now() + seconds(20);
  while (most < 1000u && std::chrono::steady_clock::now() < until) {
    for (const auto& s : st) {
      most = std::max(most, s.samples);
      armed |= s.armed;
    }
    if (const auto line = monitor.read_line(milliseconds(500))) {
      parse_monitor_line(*line, &ev, &st, &err);
    }
  }
  EXPECT_GE(most, 1000u);
  EXPECT_TRUE(armed);
  // AND the live input raised what the log replay of the same voyage raises, at the same
  // (TAG) times with the same isolation: one code path (SampleAssembler::add_sentence), and
  // times that do not depend on when the datagrams arrived
  std::string log_file;
  ASSERT_NO_FATAL_FAILURE(write_paper_nmea(f, &log_file));
  const std::string out = f.dir() + "replay.jsonl";
  ASSERT_EQ(f.run_to_end("replay",
                         {"replay", "--config",
                          std::string(USV_FDI_SOURCE_DIR) + "/config/scenarios/paper.yaml",
                          "--input", log_file, "--output", out},
                         seconds(120), nullptr, false),
            0)
      << f.log("replay");
  std::ifstream in(out);
  int compared = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.find("\"type\":\"event\"") == std::string::npos ||
        line.find("\"state\":\"raised\"") == std::string::npos) {
      continue;
    }
    const bool is_gyro = line.find("\"sensor\":\"gyro\"") != std::string::npos;
    const MonitorEvent* live = is_gyro ? gyro : acc;
    EXPECT_DOUBLE_EQ(number_of(line, "detection_time"), live->detection_time) << line;
    EXPECT_DOUBLE_EQ(number_of(line, "c_a"), live->c_a) << line;
    EXPECT_DOUBLE_EQ(number_of(line, "c_g"), live->c_g) << line;
    ++compared;
  }
  EXPECT_EQ(compared, 2) << "the replay raised " << compared << " faults";
  // AND the sidecar stops on SIGTERM
  ChildProcess& svc = f.process("svc");
  svc.signal(SIGTERM);
  const auto code = svc.wait_exit(seconds(10));
  ASSERT_TRUE(code.has_value()) << f.log("svc");
  EXPECT_EQ(*code, 0) << f.log("svc");
}

/// "\s:HE0001,n:N,c:MS*hh\$BODY*hh\r\n"
std::string tagged(const std::string& body, std::int64_t n, std::int64_t ms) {
  nmea::TagBlock tag;
  tag.source = "HE0001";
  tag.line_count = (n - 1) % 999 + 1;
  tag.unix_time_ms = ms;
  return nmea::format_tag_block(tag).value() + nmea::test::with_checksum(body) + "\r\n";
}

TEST(NmeaUdpEndToEnd, StoppedRsaSentenceIsReportedAsRudderStaleInFdiStatus) {
  // GIVEN a sidecar reading NMEA over UDP multicast and a monitor of its status
  Fleet f;
  const unsigned m = 257300002;
  const unsigned port = test_port(1);
  const std::string cfg =
      f.write_service_config("svc", m, nmea_service(port, {"rudder_wait: 0.1"}));
  ChildProcess& monitor = f.start("monitor", {"monitor", "--json", "--status"});
  f.start_service("svc", cfg, 1);
  ASSERT_TRUE(f.wait_for_log("svc", "NMEA input: multicast group", seconds(10))) << f.log("svc");
  // WHEN ROT, RSA and VBW arrive at 10 Hz (TAG time) for 3 s, then ROT and VBW without RSA
  // (sent 5 times faster than real time) until the status says so
  nmea_udp::NmeaUdpSender tx(nmea_udp::Endpoint{kGroup, static_cast<std::uint16_t>(port)},
                             "127.0.0.1", 0);
  const std::int64_t epoch = 1767225600000;
  std::int64_t n = 0;
  bool reported = false;
  std::string status_line, last_status;
  const auto deadline = std::chrono::steady_clock::now() + seconds(60);
  for (int k = 0; !reported && std::chrono::steady_clock::now() < deadline; ++k) {
    const std::int64_t ms = epoch + 100 * k;
    std::string lines =
        tagged("HEROT,6.000,A", n + 1, ms) + tagged("VDVBW,1.9438,0.0100,A,,,V", n + 2, ms);
    n += 2;
    if (k < 30) lines += tagged("AGRSA,2.000,A,,V", ++n, ms);
    ASSERT_TRUE(tx.send(std::string(nmea::kIec450Header) + lines));
    std::this_thread::sleep_for(milliseconds(10));
    // The monitor's status lines so far (a short read: the sender goes on meanwhile)
    while (auto line = monitor.read_line(milliseconds(10))) {
      if (line->find("\"type\":\"status\"") == std::string::npos) continue;
      std::vector<MonitorEvent> ev;
      std::vector<MonitorStatus> st;
      std::string err;
      last_status = *line;
      if (!parse_monitor_line(*line, &ev, &st, &err) || st.empty()) continue;
      if (st.back().has_flag("rudder_missing") &&
          line->find("NMEA RSA stale") != std::string::npos) {
        reported = true;
        status_line = *line;
        break;
      }
    }
  }
  // THEN FdiStatus flags the rudder input missing and its message names the RSA sentence
  ASSERT_TRUE(reported) << "last status: " << last_status << "\n" << f.log("svc");
  EXPECT_NE(status_line.find("(delta)"), std::string::npos) << status_line;
  EXPECT_EQ(status_line.find("NMEA ROT stale"), std::string::npos) << status_line;
  EXPECT_EQ(status_line.find("NMEA VBW stale"), std::string::npos) << status_line;
  // AND the sidecar logged that RSA stopped
  EXPECT_TRUE(f.wait_for_log("svc", "NMEA input: RSA (delta) has stopped", seconds(5)))
      << f.log("svc");
}

TEST(NmeaUdpEndToEnd, LostDatagramsAreCountedAndInventNoFault) {
  // GIVEN the paper's scenario as the simulator's NMEA log (ROT, RSA, VBW per sample, TAG
  // times and line counts), a sidecar reading NMEA over UDP multicast, and a monitor
  Fleet f;
  const unsigned m = 257300003;
  const unsigned port = test_port(2);
  std::vector<std::string> lines;
  ASSERT_NO_FATAL_FAILURE(paper_nmea_lines(f, &lines));
  // (the default nmea.max_age, 1 s, with hold_until_due: a value is not given again once its
  // next sentence is due)
  const std::string cfg =
      f.write_service_config("svc", m, nmea_service(port, {"  hold_until_due: true"}, ""));
  ChildProcess& monitor = f.start("monitor", {"monitor", "--json", "--status"});
  f.start_service("svc", cfg, 1);
  ASSERT_TRUE(f.wait_for_log("svc", "NMEA input: multicast group", seconds(10))) << f.log("svc");
  // WHEN the samples are sent as IEC 61162-450 datagrams (10 times faster than real time) but
  // every 37th datagram is lost on the way
  nmea_udp::NmeaUdpSender tx(nmea_udp::Endpoint{kGroup, static_cast<std::uint16_t>(port)},
                             "127.0.0.1", 0);
  unsigned lost = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < 1001; ++k) {
    std::this_thread::sleep_until(t0 + milliseconds(10 * k));
    if (k % 37 == 36) {
      ++lost;
      continue;
    }
    ASSERT_TRUE(tx.send(std::string(nmea::kIec450Header) + lines[3 * k] + lines[3 * k + 1] +
                        lines[3 * k + 2]));
  }
  std::vector<MonitorEvent> ev;
  std::vector<MonitorStatus> st;
  std::string err, lost_status;
  const auto deadline = std::chrono::steady_clock::now() + seconds(30);
  while (lost_status.empty() && std::chrono::steady_clock::now() < deadline) {
    const auto line = monitor.read_line(milliseconds(500));
    if (!line) continue;
    ASSERT_TRUE(parse_monitor_line(*line, &ev, &st, &err)) << err;
    if (line->find("\"type\":\"status\"") != std::string::npos &&
        line->find("NMEA " + std::to_string(3 * lost) + " lines lost") != std::string::npos) {
      lost_status = *line;
    }
  }
  // THEN FdiStatus counts the lost lines (3 per datagram) ...
  EXPECT_FALSE(lost_status.empty()) << "no status with " << 3 * lost << " lines lost\n"
                                    << f.log("svc");
  // ... both faults were still raised and isolated to their sensors, and nothing else was
  // raised during the voyage: a lost datagram is a gap in the data, never a fault
  const MonitorEvent* gyro = first(ev, "gyro", "raised", 0.0, 100.0);
  const MonitorEvent* acc = first(ev, "accelerometer", "raised", 0.0, 100.0);
  ASSERT_NE(gyro, nullptr) << dump(ev) << f.log("svc");
  ASSERT_NE(acc, nullptr) << dump(ev) << f.log("svc");
  EXPECT_GE(gyro->stamp, 20.0) << dump(ev);
  EXPECT_LE(gyro->stamp, 23.0) << dump(ev);
  EXPECT_GE(gyro->c_g, 0.8) << dump(ev);
  EXPECT_GE(acc->stamp, 60.0) << dump(ev);
  EXPECT_LE(acc->stamp, 63.0) << dump(ev);
  EXPECT_GE(acc->c_a, 0.8) << dump(ev);
  for (const auto& e : ev) {
    if (e.stamp >= 100.0 || e.state != "raised") continue;
    EXPECT_TRUE((e.sensor == "gyro" && e.stamp >= 20.0 && e.stamp < 40.0) ||
                (e.sensor == "accelerometer" && e.stamp >= 60.0 && e.stamp < 80.0))
        << dump(ev) << f.log("svc");
  }
}

TEST(NmeaUdpEndToEnd, FromTheNmeaNetworkToTheBridgeAlertsGarbageIsCountedAndNeverActs) {
  // GIVEN a sidecar reading NMEA over UDP multicast, a bridge adapter sending its alerts to the
  // bridge alert management system (the test, on 127.0.0.1), and the noise-free paper scenario
  // (gyro bias 20-40 s, accelerometer bias 60-80 s) as the simulator's NMEA log
  Fleet f;
  const unsigned m = 257300004;
  const std::string ms = std::to_string(m);
  const unsigned port = test_port(3);
  std::vector<std::string> lines;
  ASSERT_NO_FATAL_FAILURE(paper_nmea_lines(f, &lines));
  // The stream pauses while the gyro fault is acknowledged: the wall-clock INS watchdog waits
  // longer than that. Statuses at least every 0.5 s: the bridge calls a vessel silent after 2 s.
  f.start_service(
      "svc",
      f.write_service_config(
          "svc", m,
          nmea_service(port, {"input_timeout: 600", "status_uplink: {heartbeat: 0.5}"}, "")),
      0);
  ASSERT_TRUE(f.wait_for_log("svc", "NMEA input: multicast group", seconds(10))) << f.log("svc");
  bam_side::Udp bam_rx, bam_tx;
  const int acn_in = bam_side::free_port();
  f.start("bridge", {"bridge", "--mmsi", ms, "--out", bam_rx.endpoint(), "--in",
                     "127.0.0.1:" + std::to_string(acn_in), "--hbt-period", "0.5", "--alc-period",
                     "1", "--ack-timeout", "5", "--silent-after", "2"});
  ASSERT_TRUE(f.wait_for_log("bridge", "running", seconds(20))) << f.log("bridge");
  bam_side::Bam bam;
  ASSERT_TRUE(bam_side::receive_until(bam_rx, &bam, seconds(20), [&] {
    return !bam.hbt.empty() && bam.hbt.back().normal;
  })) << f.log("bridge");

  // Sends samples [from, to) as IEC 61162-450 datagrams, 10 times faster than real time, with
  // garbage among them: every 25th datagram carries, after its three sentences, a ROT of an
  // absurd rate, a ROT with a wrong checksum, a truncated sentence and a line that is not
  // NMEA; every 40th is followed by a datagram of another IEC 61162-450 type and one of bytes.
  nmea_udp::NmeaUdpSender tx(nmea_udp::Endpoint{kGroup, static_cast<std::uint16_t>(port)},
                             "127.0.0.1", 0);
  const std::string absurd = nmea::test::with_checksum("HEROT,99999.0,A") + "\r\n";
  std::string bad_checksum = nmea::test::with_checksum("HEROT,12.5,A");
  bad_checksum.back() = bad_checksum.back() == '0' ? '1' : '0';
  bad_checksum += "\r\n";
  unsigned garbage_lines = 0, garbage_datagrams = 0;
  const auto send = [&](std::size_t from, std::size_t to) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t k = from; k < to; ++k) {
      std::this_thread::sleep_until(t0 + milliseconds(10 * (k - from)));
      std::string d =
          std::string(nmea::kIec450Header) + lines[3 * k] + lines[3 * k + 1] + lines[3 * k + 2];
      if (k % 25 == 7) {
        d += absurd + bad_checksum + "$HERO\r\n" + "not nmea at all\r\n";
        garbage_lines += 4;
      }
      ASSERT_TRUE(tx.send(d));
      if (k % 40 == 11) {
        ASSERT_TRUE(tx.send(std::string("RrUdP\0garbage\r\n", 15)));
        ASSERT_TRUE(tx.send("\x01\x02\x03\xff\r\n"));
        garbage_datagrams += 2;
      }
    }
  };

  // WHEN the first 30 s are sent (the gyro bias has begun)
  send(0, 300);
  // THEN the gyro's alert is active-unacknowledged (V), the accelerometer's not raised
  ASSERT_TRUE(bam_side::receive_until(bam_rx, &bam, seconds(30),
                                      [&] { return bam.state_is(bam_side::kGyro, bam_side::V); }))
      << bam.dump() << f.log("bridge") << f.log("svc");
  EXPECT_FALSE(bam.saw(bam_side::kAccel, bam_side::V)) << bam.dump();
  // WHEN the bridge acknowledges it while the fault lasts
  bam_tx.send_to(acn_in, bam_side::acn_datagram(bam_side::kGyro, 'A'));
  // THEN it is active-acknowledged (A)
  ASSERT_TRUE(bam_side::receive_until(bam_rx, &bam, seconds(20),
                                      [&] { return bam.state_is(bam_side::kGyro, bam_side::A); }))
      << bam.dump() << f.log("bridge") << f.log("svc");

  // WHEN the rest of the voyage is sent
  send(300, 1001);
  // THEN the gyro's alert, acknowledged and over, is normal (N); the accelerometer's went V,
  // then rectified-unacknowledged (U)
  ASSERT_TRUE(bam_side::receive_until(bam_rx, &bam, seconds(60),
                                      [&] {
                                        return bam.state_is(bam_side::kGyro, bam_side::N) &&
                                               bam.state_is(bam_side::kAccel, bam_side::U);
                                      }))
      << bam.dump() << f.log("bridge") << f.log("svc");
  EXPECT_TRUE(bam.saw(bam_side::kAccel, bam_side::V)) << bam.dump();
  // WHEN the bridge acknowledges it, THEN it is normal too
  bam_tx.send_to(acn_in, bam_side::acn_datagram(bam_side::kAccel, 'A'));
  ASSERT_TRUE(bam_side::receive_until(bam_rx, &bam, seconds(20),
                                      [&] { return bam.state_is(bam_side::kAccel, bam_side::N); }))
      << bam.dump() << f.log("bridge");
  // AND the garbage acted on nothing: one alert per sensor's fault, no unknown-sensor alert,
  // each raised once
  EXPECT_FALSE(bam.saw(bam_side::kUnknown, bam_side::V)) << bam.dump();
  std::set<std::pair<long, int>> distinct;
  for (const auto& a : bam.alf) {
    if (a.state == bam_side::V) distinct.insert({a.alert.id, a.revision});
  }
  EXPECT_EQ(distinct.size(), 2u) << bam.dump();
  // AND every garbage line and datagram was refused, counted by reason (the sidecar's summary
  // when it stops), and the voyage's lines all used
  EXPECT_TRUE(f.wait_for_log("svc", "line(s) refused", seconds(5))) << f.log("svc");
  f.process("svc").signal(SIGTERM);
  ASSERT_TRUE(f.process("svc").wait_exit(seconds(10)).has_value());
  const std::string svc = f.log("svc");
  const auto at = svc.find("NMEA input stopped: ");
  ASSERT_NE(at, std::string::npos) << svc;
  const std::string summary = svc.substr(at, svc.find('\n', at) - at);
  EXPECT_NE(summary.find(" " + std::to_string(3 * 1001) + " used "), std::string::npos) << summary;
  EXPECT_NE(summary.find(" " + std::to_string(garbage_lines + garbage_datagrams) + " refused ("),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("checksum mismatch"), std::string::npos) << summary;
  EXPECT_NE(summary.find("out of range"), std::string::npos) << summary;
}

}  // namespace
}  // namespace usvfdi::dds::test
