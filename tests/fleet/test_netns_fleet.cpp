// Self-test of the C++ namespace helper (netns_fleet.hpp): processes started through in() run in
// their node's namespace with its address and its own /dev/shm, set_link() cuts a vessel's link,
// and the namespaces (and their /dev/shm) are gone after the helper is.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include "netns_fleet.hpp"
#include "process.hpp"

namespace usvfdi::fleet::test {
namespace {

using dds::test::ChildProcess;
using std::chrono::milliseconds;

std::string run_in(const NetnsFleet& fleet, const std::string& node,
                   const std::vector<std::string>& argv) {
  ChildProcess p(fleet.in(node, argv));
  std::string out = p.read_all(milliseconds(10000));
  EXPECT_EQ(p.wait_exit(milliseconds(5000)).value_or(-1), 0) << out;
  return out;
}

bool namespace_exists(const std::string& ns) {
  return ::access(("/run/netns/" + ns).c_str(), F_OK) == 0;
}

TEST(NetnsFleet, NodesHaveTheirAddressesAndAreRemovedAfterwards) {
  const std::string name = "nf" + std::to_string(::getpid() % 100000);
  {
    NetnsFleet fleet(name, 2);
    if (!fleet.available()) GTEST_SKIP() << fleet.skip_reason();
    EXPECT_EQ(fleet.addr("shore"), "10.77.0.1");
    EXPECT_EQ(fleet.addr(NetnsFleet::vessel(2)), "10.77.0.12");
    for (const std::string node : {"shore", "v1", "v2"}) {
      const std::string dev = node == "shore" ? "br0" : "eth0";
      const std::string out =
          run_in(fleet, node, {"/usr/sbin/ip", "-4", "-o", "addr", "show", "dev", dev});
      EXPECT_NE(out.find(" " + fleet.addr(node) + "/24 "), std::string::npos)
          << node << ": " << out;
    }
    EXPECT_EQ(fleet.addr("d1"), "10.77.0.3");
    EXPECT_NE(run_in(fleet, "d1", {"/usr/sbin/ip", "-4", "-o", "addr", "show", "dev", "eth0"})
                  .find(" 10.77.0.3/24 "),
              std::string::npos);
    // Each node its own /dev/shm, shared by what runs on it.
    run_in(fleet, "v1", {"/bin/sh", "-c", "echo v1 > /dev/shm/netns-fleet-probe"});
    EXPECT_EQ(run_in(fleet, "v1", {"/bin/cat", "/dev/shm/netns-fleet-probe"}), "v1\n");
    ChildProcess other(fleet.in("v2", {"/usr/bin/test", "-e", "/dev/shm/netns-fleet-probe"}));
    EXPECT_EQ(other.wait_exit(milliseconds(5000)).value_or(-1), 1) << "v2 sees v1's /dev/shm";
    EXPECT_NE(::access("/dev/shm/netns-fleet-probe", F_OK), 0);
    EXPECT_EQ(::access((fleet.shm_dir("v1") + "/netns-fleet-probe").c_str(), F_OK), 0);
    EXPECT_TRUE(namespace_exists(name + "-v2"));
    // A partition: vessel 1's link at the bridge goes down and comes back.
    fleet.set_link("v1", false);
    EXPECT_NE(run_in(fleet, "shore", {"/usr/sbin/ip", "-o", "link", "show", name + "v1s"})
                  .find("state DOWN"),
              std::string::npos);
    fleet.set_link("v1", true);
  }
  EXPECT_FALSE(namespace_exists(name + "-shore"));
  EXPECT_FALSE(namespace_exists(name + "-v1"));
  EXPECT_FALSE(namespace_exists(name + "-v2"));
  EXPECT_NE(::access(("/dev/shm/usv-fdi-netns/" + name + "-v1").c_str(), F_OK), 0);
}

}  // namespace
}  // namespace usvfdi::fleet::test
