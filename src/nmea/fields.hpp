// Reading and writing typed fields of a Sentence (internal to src/nmea).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "usv_fdi/nmea/result.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea::fields {

/// Refuses a proprietary sentence, another formatter, or a field count outside [min, max].
std::optional<Rejection> expect(const Sentence& s, std::string_view formatter, std::size_t min,
                                std::size_t max);

/// "field 3 (rate of turn)" for messages (index is 0-based, fields count from 1).
std::string name(std::size_t index, const char* what);

/// A decimal number [+-]digits[.digits] (no exponent, no inf/nan); empty -> nullopt. Refused:
/// another syntax (kBadField), a value beyond +-limit (kOutOfRange).
std::optional<Rejection> number(const Sentence& s, std::size_t index, const char* what,
                                double limit, std::optional<double>* out);

/// As number(), and the value must lie in [lo, hi].
std::optional<Rejection> number_in(const Sentence& s, std::size_t index, const char* what,
                                   double lo, double hi, std::optional<double>* out);

/// An unsigned integer (digits only) in [lo, hi]; empty -> nullopt.
std::optional<Rejection> integer(const Sentence& s, std::size_t index, const char* what, long lo,
                                 long hi, std::optional<long>* out);

/// One letter out of `allowed`; empty -> '\0'.
std::optional<Rejection> letter(const Sentence& s, std::size_t index, const char* what,
                                std::string_view allowed, char* out);

/// The field must be empty or equal to `unit` (e.g. "T" after a true heading).
std::optional<Rejection> unit(const Sentence& s, std::size_t index, const char* what,
                              std::string_view unit);

/// An empty sentence of this talker and formatter (for to_sentence).
Sentence make_sentence(const std::string& talker, const char* formatter);

/// Shortest decimal text that reads back to the same double (fixed notation, no exponent).
std::string format_number(const std::optional<double>& value);
/// Decimal digits of an integer, or empty.
std::string format_integer(const std::optional<long>& value);
/// The letter, or empty for '\0'.
std::string format_letter(char c);
/// The letter of a char-valued enum (Status, modes), or empty for '\0'.
template <class Enum>
std::string format_letter(Enum e) {
  return format_letter(static_cast<char>(e));
}

}  // namespace usvfdi::nmea::fields

namespace usvfdi::nmea::fields {

/// to_sentence(x), formatted, and refused where `parse` refuses the sentence or reads another
/// value from it (a field that does not fit its text, e.g. an hour of 123): a formatter never
/// writes what its parser would reject or read differently.
template <class T, class Parse>
Result<std::string> format_checked(const T& x, Parse parse) {
  const Sentence s = to_sentence(x);
  auto text = format_sentence(s);
  if (!text) return text.rejection();
  const auto back = parse(s);
  if (!back) return back.rejection();
  if (!(back.value() == x)) {
    return reject(Reason::kOutOfRange, s.formatter + ": a value does not fit its field: " +
                                           text.value().substr(0, text.value().size() - 2));
  }
  return text;
}

}  // namespace usvfdi::nmea::fields
