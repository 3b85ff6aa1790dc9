// A forged all-clear (issue 15, High 1): a participant that writes `normal` or `acknowledged` for
// another vessel's raised fault instance must not hide the alarm on a running monitor. The real
// sidecar, simulator and monitor, and a forger (usv_fdi_dds_probe publish-faults with a higher
// sequence), each in its own process on loopback, without DDS Security (the monitor's first-writer
// rule; DDS Security's own test is tests/security/test_service_security.cpp).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <sstream>
#include <string>
#include <vector>

#include "fleet.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

/// Everything the monitor printed, and the latest fault of each sensor in it.
struct MonitorOut {
  std::vector<std::string> lines;
  std::vector<MonitorEvent> events;
  const MonitorEvent* latest(const std::string& sensor) const {
    const MonitorEvent* out = nullptr;
    for (const auto& e : events) {
      if (e.sensor == sensor) out = &e;
    }
    return out;
  }
  bool has(const std::string& text) const {
    for (const auto& l : lines) {
      if (l.find(text) != std::string::npos) return true;
    }
    return false;
  }
  int count(const std::string& text) const {
    int n = 0;
    for (const auto& l : lines) n += l.find(text) != std::string::npos ? 1 : 0;
    return n;
  }
  std::string dump() const {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
  }
};

/// Reads the monitor's lines for `for_ms`, or until `done` holds.
template <class Done>
bool read_for(ChildProcess& m, MonitorOut* out, milliseconds timeout, Done done) {
  const auto deadline = Clock::now() + timeout;
  while (!done(*out)) {
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return false;
    const auto line = m.read_line(left);
    if (!line) return false;
    out->lines.push_back(*line);
    std::string err;
    EXPECT_TRUE(parse_monitor_line(*line, &out->events, nullptr, &err)) << err << ": " << *line;
  }
  return true;
}

TEST(ForgedEvents, AForgedAllClearDoesNotHideARaisedAlarmOnARunningMonitor) {
  Fleet f;
  const unsigned m = 257400001;
  const std::string ms = std::to_string(m);
  // GIVEN a sidecar, a running monitor, and the paper's first 70 s: gyro #2 cleared (awaiting its
  // acknowledgement), accelerometer #1 raised
  const std::string cfg = f.write_service_config("svc", m, {"input_timeout: 60"});
  ChildProcess& mon = f.start("monitor", {"monitor", "--json"});
  f.start_service("svc", cfg, 1);
  const auto sim = f.run_to_end(
      "sim", sim_args({"--mmsi", ms, "--speed", "25", "--duration", "70"}), seconds(40));
  ASSERT_TRUE(sim.has_value() && *sim == 0) << f.log("sim");
  MonitorOut out;
  ASSERT_TRUE(read_for(mon, &out, seconds(15),
                       [](const MonitorOut& o) {
                         const MonitorEvent* a = o.latest("accelerometer");
                         const MonitorEvent* g = o.latest("gyro");
                         return a != nullptr && a->state == "raised" && g != nullptr &&
                                g->state == "cleared";
                       }))
      << out.dump() << f.log("monitor");

  // WHEN a forger writes the accelerometer instance `normal` and the gyro `acknowledged`, both with
  // a sequence far ahead (#100)
  f.start_probe("forge_acc", "publish-faults",
                {"--vessels", "1", "--mmsi-base", ms, "--sensor", "0", "--state", "0", "--sequence",
                 "100", "--message", "all clear", "--timeout", "60"});
  f.start_probe("forge_gyro", "publish-faults",
                {"--vessels", "1", "--mmsi-base", ms, "--sensor", "1", "--state", "4", "--sequence",
                 "100", "--message", "acknowledged", "--timeout", "60"});
  // THEN the monitor reports both conflicts, naming the vessel, the sensor and both writers
  ASSERT_TRUE(read_for(mon, &out, seconds(20),
                       [](const MonitorOut& o) { return o.count("\"type\":\"conflict\"") >= 2; }))
      << out.dump() << f.log("monitor");
  for (const char* s : {"accelerometer", "gyro"}) {
    SCOPED_TRACE(s);
    const std::string head =
        "{\"type\":\"conflict\",\"mmsi\":" + ms + ",\"sensor\":\"" + s + "\",\"verdict\":\"held\"";
    EXPECT_TRUE(out.has(head)) << out.dump();
  }
  EXPECT_NE(f.log("monitor").find("CONFLICT vessel " + ms + " accelerometer: writer "),
            std::string::npos)
      << f.log("monitor");
  EXPECT_NE(f.log("monitor").find("#100 normal but the instance belongs to writer "),
            std::string::npos)
      << f.log("monitor");
  // AND it still shows the sidecar's states, not the forged ones
  ASSERT_NE(out.latest("accelerometer"), nullptr);
  EXPECT_EQ(out.latest("accelerometer")->state, "raised") << out.dump();
  EXPECT_EQ(out.latest("accelerometer")->sequence, 1u) << out.dump();
  EXPECT_EQ(out.latest("gyro")->state, "cleared") << out.dump();
  EXPECT_EQ(out.latest("gyro")->sequence, 2u) << out.dump();

  // WHEN the forgers leave
  for (const char* p : {"forge_acc", "forge_gyro"}) {
    f.process(p).signal(SIGTERM);
    EXPECT_EQ(f.process(p).wait_exit(seconds(10)).value_or(-1), 0) << f.log(p);
  }
  // THEN nothing they wrote appears; a real change still does: the operator acknowledges the gyro
  const auto ack =
      f.run_to_end("ack", {"monitor", "--ack", ms + ":gyro:2", "--operator", "alice"}, seconds(30));
  ASSERT_TRUE(ack.has_value());
  EXPECT_EQ(*ack, 0) << f.log("ack") << f.log("svc");
  ASSERT_TRUE(read_for(mon, &out, seconds(10), [](const MonitorOut& o) {
    const MonitorEvent* g = o.latest("gyro");
    return g != nullptr && g->state == "acknowledged";
  })) << out.dump();
  EXPECT_EQ(out.latest("gyro")->sequence, 3u) << out.dump();
  EXPECT_EQ(out.latest("accelerometer")->state, "raised") << out.dump();
  EXPECT_EQ(out.latest("accelerometer")->sequence, 1u) << out.dump();
  for (const auto& e : out.events) EXPECT_LT(e.sequence, 100u) << out.dump();
}

}  // namespace
}  // namespace usvfdi::dds::test
