// Character and field helpers (src/nmea/text.hpp).
#include "text.hpp"

namespace usvfdi::nmea {

std::string quote_char(char c) {
  if (is_printable(c)) return std::string("'") + c + "'";
  return "0x" + hex_byte(static_cast<unsigned char>(c));
}

std::string hex_byte(int value) {
  static const char kDigits[] = "0123456789ABCDEF";
  std::string out(2, '0');
  out[0] = kDigits[(value >> 4) & 0xF];
  out[1] = kDigits[value & 0xF];
  return out;
}

namespace {
int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}
}  // namespace

bool parse_hex_byte(std::string_view text, int* value) {
  if (text.size() != 2) return false;
  const int hi = hex_digit(text[0]);
  const int lo = hex_digit(text[1]);
  if (hi < 0 || lo < 0) return false;
  *value = hi * 16 + lo;
  return true;
}

bool parse_digits(std::string_view text, std::int64_t* value) {
  if (text.empty() || text.size() > 18) return false;
  std::int64_t v = 0;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  *value = v;
  return true;
}

std::vector<std::string> split(std::string_view text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(separator, start);
    if (end == std::string_view::npos) {
      parts.emplace_back(text.substr(start));
      return parts;
    }
    parts.emplace_back(text.substr(start, end - start));
    start = end + 1;
  }
}

}  // namespace usvfdi::nmea
