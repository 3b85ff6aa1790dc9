// Markdown and JSON outputs of the detection benchmark.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <tuple>

#include "runner.hpp"

namespace usvfdi::bench {

namespace {

std::string fmt(const char* f, double x) {
  if (!std::isfinite(x)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

std::string pct(int a, int b) {
  if (b == 0) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%d/%d (%.0f %%)", a, b, 100.0 * a / b);
  return buf;
}

std::string json_num(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string json_str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

/// One method's aggregate over a table, as a JSON object.
void write_method_summary(std::ostream& o, const MethodSummary& m) {
  o << "{\"faults\": " << m.faults << ", \"detected\": " << m.detected
    << ", \"isolated\": " << m.isolated << ", \"armed_at_onset\": " << m.armed_at_onset
    << ", \"detected_when_armed\": " << m.detected_armed << ", \"recovered\": " << m.recovered
    << ", \"held\": " << m.held << ", \"false_alarms\": " << m.false_alarms
    << ", \"healthy_hours\": " << json_num(m.healthy_hours)
    << ", \"healthy_armed_hours\": " << json_num(m.healthy_armed_hours)
    << ", \"false_alarms_per_hour\": " << json_num(m.fa_per_hour())
    << ", \"false_alarms_armed\": " << m.false_alarms_armed
    << ", \"false_alarms_per_armed_hour\": " << json_num(m.fa_per_armed_hour())
    << ", \"delay_median\": " << json_num(m.delay_median)
    << ", \"delay_p95\": " << json_num(m.delay_p95)
    << ", \"recovery_median\": " << json_num(m.recovery_median)
    << ", \"recovery_p95\": " << json_num(m.recovery_p95) << ", \"runs\": " << m.runs
    << ", \"armed_runs\": " << m.armed_runs << ", \"arming_median\": " << json_num(m.arming_median)
    << ", \"arming_max\": " << json_num(m.arming_max)
    << ", \"a_error_median\": " << json_num(m.a_error_median)
    << ", \"a_error_p95\": " << json_num(m.a_error_p95)
    << ", \"healthy_run_hours\": " << json_num(m.healthy_run_hours)
    << ", \"healthy_run_mismatches\": " << m.healthy_run_mismatches
    << ", \"healthy_run_frozen_share\": " << json_num(m.frozen_share()) << ", \"per_kind\": {";
  for (std::size_t i = 0; i < standard_kinds().size(); ++i) {
    o << (i ? ", " : "") << json_str(to_string(standard_kinds()[i])) << ": [" << m.per_kind[i][0]
      << ", " << m.per_kind[i][1] << ", " << m.per_kind[i][2] << "]";
  }
  o << "}}";
}

/// One table (its name, note, size and every method's aggregate), as a JSON object.
void write_table(std::ostream& o, const TableSummary& t) {
  o << "{\"name\": " << json_str(t.name) << ", \"note\": " << json_str(t.note)
    << ", \"runs\": " << t.runs << ", \"hours\": " << json_num(t.hours) << ", \"methods\": {";
  for (int k = 0; k < kMethods; ++k) {
    o << (k ? ", " : "") << json_str(method_name(k)) << ": ";
    write_method_summary(o, t.m[k]);
  }
  o << "}}";
}

/// One method's result on the run of case c, as a JSON object.
void write_method_result(std::ostream& o, const Case& c, const MethodResult& m) {
  const double ref = c.A_ref.norm();
  o << "{\"t_armed\": " << json_num(m.t_armed) << ", \"live\": [";
  for (std::size_t j = 0; j < m.live.size(); ++j) {
    o << (j ? ", " : "") << "[" << json_num(m.live[j].from) << ", " << json_num(m.live[j].to)
      << "]";
  }
  o << "], \"unarms\": " << m.unarms << ", \"converged\": " << (m.converged ? "true" : "false")
    << ", \"a_error\": " << json_num(ref > 0 ? (m.A_final - c.A_ref).norm() / ref : kNaN)
    << ", \"A_final\": [" << json_num(m.A_final(0, 0)) << ", " << json_num(m.A_final(0, 1)) << ", "
    << json_num(m.A_final(1, 0)) << ", " << json_num(m.A_final(1, 1)) << "]"
    << ", \"healthy_s\": " << json_num(m.score.healthy_time) << ", \"frozen_samples\": "
    << (m.has_identification ? std::to_string(m.frozen_samples) : "null")
    << ", \"mismatches\": " << m.mismatches.size() << ", \"false_alarms\": [";
  for (std::size_t j = 0; j < m.score.false_alarm_events.size(); ++j) {
    const Alarm& a = m.score.false_alarm_events[j];
    o << (j ? ", " : "") << "[" << json_num(a.t) << ", " << json_str(to_string(a.sensor)) << ", "
      << json_str(to_string(a.kind)) << ", " << json_num(m.score.false_alarm_durations[j]) << "]";
  }
  o << "]";
  for (const FaultScore& f : m.score.faults) {
    o << ", \"detected\": " << (f.detected ? "true" : "false")
      << ", \"isolated\": " << (f.isolated ? "true" : "false")
      << ", \"raised_sensor\": " << json_str(f.detected ? to_string(f.raised_sensor) : "")
      << ", \"delay\": " << json_num(f.delay)
      << ", \"recovery_delay\": " << json_num(f.recovery_delay)
      << ", \"held\": " << (f.held ? "true" : "false") << ", \"shown\": " << json_num(f.shown);
  }
  o << "}";
}

/// One run (its case, its data span, the fault put in and every method's result), as a JSON
/// object.
void write_run(std::ostream& o, const Case& c, const CaseResult& r) {
  o << "{\"table\": " << json_str(c.table) << ", \"voyage\": " << json_str(c.voyage)
    << ", \"rate_hz\": " << json_num(c.rate_hz) << ", \"seed\": " << c.seed
    << ", \"samples\": " << r.samples << ", \"t_first\": " << json_num(r.t_first)
    << ", \"t_last\": " << json_num(r.t_last);
  if (c.faulty) {
    o << ", \"fault\": {\"sensor\": " << json_str(to_string(c.fault.sensor))
      << ", \"kind\": " << json_str(to_string(c.fault.kind))
      << ", \"t_start\": " << json_num(c.fault.t_start)
      << ", \"t_end\": " << json_num(c.fault.t_end) << ", \"magnitude\": " << json_num(c.magnitude)
      << "}";
  }
  o << ", \"methods\": {";
  for (int k = 0; k < kMethods; ++k) {
    o << (k ? ", " : "") << json_str(method_name(k)) << ": ";
    write_method_result(o, c, r.m[k]);
  }
  o << "}}";
}

}  // namespace

std::string to_overview(const std::vector<TableSummary>& tables) {
  std::ostringstream o;
  o << "| subject @ rate | healthy h | faults |";
  for (int k = 0; k < kMethods; ++k) {
    o << " " << method_name(k) << ": detected / isolated | false alarms per h | median delay [s] |";
  }
  o << "\n|---|---|---|";
  for (int k = 0; k < kMethods; ++k) o << "---|---|---|";
  o << "\n";
  for (const TableSummary& t : tables) {
    o << "| " << t.name << " | " << fmt("%.1f", t.m[kOracle].healthy_hours) << " | "
      << t.m[kOracle].faults << " |";
    for (int k = 0; k < kMethods; ++k) {
      const MethodSummary& m = t.m[k];
      if (m.faults > 0) {
        o << " " << fmt("%.0f %%", 100.0 * m.detected / m.faults) << " / "
          << fmt("%.0f %%", 100.0 * m.isolated / m.faults) << " |";
      } else {
        o << " – |";
      }
      o << " " << fmt("%.2f", m.fa_per_hour()) << " | " << fmt("%.2f", m.delay_median) << " |";
    }
    o << "\n";
  }
  return o.str();
}

std::string data_class(const Case& c) {
  if (c.voyage == "course/calm") return "calm";
  if (c.voyage == "voyage/sea3/mems") return "sea 3, MEMS";
  if (c.subject.find("hsva") != std::string::npos) return "HSVA recorded";
  return c.voyage;
}

std::vector<BreakdownRow> breakdown(const std::vector<Case>& cases,
                                    const std::vector<CaseResult>& results) {
  std::vector<BreakdownRow> rows;
  const auto& kinds = standard_kinds();
  auto row_of = [&rows](const std::string& data, Sensor sensor, FaultKind kind) -> BreakdownRow& {
    for (BreakdownRow& r : rows) {
      if (r.data == data && r.sensor == sensor && r.kind == kind) return r;
    }
    rows.push_back(BreakdownRow{});
    rows.back().data = data;
    rows.back().sensor = sensor;
    rows.back().kind = kind;
    return rows.back();
  };
  for (const CaseResult& r : results) {
    const Case& c = cases.at(r.index);
    const std::string data = data_class(c);
    // Every method scores the same faults; count them once, from the engine's scores.
    for (std::size_t i = 0; i < r.m[kEngine].score.faults.size(); ++i) {
      const InjectedFault& f = r.m[kEngine].score.faults[i].fault;
      if (std::find(kinds.begin(), kinds.end(), f.kind) == kinds.end()) continue;
      BreakdownRow& row = row_of(data, f.sensor, f.kind);
      ++row.faults;
      for (int k = 0; k < kMethods; ++k) {
        if (i >= r.m[k].score.faults.size()) continue;
        const FaultScore& s = r.m[k].score.faults[i];
        if (!s.detected) continue;
        ++row.m[k][0];
        if (s.isolated) ++row.m[k][1];
        if (s.delay <= BreakdownRow::kEarly) ++row.m[k][2];
        if (s.held) ++row.m[k][3];
      }
    }
  }
  // Data classes in the order first seen; within one, by sensor, then in table order of kinds.
  std::vector<std::string> order;
  for (const BreakdownRow& r : rows) {
    if (std::find(order.begin(), order.end(), r.data) == order.end()) order.push_back(r.data);
  }
  auto rank = [&](const BreakdownRow& r) {
    const auto d = std::find(order.begin(), order.end(), r.data) - order.begin();
    const auto k = std::find(kinds.begin(), kinds.end(), r.kind) - kinds.begin();
    return std::make_tuple(d, static_cast<int>(r.sensor), k);
  };
  std::stable_sort(rows.begin(), rows.end(),
                   [&](const BreakdownRow& a, const BreakdownRow& b) { return rank(a) < rank(b); });
  return rows;
}

namespace {

/// Where the faults are missed: a row per data class, sensor and kind.
std::string to_breakdown(const std::vector<BreakdownRow>& rows) {
  std::ostringstream o;
  o << "Where the faults are found and missed, over every table (detected / isolated / "
       "detected within "
    << fmt("%.0f", BreakdownRow::kEarly)
    << " s of the onset / raised on the faulty sensor until the fault's end, of the "
       "faults):\n\n";
  o << "| data | sensor | kind | faults |";
  for (int k = 0; k < kMethods; ++k) o << " " << method_name(k) << " |";
  o << "\n|---|---|---|---|";
  for (int k = 0; k < kMethods; ++k) o << "---|";
  o << "\n";
  for (const BreakdownRow& r : rows) {
    o << "| " << r.data << " | " << to_string(r.sensor) << " | " << to_string(r.kind) << " | "
      << r.faults << " |";
    for (int k = 0; k < kMethods; ++k) {
      o << " " << r.m[k][0] << " / " << r.m[k][1] << " / " << r.m[k][2] << " / " << r.m[k][3]
        << " |";
    }
    o << "\n";
  }
  return o.str();
}

}  // namespace

std::string to_markdown(const std::vector<TableSummary>& tables, const std::string& header,
                        const std::vector<BreakdownRow>& rows) {
  std::ostringstream o;
  if (!header.empty()) o << header << "\n\n";
  o << to_overview(tables) << "\n";
  if (!rows.empty()) o << to_breakdown(rows) << "\n";
  for (const TableSummary& t : tables) {
    o << "#### " << t.name << " (" << t.runs << " runs, " << fmt("%.1f", t.hours)
      << " h of data)\n\n";
    if (!t.note.empty()) o << t.note << ".\n\n";
    o << "| method | detected | isolated | detected when armed at onset | false alarms "
         "(healthy h) | per healthy h | per armed healthy h (h) | delay median / p95 [s] | "
         "raised until the end | recovery median / p95 [s] "
         "(cleared) | armed (runs) | arming median / max [s] | Â error median / p95 |\n";
    o << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (int k = 0; k < kMethods; ++k) {
      const MethodSummary& m = t.m[k];
      o << "| " << method_name(k) << " | " << pct(m.detected, m.faults) << " | "
        << pct(m.isolated, m.faults) << " | " << pct(m.detected_armed, m.armed_at_onset) << " | "
        << m.false_alarms << " (" << fmt("%.1f", m.healthy_hours) << ") | "
        << fmt("%.2f", m.fa_per_hour()) << " | " << fmt("%.2f", m.fa_per_armed_hour()) << " ("
        << fmt("%.1f", m.healthy_armed_hours) << ") | " << fmt("%.2f", m.delay_median) << " / "
        << fmt("%.2f", m.delay_p95) << " | " << pct(m.held, m.faults) << " | "
        << fmt("%.1f", m.recovery_median) << " / " << fmt("%.1f", m.recovery_p95) << " ("
        << m.recovered << "/" << m.detected << ") | " << m.armed_runs << "/" << m.runs << " | "
        << fmt("%.0f", m.arming_median) << " / " << fmt("%.0f", m.arming_max) << " | "
        << fmt("%.3f", m.a_error_median) << " / " << fmt("%.3f", m.a_error_p95) << " |\n";
    }
    if (t.m[kEngine].healthy_run_hours > 0) {
      o << "\nOn the healthy runs (" << fmt("%.1f", t.m[kEngine].healthy_run_hours)
        << " h): model-mismatch verdicts per hour";
      for (int k = 0; k < kMethods; ++k) {
        o << (k ? ", " : " ") << method_name(k) << " " << fmt("%.2f", t.m[k].mismatches_per_hour())
          << " (" << t.m[k].healthy_run_mismatches << ")";
      }
      o << "; identification frozen on";
      bool first = true;
      for (int k = 0; k < kMethods; ++k) {
        if (!t.m[k].has_identification) continue;
        o << (first ? " " : " / ") << fmt("%.1f %%", 100.0 * t.m[k].frozen_share()) << " ("
          << method_name(k) << ")";
        first = false;
      }
      o << " of the samples.\n";
    }
    bool any = false;
    for (const MethodSummary& m : t.m) any = any || m.faults > 0;
    if (any) {
      o << "\n| detected / isolated by kind |";
      for (FaultKind k : standard_kinds()) o << " " << to_string(k) << " |";
      o << "\n|---|";
      for (std::size_t i = 0; i < standard_kinds().size(); ++i) o << "---|";
      o << "\n";
      for (int k = 0; k < kMethods; ++k) {
        o << "| " << method_name(k) << " |";
        for (const auto& pk : t.m[k].per_kind) {
          o << " " << pk[1] << " / " << pk[2] << " of " << pk[0] << " |";
        }
        o << "\n";
      }
    }
    o << "\n";
  }
  return o.str();
}

std::string to_json(const std::vector<Case>& cases, const std::vector<CaseResult>& results,
                    const std::vector<TableSummary>& tables, const std::string& header) {
  std::ostringstream o;
  o << "{\n  \"header\": " << json_str(header) << ",\n  \"tables\": [\n";
  for (std::size_t ti = 0; ti < tables.size(); ++ti) {
    o << "    ";
    write_table(o, tables[ti]);
    o << (ti + 1 < tables.size() ? "," : "") << "\n";
  }
  o << "  ],\n  \"runs\": [\n";
  for (std::size_t i = 0; i < results.size(); ++i) {
    o << "    ";
    write_run(o, cases[results[i].index], results[i]);
    o << (i + 1 < results.size() ? "," : "") << "\n";
  }
  o << "  ]\n}\n";
  return o.str();
}

}  // namespace usvfdi::bench
