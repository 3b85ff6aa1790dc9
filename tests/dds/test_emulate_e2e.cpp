// End-to-end test of `usv-fdi emulate`, the fleet emulator of the shore benchmark: N vessels'
// FdiStatus and FaultEvents from a few participants reach a real `usv-fdi monitor`, every
// vessel with its status, events with increasing sequences, bursts of simultaneous raises.
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "fleet.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::seconds;

TEST(EmulateEndToEnd, EveryEmulatedVesselReachesTheMonitorWithItsEventsAndBursts) {
  // GIVEN a monitor
  Fleet f;
  ChildProcess& monitor = f.start("monitor", {"monitor", "--json", "--status"});
  // WHEN 30 vessels on 3 participants publish statuses at 2 Hz, 10 fault events per second and a
  // burst of 12 simultaneous gyro raises every 2 s
  f.start("emulate", {"emulate", "--vessels", "30", "--participants", "3", "--first-mmsi",
                      "990000101", "--status-rate", "2", "--event-rate", "10", "--burst", "12",
                      "--burst-every", "2", "--duration", "60"});
  // THEN the monitor shows every vessel's status and the raises of at least one burst
  std::vector<MonitorEvent> ev;
  std::vector<MonitorStatus> st;
  std::string err;
  std::set<unsigned> with_status;
  const bool complete = read_monitor_until(
      monitor, &ev, &st, seconds(60),
      [&](const std::vector<MonitorEvent>& e) {
        for (const auto& s : st) with_status.insert(s.mmsi);
        std::set<unsigned> gyro_raised;
        for (const auto& x : e) {
          if (x.sensor == "gyro" && x.state == "raised") gyro_raised.insert(x.mmsi);
        }
        return with_status.size() == 30 && gyro_raised.size() >= 12;
      },
      &err);
  ASSERT_TRUE(complete) << err << " statuses of " << with_status.size() << " vessels, " << ev.size()
                        << " events\n"
                        << f.log("emulate");
  for (unsigned m : with_status) {
    EXPECT_GE(m, 990000101u);
    EXPECT_LE(m, 990000130u);
  }
  // Sequences of an instance increase (a latched reader may skip a state overwritten before it
  // was delivered).
  std::map<std::pair<unsigned, std::string>, unsigned long long> last;
  for (const auto& e : ev) {
    auto& seq = last[{e.mmsi, e.sensor}];
    EXPECT_GT(e.sequence, seq) << e.mmsi << " " << e.sensor;
    seq = e.sequence;
    EXPECT_TRUE(e.state == "raised" || e.state == "cleared") << e.state;
  }
}

}  // namespace
}  // namespace usvfdi::dds::test
