// Helpers for the end-to-end tests of the usv-fdi executable over real Fast DDS: every
// process (sidecar, simulator publisher, monitor) is the real `usv-fdi` binary in its own
// process, on UDPv4 bound to 127.0.0.1, in a domain and partition private to the test.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "monitor_json.hpp"
#include "process.hpp"

namespace usvfdi::dds::test {

/// The monitor's JSON Lines, as the one model of the test-support library (monitor_json.hpp).
using MonitorEvent = usvfdi::test_support::MonitorFault;
using MonitorStatus = usvfdi::test_support::MonitorStatusLine;
using MonitorVessel = usvfdi::test_support::MonitorVesselChange;

/// Parses monitor --json lines (others are ignored); returns false on a malformed JSON line.
bool parse_monitor_line(const std::string& line, std::vector<MonitorEvent>* events,
                        std::vector<MonitorStatus>* statuses, std::string* error,
                        std::vector<MonitorVessel>* vessels = nullptr);

/// `usv-fdi sim --publish` of the paper's scenario on the Otter, noise-free, RELIABLE, with a
/// short linger, followed by `extra`.
std::vector<std::string> sim_args(const std::vector<std::string>& extra);

class Fleet {
 public:
  /// Creates a private directory for configs and logs, a domain id and a partition.
  Fleet();
  /// Kills (SIGKILL) whatever is still running; removes the directory unless the test failed.
  ~Fleet();

  const std::string& dir() const { return dir_; }
  /// --domain, --partition, --participant-profile (loopback), --qos (shipped profiles).
  std::vector<std::string> dds_args() const;

  /// Writes the paper scenario's engine config (config/scenarios/paper.yaml) with a service
  /// section: mmsi, reliable_inputs, status_rate 5, rudder_wait 1 s (wall time for a resent
  /// sample), state_dir <dir>/state_<name> (unless
  /// `extra` sets it), and `extra` lines (indented 2 spaces).
  std::string write_service_config(const std::string& name, unsigned mmsi,
                                   const std::vector<std::string>& extra = {}) const;

  /// The state directory write_service_config() gives the sidecar of config `name`.
  std::string state_dir(const std::string& name) const { return dir_ + "state_" + name; }

  /// Starts `usv-fdi <args> <dds_args>` (without the DDS options if !dds) with stderr to
  /// <dir>/<name>.log.
  ChildProcess& start(const std::string& name, std::vector<std::string> args,
                      const std::vector<std::string>& extra_env = {}, bool dds = true);
  /// Starts `usv_fdi_dds_probe <mode> <args>` on the fleet's domain and partition.
  ChildProcess& start_probe(const std::string& name, const std::string& mode,
                            std::vector<std::string> args);
  ChildProcess& process(const std::string& name) { return *procs_.at(name); }
  std::string log(const std::string& name) const;
  /// Waits until <name>.log contains `text`.
  bool wait_for_log(const std::string& name, const std::string& text,
                    std::chrono::milliseconds timeout) const;

  /// Starts the sidecar for `mmsi` and waits until it runs; with `wait_monitors`, also until
  /// that many fault-event readers are matched.
  ChildProcess& start_service(const std::string& name, const std::string& config,
                              int wait_monitors = 0, std::vector<std::string> extra_args = {});
  /// Runs a process to its end (bounded); returns its exit code (nullopt: still running).
  std::optional<int> run_to_end(const std::string& name, std::vector<std::string> args,
                                std::chrono::milliseconds timeout, std::string* out = nullptr,
                                bool dds = true);

 private:
  std::string dir_;
  std::string domain_, partition_;
  std::map<std::string, std::unique_ptr<ChildProcess>> procs_;
};

/// Reads monitor lines until `done(events)` holds or the timeout elapses.
template <class Done>
bool read_monitor_until(ChildProcess& monitor, std::vector<MonitorEvent>* events,
                        std::vector<MonitorStatus>* statuses, std::chrono::milliseconds timeout,
                        Done done, std::string* error) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done(*events)) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    const auto line = monitor.read_line(left);
    if (!line) return false;
    if (!parse_monitor_line(*line, events, statuses, error)) return false;
  }
  return true;
}

/// Reads monitor lines until a status of each of `mmsis` has counted at least `samples` samples:
/// a sidecar's status uplink sends the final count with its next heartbeat (within 3 s by
/// default), not at once.
inline bool read_until_samples(ChildProcess& monitor, std::vector<MonitorEvent>* events,
                               std::vector<MonitorStatus>* statuses,
                               const std::vector<unsigned>& mmsis, unsigned long long samples,
                               std::chrono::milliseconds timeout, std::string* error) {
  return read_monitor_until(
      monitor, events, statuses, timeout,
      [&](const std::vector<MonitorEvent>&) {
        for (unsigned m : mmsis) {
          bool seen = false;
          for (const MonitorStatus& s : *statuses)
            seen = seen || (s.mmsi == m && s.samples >= samples);
          if (!seen) return false;
        }
        return true;
      },
      error);
}

}  // namespace usvfdi::dds::test
