// Prometheus metrics of a sidecar (issue 13, section 4): a text endpoint (GET /metrics) served
// by prometheus-cpp's exposer, refreshed from the pipeline's status and liveness. An adapter:
// the core and the pipeline know nothing of it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::metrics {

/// The sidecar's metrics, every one labelled with the vessel's MMSI:
///   usv_fdi_raises_total{sensor}              faults raised this run (transitions into raised)
///   usv_fdi_statistic{channel}                J_N of the residual channel, and
///   usv_fdi_threshold{channel}                its enter threshold (0 before arming)
///   usv_fdi_isolation_confidence{sensor}      C_a, C_g
///   usv_fdi_converged, usv_fdi_armed, usv_fdi_model_mismatch   0 or 1
///   usv_fdi_identification_paused, usv_fdi_isolation_paused   PauseReason bits (0: running)
///   usv_fdi_input_age_seconds{input}          since the last INS / rudder sample (+Inf: none yet)
///   usv_fdi_thread_age_seconds{thread}        since each pipeline thread last went round
///   usv_fdi_samples_total                     samples assembled
///   usv_fdi_dropped_samples_total{queue}      queue overflows (input, identification, output)
///   usv_fdi_lost_samples_total{input}         sequence gaps of the INS / rudder topics
///   usv_fdi_rejected_samples_total            samples refused for their time stamp
class SidecarMetrics {
 public:
  /// Serves on `bind` ("host:port"; port 0: any free port). Throws std::runtime_error naming
  /// the address when it cannot listen.
  SidecarMetrics(const std::string& bind, std::uint32_t mmsi);
  ~SidecarMetrics();
  SidecarMetrics(const SidecarMetrics&) = delete;
  SidecarMetrics& operator=(const SidecarMetrics&) = delete;

  /// The ports it listens on (the one chosen for port 0).
  std::vector<int> ports() const;
  /// Refreshes every metric from a status snapshot and the threads' liveness.
  void update(const pipeline::PipelineStatus& status, const pipeline::PipelineLiveness& live);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace usvfdi::metrics
