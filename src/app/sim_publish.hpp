// usv-fdi sim --publish: the simulator as a DDS publisher of INS and rudder samples.
#pragma once

#include <cstdint>
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

/// Publishes every vessel's simulation in lockstep (all at the first vessel's rate), paced
/// to real time x speed, until the duration ends or SIGINT/SIGTERM (blocked beforehand).
/// Returns a process exit code.
int publish_simulation(const std::vector<std::pair<std::uint32_t, SimConfig>>& vessels,
                       const usvfdi::dds::DdsConfig& dds, const PublishOptions& opt);

}  // namespace usvfdi::app
