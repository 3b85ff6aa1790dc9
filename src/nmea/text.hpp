// Character and field helpers shared by the sentence, datagram and typed parsers (internal).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace usvfdi::nmea {

/// Printable ASCII 0x20..0x7E.
inline bool is_printable(char c) { return c >= 0x20 && c <= 0x7E; }
/// Reserved by NMEA 0183 inside the fields: '$', '!', '*', '\', '~'.
inline bool is_reserved(char c) {
  return c == '$' || c == '!' || c == '*' || c == '\\' || c == '~';
}
/// "'x'" for a printable character, "0x1F" otherwise.
std::string quote_char(char c);
/// Two upper-case hex digits.
std::string hex_byte(int value);
/// Two hex digits (either case) -> 0..255; false otherwise.
bool parse_hex_byte(std::string_view text, int* value);
/// Digits only (1..18 of them) -> a non-negative integer; false otherwise.
bool parse_digits(std::string_view text, std::int64_t* value);
/// Splits at every separator (n separators give n + 1 parts).
std::vector<std::string> split(std::string_view text, char separator);

}  // namespace usvfdi::nmea
