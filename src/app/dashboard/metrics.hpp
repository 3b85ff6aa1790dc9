// The dashboard's Prometheus text (issue 13, section 4): the fleet as the board sees it, for a
// fleet operations centre's monitoring stack. Built with prometheus-cpp (a registry filled from
// the board's input, serialised by its TextSerializer) and served at GET /metrics. No DDS, no
// HTTP in here.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>

#include "board.hpp"

namespace usvfdi::app::dashboard {

/// The metrics text, every vessel-level metric labelled with the vessel's MMSI:
///   usv_fdi_fleet_vessels                           vessels on the board (heard, latched or
///                                                   on the roster)
///   usv_fdi_fleet_silent{mmsi}                      1 silent or never heard, 0 heard lately
///   usv_fdi_fleet_heard_age_seconds{mmsi}           since the vessel was last heard (+Inf:
///                                                   never)
///   usv_fdi_fleet_fault_active{mmsi,sensor}         1 while the latched instance is active
///   usv_fdi_fleet_fault_unacknowledged{mmsi,sensor} 1 while it waits for an acknowledgement
///                                                   (active-unacknowledged or
///                                                   rectified-unacknowledged)
///   usv_fdi_fleet_raises_total{mmsi,sensor}         raises this dashboard has seen (a refined
///                                                   kind is none)
///   usv_fdi_fleet_converged{mmsi}, usv_fdi_fleet_armed{mmsi}   0 or 1, from FdiStatus
///   usv_fdi_fleet_writer_conflicts_total            samples of another writer than an
///                                                   instance's owner (FleetView::conflicts)
///   usv_fdi_dashboard_acks{state}                   acknowledgements asked (the last 100 kept)
///                                                   by state (pending, accepted, refused,
///                                                   unconfirmed)
std::string fleet_metrics(const BoardInput& in, const EventHistory& events,
                          const std::deque<AckOutcome>& acks);

}  // namespace usvfdi::app::dashboard
