// C++ face of tests/fleet/netns.sh for gtest fleet tests: an RAII set of network namespaces (a
// shore namespace with a bridge, two discovery-server hosts, N vessel namespaces; each node with
// its own /dev/shm), removed
// again when the object goes away, including the processes still running in them. Header-only;
// needs USV_FDI_NETNS_SCRIPT (the path of netns.sh) defined by the build.
//
//   usvfdi::fleet::test::NetnsFleet fleet("ft", 5);
//   if (!fleet.available()) GTEST_SKIP() << fleet.skip_reason();
//   ChildProcess sidecar(fleet.in("v1", {usv_fdi_exe, "run", ...}));
//   fleet.addr("shore");        // "10.77.0.1"
//   fleet.set_link("v1", false);  // partition vessel 1 from the shore (and the other vessels)
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace usvfdi::fleet::test {

class NetnsFleet {
 public:
  /// Makes NAME-shore and NAME-v1..NAME-vN (NAME: letters and digits, at most 8; make it unique
  /// per process, e.g. with the pid). When namespaces cannot be made here, available() is false
  /// and skip_reason() says why; when they can but setting up fails, throws std::runtime_error.
  NetnsFleet(std::string name, unsigned vessels) : name_(std::move(name)), vessels_(vessels) {
    int rc = 0;
    const std::string why = run(kScript + std::string(" check"), &rc);
    if (rc != 0) {
      skip_reason_ = why.empty() ? "network namespaces unavailable" : why;
      return;
    }
    const std::string out = run(kScript + (" up " + name_ + " " + std::to_string(vessels_)), &rc);
    if (rc != 0) throw std::runtime_error("netns.sh up " + name_ + " failed: " + out);
    up_ = true;
  }
  ~NetnsFleet() {
    if (up_) {
      int rc = 0;
      (void)run(kScript + (" down " + name_), &rc);
    }
  }
  NetnsFleet(const NetnsFleet&) = delete;
  NetnsFleet& operator=(const NetnsFleet&) = delete;

  bool available() const { return up_; }
  const std::string& skip_reason() const { return skip_reason_; }
  unsigned vessels() const { return vessels_; }
  /// Nodes: "shore", "d0" and "d1" (discovery-server hosts), "v<i>" (vessel i, 1-based).
  static std::string vessel(unsigned i) { return "v" + std::to_string(i); }
  /// IPv4 address of a node ("shore" -> 10.77.0.1, "d0"/"d1" -> 10.77.0.2/3,
  /// "v<i>" -> 10.77.0.(10+i)); the shore also holds 10.77.0.5.
  std::string addr(const std::string& node) const {
    if (node == "shore") return "10.77.0.1";
    if (node == "d0") return "10.77.0.2";
    if (node == "d1") return "10.77.0.3";
    return "10.77.0." + std::to_string(10 + std::stoul(node.substr(1)));
  }
  /// The argv that runs `argv` on `node` (for ChildProcess or posix_spawn): in its network
  /// namespace, with its own /dev/shm (what `netns.sh exec` does). Every step execs the next, so
  /// the process keeps the pid (and the parent-death signal) of the one spawned.
  std::vector<std::string> in(const std::string& node, const std::vector<std::string>& argv) const {
    std::vector<std::string> out = {"/usr/sbin/ip",
                                    "netns",
                                    "exec",
                                    name_ + "-" + node,
                                    "unshare",
                                    "--mount",
                                    "sh",
                                    "-c",
                                    "mount --bind \"$0\" /dev/shm && exec \"$@\"",
                                    shm_dir(node)};
    out.insert(out.end(), argv.begin(), argv.end());
    return out;
  }
  /// The directory mounted on `node`'s /dev/shm (netns.sh: FLEET_SHM_ROOT/NAME-<node>).
  std::string shm_dir(const std::string& node) const {
    const char* root = std::getenv("FLEET_SHM_ROOT");
    return std::string(root != nullptr ? root : "/dev/shm/usv-fdi-netns") + "/" + name_ + "-" +
           node;
  }
  /// Takes `node`'s (v<i>, d0, d1) link to the shore bridge down (a network partition) or back
  /// up: what `netns.sh link` does, with one `ip` command (no shell script: a partition test on
  /// a starved machine wants the cut to happen when it asks for it).
  void set_link(const std::string& node, bool up) const {
    int rc = 0;
    const std::string out = run("/usr/sbin/ip -n " + name_ + "-shore link set " + name_ + node +
                                    "s " + (up ? "up" : "down"),
                                &rc);
    if (rc != 0) throw std::runtime_error("ip link set " + node + " failed: " + out);
  }

 private:
  static constexpr const char* kScript = USV_FDI_NETNS_SCRIPT;

  /// Runs a shell command, returns its stdout+stderr (trimmed) and sets *rc to its exit code.
  static std::string run(const std::string& cmd, int* rc) {
    std::string out;
    FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
    if (p == nullptr) {
      *rc = -1;
      return "popen failed";
    }
    std::array<char, 512> buf{};
    while (std::fgets(buf.data(), static_cast<int>(buf.size()), p) != nullptr) out += buf.data();
    const int status = ::pclose(p);
    *rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
    return out;
  }

  std::string name_;
  unsigned vessels_;
  bool up_ = false;
  std::string skip_reason_;
};

}  // namespace usvfdi::fleet::test
