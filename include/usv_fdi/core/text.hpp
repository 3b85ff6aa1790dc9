// One escaping function for every string a peer supplies (an operator id, a fault message, an
// identity's name, a partition): before it reaches a log line, a table, JSON or the state journal,
// nothing in it may end a line, move the cursor or talk to the terminal. Header-only, no
// dependency.
#pragma once

#include <cstdio>
#include <ctime>
#include <string>
#include <string_view>

namespace usvfdi {

/// The length of the valid UTF-8 sequence at s[i] (1 for ASCII), its code point in *cp; 0 when
/// it is not valid UTF-8: a stray continuation byte, a sequence cut short, an overlong form, a
/// surrogate, or a value past U+10FFFF.
inline std::size_t utf8_sequence(std::string_view s, std::size_t i, unsigned* cp) {
  const unsigned char c = static_cast<unsigned char>(s[i]);
  std::size_t n = 0;
  unsigned v = 0;
  if (c < 0x80) {
    n = 1;
    v = c;
  } else if (c >= 0xc2 && c <= 0xdf) {
    n = 2;
    v = c & 0x1fu;
  } else if (c >= 0xe0 && c <= 0xef) {
    n = 3;
    v = c & 0x0fu;
  } else if (c >= 0xf0 && c <= 0xf4) {
    n = 4;
    v = c & 0x07u;
  } else {
    return 0;
  }
  if (i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    const unsigned char cc = static_cast<unsigned char>(s[i + k]);
    if ((cc & 0xc0u) != 0x80u) return 0;
    v = (v << 6) | (cc & 0x3fu);
  }
  if ((n == 3 && v < 0x800) || (n == 4 && (v < 0x10000 || v > 0x10ffff))) return 0;
  if (v >= 0xd800 && v <= 0xdfff) return 0;  // surrogates are not characters
  *cp = v;
  return n;
}

/// `s` with every byte that is not printable text replaced by a visible escape: newline -> "\n",
/// CR -> "\r", tab -> "\t", any other C0 control or DEL -> "\xHH"; in
/// UTF-8, the C1 controls (U+0080..U+009F) and the bidirectional overrides and isolates
/// (U+202A..U+202E, U+2066..U+2069) -> "\u{XXXX}"; a byte that is not part of valid UTF-8 ->
/// "\xHH". Printable ASCII (the backslash too) and other valid UTF-8 pass unchanged, so plain text
/// is unchanged and escaping is idempotent: a text escaped by the sidecar and again by the monitor
/// reads the same. (The price: a peer's literal "\n" looks like an escaped newline; it still
/// cannot end a line.)
inline std::string escape_text(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  const auto hex = [&out](unsigned v, const char* fmt) {
    char buf[16];
    std::snprintf(buf, sizeof buf, fmt, v);
    out += buf;
  };
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      switch (c) {
        case '\n':
          out += "\\n";
          break;
        case '\r':
          out += "\\r";
          break;
        case '\t':
          out += "\\t";
          break;
        default:
          if (c < 0x20 || c == 0x7f) {
            hex(c, "\\x%02x");
          } else {
            out += static_cast<char>(c);
          }
      }
      ++i;
      continue;
    }
    unsigned cp = 0;
    const std::size_t n = utf8_sequence(s, i, &cp);
    if (n == 0) {
      hex(c, "\\x%02x");
      ++i;
      continue;
    }
    if ((cp >= 0x80 && cp <= 0x9f) || (cp >= 0x202a && cp <= 0x202e) ||
        (cp >= 0x2066 && cp <= 0x2069)) {
      hex(cp, "\\u{%04x}");
    } else {
      out.append(s.data() + i, n);
    }
    i += n;
  }
  return out;
}

/// A Unix time [s] as UTC, ISO 8601 to the second ("2026-12-01T23:52:26Z").
inline std::string utc_text(double unix_s) {
  const std::time_t t = static_cast<std::time_t>(unix_s);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace usvfdi
