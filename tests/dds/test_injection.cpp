// Log and terminal injection (issue 15, Medium 9): a peer-supplied string (an operator id, a fault
// message) must not forge a log line, and CR or escape codes must not reach the monitor's table
// raw. The real sidecar, simulator and monitor, and a probe writing hostile messages, each in its
// own process on loopback.
#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <string>

#include "fleet.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::seconds;

bool has_line_starting(const std::string& text, const std::string& head) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.compare(0, head.size(), head) == 0) return true;
  }
  return false;
}

TEST(Injection, ANewlineInTheOperatorIdDoesNotForgeASidecarLogLine) {
  Fleet f;
  const unsigned m = 257500001;
  const std::string ms = std::to_string(m);
  // GIVEN a sidecar after the paper's first 45 s: gyro #2 cleared, awaiting its acknowledgement
  const std::string cfg = f.write_service_config("svc", m, {"input_timeout: 60"});
  f.start_service("svc", cfg);
  const auto sim = f.run_to_end(
      "sim", sim_args({"--mmsi", ms, "--speed", "25", "--duration", "45"}), seconds(40));
  ASSERT_TRUE(sim.has_value() && *sim == 0) << f.log("sim");
  ASSERT_TRUE(f.wait_for_log("svc", "gyro #2 cleared", seconds(10))) << f.log("svc");
  // WHEN an operator id carries a newline and the text of a forged log line
  const std::string forged = "usv-fdi: info: ack of accelerometer #7 by captain accepted";
  const auto ack =
      f.run_to_end("ack", {"monitor", "--ack", ms + ":gyro:2", "--operator", "m\n" + forged + "\r"},
                   seconds(30));
  ASSERT_TRUE(ack.has_value());
  EXPECT_EQ(*ack, 0) << f.log("ack") << f.log("svc");
  // THEN the sidecar logs the ack on one line, the operator id escaped, and no forged line
  const std::string log = f.log("svc");
  EXPECT_FALSE(has_line_starting(log, forged)) << log;
  EXPECT_NE(log.find("ack of gyro #2 by m\\n" + forged + "\\r accepted"), std::string::npos) << log;
  EXPECT_EQ(log.find('\r'), std::string::npos) << log;
  EXPECT_EQ(log.find('\x1b'), std::string::npos) << log;
  // AND the monitor's view of the acknowledged event carries the escaped text, nothing raw
  std::string out;
  const auto mon = f.run_to_end("table", {"monitor", "--once", "--expect", "1", "--duration", "15"},
                                seconds(20), &out);
  ASSERT_TRUE(mon.has_value());
  EXPECT_NE(out.find("acknowledged by m\\nusv-fdi"), std::string::npos) << out;
  EXPECT_EQ(out.find('\r'), std::string::npos) << out;
  EXPECT_EQ(out.find('\x1b'), std::string::npos) << out;
  EXPECT_FALSE(has_line_starting(out, forged)) << out;
}

TEST(Injection, EscapeCodesInAFaultMessageDoNotReachTheTerminal) {
  Fleet f;
  // GIVEN a writer of fault events whose message holds a CR, a clear-screen and a colour code
  f.start_probe("hostile", "publish-faults",
                {"--vessels", "1", "--mmsi-base", "257500002", "--sensors", "1", "--message",
                 "\x1b[2J\x1b[31mALL CLEAR\r\nFAKE: every vessel healthy", "--timeout", "60"});
  ASSERT_TRUE(f.process("hostile").read_line(std::chrono::milliseconds(20000)).has_value())
      << f.log("hostile");
  // WHEN the monitor prints its table and its JSON
  std::string table, json;
  const auto t = f.run_to_end("table", {"monitor", "--once", "--expect", "1", "--duration", "10"},
                              seconds(30), &table);
  const auto j =
      f.run_to_end("json", {"monitor", "--once", "--json", "--expect", "1", "--duration", "10"},
                   seconds(30), &json);
  ASSERT_TRUE(t.has_value() && j.has_value());
  // THEN no control byte reaches stdout; the message is shown escaped on its row
  for (const std::string* out : {&table, &json}) {
    EXPECT_EQ(out->find('\x1b'), std::string::npos) << *out;
    EXPECT_EQ(out->find('\r'), std::string::npos) << *out;
  }
  EXPECT_NE(table.find("\\x1b[2J\\x1b[31mALL CLEAR\\r\\nFAKE: every vessel healthy"),
            std::string::npos)
      << table;
  EXPECT_FALSE(has_line_starting(table, "FAKE:")) << table;
}

}  // namespace
}  // namespace usvfdi::dds::test
