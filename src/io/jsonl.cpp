#include "usv_fdi/io/jsonl.hpp"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "usv_fdi/core/text.hpp"

namespace usvfdi::io {
namespace {

std::string array4(const Vec4& a) {
  return "[" + json_number(a(0)) + "," + json_number(a(1)) + "," + json_number(a(2)) + "," +
         json_number(a(3)) + "]";
}

const char* boolean(bool b) { return b ? "true" : "false"; }

}  // namespace

std::string json_string(const std::string& s) {
  std::string o;
  o.reserve(s.size() + 2);
  o += '"';
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      switch (c) {
        case '"':
          o += "\\\"";
          break;
        case '\\':
          o += "\\\\";
          break;
        case '\b':
          o += "\\b";
          break;
        case '\f':
          o += "\\f";
          break;
        case '\n':
          o += "\\n";
          break;
        case '\r':
          o += "\\r";
          break;
        case '\t':
          o += "\\t";
          break;
        default:
          if (c < 0x20 || c == 0x7F) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            o += buf;
          } else {
            o += static_cast<char>(c);
          }
      }
      ++i;
      continue;
    }
    unsigned cp = 0;
    const std::size_t n = utf8_sequence(s, i, &cp);
    if (n == 0) {
      o += "\\ufffd";
      ++i;
    } else {
      o.append(s, i, n);
      i += n;
    }
  }
  o += '"';
  return o;
}

std::string json_string_array(const std::string& names, const char* separator) {
  std::string out = "[";
  std::size_t start = 0;
  while (start < names.size()) {
    std::size_t end = names.find(',', start);
    if (end == std::string::npos) end = names.size();
    if (out.size() > 1) out += separator;
    out += json_string(names.substr(start, end - start));
    start = end + 1;
  }
  return out + "]";
}

std::string json_number(double x) { return json_number(x, 9); }

std::string json_number(double x, int digits) {
  if (!std::isfinite(x)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
  return buf;
}

std::string fault_event_fields(const FaultEvent& e, int digits) {
  const auto num = [digits](double x) { return json_number(x, digits); };
  return "\"sensor\":" + json_string(to_string(e.sensor)) +
         ",\"state\":" + json_string(to_string(e.state)) +
         ",\"kind\":" + json_string(to_string(e.kind)) +
         ",\"sequence\":" + std::to_string(e.sequence) +
         ",\"incarnation\":" + std::to_string(e.incarnation) + ",\"c_a\":" + num(e.c_a) +
         ",\"c_g\":" + num(e.c_g) + ",\"statistic\":" + num(e.statistic) +
         ",\"threshold\":" + num(e.threshold) + ",\"onset_time\":" + num(e.onset_time) +
         ",\"detection_time\":" + num(e.detection_time) + ",\"stamp\":" + num(e.t) + ",\"a\":[" +
         num(e.A(0, 0)) + "," + num(e.A(0, 1)) + "," + num(e.A(1, 0)) + "," + num(e.A(1, 1)) +
         "],\"message\":" + json_string(e.message);
}

void JsonlWriter::event(const FaultEvent& e) {
  out_ << "{\"type\":\"event\"," << fault_event_fields(e) << "}\n";
}

void JsonlWriter::mismatch(double t, bool active, const std::string& reason) {
  out_ << "{\"type\":\"mismatch\",\"t\":" << json_number(t) << ",\"active\":" << boolean(active)
       << ",\"reason\":" << json_string(active ? reason : "model holds again") << "}\n";
}

void JsonlWriter::signal(double t, const IsolatorStatus& iso) {
  const auto pair = [](const Vec2& x) {
    return "[" + json_number(x(0), 6) + "," + json_number(x(1), 6) + "]";
  };
  out_ << "{\"type\":\"signal\",\"t\":" << json_number(t) << ",\"armed\":" << boolean(iso.armed)
       << ",\"mismatch\":" << boolean(iso.model_mismatch) << ",\"j\":" << pair(iso.J)
       << ",\"threshold\":" << pair(iso.thresholds) << ",\"c_a\":" << json_number(iso.c_a, 6)
       << ",\"c_g\":" << json_number(iso.c_g, 6) << "}\n";
}

void JsonlWriter::estimate(double t, const Estimate& est, bool armed) {
  out_ << "{\"type\":\"estimate\",\"t\":" << json_number(t) << ",\"a\":" << array4(to_params(est.A))
       << ",\"converged\":" << boolean(est.converged)
       << ",\"excitation\":" << json_number(est.excitation) << ",\"armed\":" << boolean(armed)
       << ",\"status\":" << json_string(to_string(est.status))
       << ",\"settling\":" << json_number(est.settling)
       << ",\"uncertainty\":" << json_number(est.uncertainty)
       << ",\"std_error\":" << array4(est.std_error)
       << ",\"speed_ratio\":" << json_number(est.speed_ratio)
       << ",\"reference_speed\":" << json_number(est.reference_speed) << "}\n";
}

void JsonlWriter::summary(const RunSummary& s) {
  out_ << "{\"type\":\"summary\",\"samples\":" << s.samples << ",\"rejected\":" << s.rejected
       << ",\"duplicates\":" << s.duplicates << ",\"model_mismatches\":" << s.model_mismatches
       << ",\"events\":" << s.events << ",\"raised\":{\"accelerometer\":" << s.raised[0]
       << ",\"gyro\":" << s.raised[1] << ",\"unknown\":" << s.raised[2]
       << "},\"final_a\":" << array4(s.final_a) << ",\"converged\":" << boolean(s.converged)
       << ",\"frozen_samples\":" << s.frozen_samples << ",\"unconvergences\":" << s.unconvergences
       << ",\"duration_s\":" << json_number(s.duration_s)
       << ",\"complete\":" << boolean(s.complete);
  if (!s.complete) out_ << ",\"error\":" << json_string(s.error);
  out_ << "}\n";
}

void JsonlWriter::flush() { out_.flush(); }

}  // namespace usvfdi::io
