// When the monitor warns that discovery may miss participants (issue 14, item 4): the limit is
// what the participant QoS in use can discover by unicast (unicast_discovery_limit() in
// fleet_view.hpp reads it); the policy, here, is pure.
#pragma once

#include <cstddef>

namespace usvfdi::app {

/// The share of the limit from which the monitor warns that it is being approached.
constexpr double kDiscoveryWarnShare = 0.75;

/// 0: well within `limit` (or no limit, `limit` <= 0); 1: `participants` (this one included) is
/// at least kDiscoveryWarnShare of it; 2: at or beyond it.
inline int discovery_limit_level(std::size_t participants, int limit) {
  if (limit <= 0) return 0;
  const double n = static_cast<double>(participants);
  if (n >= static_cast<double>(limit)) return 2;
  return n >= kDiscoveryWarnShare * static_cast<double>(limit) ? 1 : 0;
}

}  // namespace usvfdi::app
