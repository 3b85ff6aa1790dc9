// usv-fdi sim --publish: the simulator as a DDS publisher of INS and rudder samples.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/dds/dds_context.hpp"

namespace usvfdi::app {

struct PublishOptions {
  double speed = 1.0;          ///< data time per wall time (2: twice real time)
  bool reliable = false;       ///< RELIABLE writers instead of BEST_EFFORT
  double wait_readers = 10.0;  ///< wait this long for the readers before starting [s]
  int min_readers = 1;         ///< start once this many INS and rudder readers are matched
  double linger = 1.0;         ///< keep the writers this long after the last sample [s]
};

/// One vessel's samples for --publish: the classic simulator or a voyage.
class RowSource {
 public:
  virtual ~RowSource() = default;
  /// The next sample, and its surge speed *u [m/s] (NaN: none, no SpeedSample is written);
  /// false once the voyage is over.
  virtual bool next(SimRow* row, double* u) = 0;
  /// Whether this source gives a surge speed (the speed writer is created only then).
  virtual bool has_speed() const = 0;
};

/// Vessels to publish: each MMSI with its samples.
using PublishedVessels = std::vector<std::pair<std::uint32_t, std::unique_ptr<RowSource>>>;

/// Publishes every vessel's samples in lockstep (rate_hz: for the log), paced to real time x
/// speed, until one source ends or SIGINT/SIGTERM (blocked beforehand): per step, each vessel's
/// SpeedSample (where it has a speed), RudderSample, then InsSample. Returns a process exit code.
int publish_rows(PublishedVessels vessels, double rate_hz, const usvfdi::dds::DdsConfig& dds,
                 const PublishOptions& opt);

/// publish_rows of the classic simulator (no speed).
int publish_simulation(const std::vector<std::pair<std::uint32_t, SimConfig>>& vessels,
                       const usvfdi::dds::DdsConfig& dds, const PublishOptions& opt);

}  // namespace usvfdi::app
