// Typed fields of a Sentence (src/nmea/fields.hpp).
#include "fields.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "text.hpp"

namespace usvfdi::nmea::fields {

std::optional<Rejection> expect(const Sentence& s, std::string_view formatter, std::size_t min,
                                std::size_t max) {
  if (s.proprietary || s.formatter != formatter) {
    return reject(Reason::kWrongSentence, "expected " + std::string(formatter) + ", got " +
                                              (s.proprietary ? "P" : s.talker) + s.formatter);
  }
  if (s.fields.size() < min || s.fields.size() > max) {
    const std::string want =
        min == max ? std::to_string(min) : std::to_string(min) + " to " + std::to_string(max);
    return reject(Reason::kFieldCount, std::string(formatter) + " with " +
                                           std::to_string(s.fields.size()) + " fields (" + want +
                                           " expected)");
  }
  return std::nullopt;
}

std::string name(std::size_t index, const char* what) {
  return "field " + std::to_string(index + 1) + " (" + what + ")";
}

namespace {

bool decimal_syntax(std::string_view t) {
  std::size_t i = 0;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  std::size_t digits = 0;
  bool dot = false;
  for (; i < t.size(); ++i) {
    if (t[i] >= '0' && t[i] <= '9') {
      ++digits;
    } else if (t[i] == '.' && !dot) {
      dot = true;
    } else {
      return false;
    }
  }
  return digits > 0;
}

}  // namespace

std::optional<Rejection> number(const Sentence& s, std::size_t index, const char* what,
                                double limit, std::optional<double>* out) {
  out->reset();
  const std::string& text = s.fields.at(index);
  if (text.empty()) return std::nullopt;
  if (!decimal_syntax(text)) {
    return reject(Reason::kBadField, name(index, what) + ": not a number: '" + text + "'");
  }
  std::string_view digits = text;
  if (digits[0] == '+') digits.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec == std::errc::result_out_of_range || !std::isfinite(v) || std::fabs(v) > limit) {
    return reject(Reason::kOutOfRange,
                  name(index, what) + ": '" + text + "' beyond +-" + format_number(limit));
  }
  if (ec != std::errc() || end != digits.data() + digits.size()) {
    return reject(Reason::kBadField, name(index, what) + ": not a number: '" + text + "'");
  }
  *out = v;
  return std::nullopt;
}

std::optional<Rejection> number_in(const Sentence& s, std::size_t index, const char* what,
                                   double lo, double hi, std::optional<double>* out) {
  if (auto bad = number(s, index, what, std::max(std::fabs(lo), std::fabs(hi)), out)) return bad;
  if (*out && (**out < lo || **out > hi)) {
    const std::string text = s.fields[index];
    out->reset();
    return reject(Reason::kOutOfRange, name(index, what) + ": '" + text + "' outside [" +
                                           format_number(lo) + ", " + format_number(hi) + "]");
  }
  return std::nullopt;
}

std::optional<Rejection> integer(const Sentence& s, std::size_t index, const char* what, long lo,
                                 long hi, std::optional<long>* out) {
  out->reset();
  const std::string& text = s.fields.at(index);
  if (text.empty()) return std::nullopt;
  std::int64_t v = 0;
  if (!parse_digits(text, &v)) {
    return reject(Reason::kBadField, name(index, what) + ": not an integer: '" + text + "'");
  }
  if (v < lo || v > hi) {
    return reject(Reason::kOutOfRange, name(index, what) + ": " + text + " outside [" +
                                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  *out = static_cast<long>(v);
  return std::nullopt;
}

std::optional<Rejection> letter(const Sentence& s, std::size_t index, const char* what,
                                std::string_view allowed, char* out) {
  *out = '\0';
  const std::string& text = s.fields.at(index);
  if (text.empty()) return std::nullopt;
  if (text.size() != 1 || allowed.find(text[0]) == std::string_view::npos) {
    return reject(Reason::kBadField,
                  name(index, what) + ": '" + text + "' is not one of " + std::string(allowed));
  }
  *out = text[0];
  return std::nullopt;
}

std::optional<Rejection> unit(const Sentence& s, std::size_t index, const char* what,
                              std::string_view unit) {
  const std::string& text = s.fields.at(index);
  if (text.empty() || text == unit) return std::nullopt;
  return reject(Reason::kBadField,
                name(index, what) + ": '" + text + "' where '" + std::string(unit) + "' belongs");
}

Sentence make_sentence(const std::string& talker, const char* formatter) {
  Sentence s;
  s.talker = talker;
  s.formatter = formatter;
  return s;
}

std::string format_number(const std::optional<double>& value) {
  if (!value) return {};
  char buf[400];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, *value, std::chars_format::fixed);
  if (ec != std::errc()) return "nan";  // not reached for the ranges the parsers accept
  return std::string(buf, end);
}

std::string format_integer(const std::optional<long>& value) {
  return value ? std::to_string(*value) : std::string();
}

std::string format_letter(char c) { return c == '\0' ? std::string() : std::string(1, c); }

}  // namespace usvfdi::nmea::fields
