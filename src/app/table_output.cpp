#include "table_output.hpp"

#include <algorithm>
#include <set>
#include <vector>

namespace usvfdi::app {

namespace {
constexpr const char* kHomeAndClear = "\x1b[H\x1b[2J";
}  // namespace

std::vector<RowKey> TableOutput::diff(const InstanceOwners<RowKey, Row>& rows) {
  std::vector<RowKey> out;
  rows.for_each([&](const RowKey& key, const Row& r) {
    std::string content = fault_row_line(r, r.written);  // the age column at 0: not content
    content += r.writer;
    auto it = seen_.find(key);
    if (it != seen_.end() && it->second == content) return;
    if (it == seen_.end()) {
      seen_.emplace(key, std::move(content));
    } else {
      it->second = std::move(content);
    }
    out.push_back(key);
  });
  return out;
}

void TableOutput::emit(const std::string& text) {
  lines_ += static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  sink_(text);
}

void TableOutput::full_table(const TableInput& in, double now, double mono) {
  TableExtras extras;
  extras.roster = in.roster;
  emit(format_table(in.rows, in.vessels, in.live, in.conflicts, now, mono, extras));
  table_printed_ = true;
  rows_since_table_ = false;
}

void TableOutput::redraw(const TableInput& in, double now, double mono) {
  std::set<RowKey> marked;
  for (const auto& [key, at] : changed_at_) {
    if (mono - at < kMarkSeconds) marked.insert(key);
  }
  TableExtras extras;
  extras.roster = in.roster;
  extras.marked = &marked;
  emit(kHomeAndClear + format_table(in.rows, in.vessels, in.live, in.conflicts, now, mono, extras));
  table_printed_ = true;
  dirty_ = false;
  last_draw_ = mono;
}

void TableOutput::update(const TableInput& in, bool changed, double now, double mono) {
  if (terminal_) {
    if (!started_) {  // the first changes (the latched state arriving) are drawn together
      started_ = true;
      last_draw_ = mono;
    }
    if (changed) {
      const bool first = !table_printed_;
      for (const RowKey& k : diff(in.rows)) {
        if (!first) changed_at_[k] = mono;
      }
      dirty_ = true;
    }
    const double since = mono - last_draw_;
    if ((dirty_ && since >= 1.0 / kMaxRedrawRate) || since >= kRefreshPeriod) redraw(in, now, mono);
    return;
  }
  if (!changed) return;
  if (!table_printed_) {
    diff(in.rows);
    full_table(in, now, mono);
    return;
  }
  std::string text;
  for (const RowKey& k : diff(in.rows)) {
    const Row* r = in.rows.shown(k);
    if (r != nullptr) text += fault_row_line(*r, now) + "\n";
  }
  if (text.empty()) return;
  rows_since_table_ = true;
  emit(text);
}

void TableOutput::finish(const TableInput& in, double now, double mono) {
  if (terminal_) {
    diff(in.rows);
    redraw(in, now, mono);
    return;
  }
  if (!table_printed_ || rows_since_table_) full_table(in, now, mono);
}

double TableOutput::due_in(double mono) const {
  if (!terminal_) return 1e9;
  const double since = mono - last_draw_;
  const double wait = dirty_ ? 1.0 / kMaxRedrawRate - since : kRefreshPeriod - since;
  return std::max(0.0, wait);
}

}  // namespace usvfdi::app
