// How the monitor shows the fleet: JSON Lines objects and the table. Pure functions of the model
// and of the clocks passed in (`now`: wall-clock unix s, `mono`: monotonic s), so that they can be
// unit-tested; every peer-supplied text is escaped (escape_text) before it is shown.
#pragma once

#include <cstdint>
#include <set>
#include <string>

#include "instance_owners.hpp"
#include "monitor_model.hpp"
#include "roster.hpp"
#include "vessel_liveness.hpp"

namespace usvfdi::app {

/// {"type":"fault",...}: one fault instance; `heard_age`: seconds since the vessel was heard.
std::string json_row(const Row& r, double heard_age, double now);
/// One line on the inputs of a vessel: problems, counters, pauses.
std::string inputs_line(const fdi::FdiStatus& s);
/// {"type":"status",...}: one vessel's FdiStatus.
std::string json_status(const VesselStatus& v, double heard_age, double now);
/// "vessel 257000001 (silent): last heard 7.2 s ago" (the start of a vessel's line).
std::string heard_line(std::uint32_t mmsi, const VesselLiveness& live, bool gone, double mono);
/// The line printed once when a vessel goes silent or is heard again.
std::string change_line(const VesselLiveness::Change& c, double silent_after);
/// {"type":"vessel",...}: the same as JSON.
std::string json_change(const VesselLiveness::Change& c, double silent_after);
/// {"type":"conflict",...}: a writer other than an instance's owner (see InstanceOwners).
std::string json_conflict(const OwnerDecision& d, std::uint32_t mmsi, const char* sensor,
                          const std::string& writer, std::uint64_t seq, const std::string& state);
/// The line printed once when a roster vessel is found never heard, is heard after it was
/// reported, or a vessel not on the roster is heard.
std::string roster_line(const RosterWatch::Change& c);
/// {"type":"roster",...}: a vessel's state against the roster (`heard_age`: NaN if never heard).
std::string json_roster(std::uint32_t mmsi, RosterState state, double heard_age);

/// One fault instance as a row of the table (without the newline).
std::string fault_row_line(const Row& r, double now);

/// What the table shows besides the fleet: the roster (its vessels never heard, the vessels
/// heard that are not on it) and the rows to mark as recently changed ('*' in a first column;
/// nullptr: no such column).
struct TableExtras {
  const RosterWatch* roster = nullptr;
  const std::set<RowKey>* marked = nullptr;
};

/// The table: one row per fault instance, a line per vessel heard or on the roster (with its
/// status if given).
std::string format_table(const InstanceOwners<RowKey, Row>& rows,
                         const InstanceOwners<std::uint32_t, VesselStatus>* vessels,
                         const VesselLiveness& live, int conflicts, double now, double mono,
                         const TableExtras& extras = {});

}  // namespace usvfdi::app
