// The docker/compose.yaml fleet without Docker, for gtest: network namespaces (netns_fleet.hpp)
// with the real `usv-fdi` executable as sidecar and simulator on every vessel node and as the
// monitor on the shore node, and two Fast DDS discovery servers (`fast-discovery-server`, what
// `fastdds discovery` runs) on hosts of their own, at the compose file's addresses:
//
//   d0, d1      discovery servers 0 and 1 at 10.77.0.2 and 10.77.0.3, port 11811, UDP only
//               (usv_fdi_discovery_server_udp, docker/fleet_participants.xml)
//   shore node  10.77.0.1 (bridge) and 10.77.0.5: monitor with --participant-profile
//               usv_fdi_fleet_udp (UDPv4 only), --partition vessel-*
//   vessel i    10.77.0.(10+i), MMSI 257000000+i, partition vessel-<MMSI>: sidecar (run) and
//               simulator (sim --publish) with --participant-profile usv_fdi_participant
//               (shared memory + UDPv4; the node's own /dev/shm, as the compose file's vessel
//               containers share an IPC namespace)
//   every process: ROS_DISCOVERY_SERVER="10.77.0.2:11811;10.77.0.3:11811",
//                  FASTRTPS_DEFAULT_PROFILES_FILE=docker/fleet_participants.xml (or a test file)
//
// Why these transports: every node has its own network namespace but the machine's hostname, and
// Fast DDS 2.9 decides "same host, use shared memory" from a host id it derives from what it sees
// of the host; it never checks that the peer's /dev/shm is the one it writes to. Here each node
// has its own /dev/shm (as a container has), so a participant that took a peer on another node
// for a local one would lose every sample to segments nobody reads. The shore's participants use
// the UDP-only profile, so nothing crossing the bridge can depend on that guess (and no
// shared-memory path can bypass a partitioned link); a vessel's simulator and sidecar share their
// node's /dev/shm and may use shared memory between them, exactly as in the compose file.
//
// Why a partition per vessel: the INS and rudder topics are fleet-wide. Without partitions every
// sidecar matches every vessel's simulator, so each vessel's 50 Hz INS stream crosses the radio
// link to every other vessel (N^2 traffic), and when one vessel's link goes down the writers that
// serve the unreachable readers disturb the vessel's own sidecar: in three runs of this partition
// test without partitions, the cut vessel's sidecar lost 49, 79 and 308 of its own 5001 samples
// (published on the vessel itself, over UDP or shared memory) and raised spurious drift and
// accelerometer faults. With `--partition vessel-<MMSI>` on the vessel and `vessel-*` on the shore
// the inputs stay on the vessel; only events, status and acks cross the link.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "monitor_log.hpp"
#include "netns_fleet.hpp"
#include "process.hpp"

namespace usvfdi::fleet::test {

class ServiceFleet {
 public:
  struct Options {
    std::string name;  ///< namespace prefix (letters and digits, <= 8; unique per process)
    unsigned vessels = 1;
    /// FASTRTPS_DEFAULT_PROFILES_FILE of every usv-fdi process (default: the compose file's).
    std::string participant_profiles;
    std::string vessel_profile = "usv_fdi_participant";
    std::string shore_profile = "usv_fdi_fleet_udp";
    /// docker/compose.secure.yaml instead: a PKI made by make-security.sh with identities shore,
    /// vessel<i>, vessel<i>-sim and the fleet's addresses as --initial-peers. Every process then
    /// loads its security_profiles.xml and runs usv_fdi_secure_<identity>_unicast; no
    /// ROS_DISCOVERY_SERVER (SIMPLE discovery by unicast; start no discovery servers).
    std::string secure_pki;
  };

  explicit ServiceFleet(Options o);
  /// Kills what still runs (SIGKILL), removes the namespaces; keeps the logs if the test failed.
  ~ServiceFleet();
  ServiceFleet(const ServiceFleet&) = delete;
  ServiceFleet& operator=(const ServiceFleet&) = delete;

  bool available() const { return net_.available(); }
  const std::string& skip_reason() const { return net_.skip_reason(); }
  NetnsFleet& net() { return net_; }
  const std::string& dir() const { return dir_; }
  /// Seconds since the fleet was made (the clock of MonitorLog's `received`).
  double now() const;
  std::chrono::steady_clock::time_point t0() const { return t0_; }

  static unsigned mmsi(unsigned i) { return 257000000u + i; }
  static std::string partition(unsigned i) { return "vessel-" + std::to_string(mmsi(i)); }

  /// Starts both discovery servers (hosts d0, d1) and waits (bounded) until they listen.
  bool start_discovery_servers();
  /// Starts `argv` on `node`, with the fleet's environment unless `fleet_env` is false;
  /// stderr to <dir>/<name>.log.
  dds::test::ChildProcess& start(const std::string& node, const std::string& name,
                                 const std::vector<std::string>& argv, bool fleet_env = true);
  /// `usv-fdi monitor --json --status` on the shore, all vessels' partitions, + `extra`.
  dds::test::ChildProcess& start_monitor(const std::string& name,
                                         const std::vector<std::string>& extra = {});
  /// The sidecar of vessel i (paper scenario's engine config; RELIABLE inputs, status at 5 Hz,
  /// input timeout 60 s) + `extra_yaml` service lines; waits until it runs.
  dds::test::ChildProcess& start_sidecar(unsigned i,
                                         const std::vector<std::string>& extra_yaml = {});
  /// The simulator of vessel i: `sim --publish --reliable --noise-scale 0 --mmsi M` + `extra`.
  dds::test::ChildProcess& start_sim(unsigned i, const std::vector<std::string>& extra);
  /// Runs usv-fdi `args` (+ the shore's DDS options) on the shore to its end (bounded).
  std::optional<int> run_on_shore(const std::string& name, std::vector<std::string> args,
                                  std::chrono::milliseconds timeout, std::string* out = nullptr);

  dds::test::ChildProcess& process(const std::string& name) { return *procs_.at(name); }
  std::string log(const std::string& name) const;
  bool wait_for_log(const std::string& name, const std::string& text,
                    std::chrono::milliseconds timeout) const;
  /// Sends SIGTERM and waits (bounded); returns the exit code (nullopt: still running).
  std::optional<int> stop(const std::string& name, std::chrono::milliseconds timeout);
  /// The last few lines of every log, for a failure message.
  std::string logs_tail() const;

  /// DDS options of the usv-fdi processes on vessel i (`sim`: of its simulator) / the shore.
  std::vector<std::string> vessel_dds(unsigned i, bool sim = false) const;
  std::vector<std::string> shore_dds() const;

 private:
  Options opt_;
  NetnsFleet net_;
  std::chrono::steady_clock::time_point t0_;
  std::string dir_;
  std::vector<std::string> env_;
  std::map<std::string, std::unique_ptr<dds::test::ChildProcess>> procs_;
};

}  // namespace usvfdi::fleet::test
