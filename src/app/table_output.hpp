// How the monitor's table reaches stdout (issue 14, item 5). On a terminal the table is one
// screen redrawn in place (cursor home, clear, table), at most kMaxRedrawRate times a second
// (changes in between are coalesced, the first ones too: the latched state arrives as a burst)
// and once a second for the ages, with the rows changed since the first draw marked '*' for
// kMarkSeconds. Elsewhere (a pipe, a file, a test) the first change prints
// the full table, every later change only the rows that changed (one line each), and the end
// the full table again: the lines printed grow with the number of changes, not with the number
// of changes times the size of the fleet. Pure logic on caller-supplied clocks; the output goes
// to a sink, so that it can be counted.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>

#include "monitor_format.hpp"

namespace usvfdi::app {

/// What the table shows (see format_table()).
struct TableInput {
  const InstanceOwners<RowKey, Row>& rows;
  const InstanceOwners<std::uint32_t, VesselStatus>* vessels;
  const VesselLiveness& live;
  int conflicts;
  const RosterWatch* roster;
};

class TableOutput {
 public:
  static constexpr double kMaxRedrawRate = 5.0;  ///< terminal: redraws per second, at most
  static constexpr double kRefreshPeriod = 1.0;  ///< terminal: redraw this often for the ages [s]
  static constexpr double kMarkSeconds = 3.0;    ///< terminal: a changed row is marked this long

  using Sink = std::function<void(const std::string&)>;

  /// `terminal`: redraw in place (ANSI); else print the changed rows only.
  TableOutput(bool terminal, Sink sink) : terminal_(terminal), sink_(std::move(sink)) {}

  /// One turn of the monitor's loop; `changed`: the view changed since the last turn. Prints
  /// what the mode says (possibly nothing). `now`: wall-clock s, `mono`: monotonic s.
  void update(const TableInput& in, bool changed, double now, double mono);
  /// The end: the full table (a final redraw on a terminal), unless it is already up to date.
  void finish(const TableInput& in, double now, double mono);

  /// Seconds until update() would redraw a terminal with nothing new (for the loop's wait);
  /// a large number when not on a terminal.
  double due_in(double mono) const;
  /// Lines written so far.
  std::size_t lines() const { return lines_; }

 private:
  /// The keys of the rows that are new or changed since the last call (all of them the first
  /// time), recording their current content. A row's content excludes its age.
  std::vector<RowKey> diff(const InstanceOwners<RowKey, Row>& rows);
  void emit(const std::string& text);
  void full_table(const TableInput& in, double now, double mono);
  void redraw(const TableInput& in, double now, double mono);

  bool terminal_;
  Sink sink_;
  std::map<RowKey, std::string> seen_;   ///< each row's content when last printed
  std::map<RowKey, double> changed_at_;  ///< terminal: when each row last changed [mono s]
  bool table_printed_ = false;           ///< a full table has been printed
  bool rows_since_table_ = false;        ///< changed rows printed since the last full table
  bool dirty_ = false;                   ///< terminal: a change not drawn yet
  bool started_ = false;                 ///< terminal: update() has been called
  double last_draw_ = 0.0;               ///< terminal: the last redraw [mono s]
  std::size_t lines_ = 0;
};

}  // namespace usvfdi::app
