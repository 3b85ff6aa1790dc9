// NMEA 0183 sentence layer (include/usv_fdi/nmea/sentence.hpp).
#include "usv_fdi/nmea/sentence.hpp"

#include <cstdio>

#include "text.hpp"

namespace usvfdi::nmea {

const char* to_string(Reason reason) {
  switch (reason) {
    case Reason::kEmpty:
      return "empty";
    case Reason::kNoStart:
      return "no start character";
    case Reason::kTooLong:
      return "too long";
    case Reason::kNonPrintable:
      return "non-printable character";
    case Reason::kReservedCharacter:
      return "reserved character";
    case Reason::kNoChecksum:
      return "no checksum";
    case Reason::kBadChecksumSyntax:
      return "bad checksum syntax";
    case Reason::kChecksumMismatch:
      return "checksum mismatch";
    case Reason::kBadAddress:
      return "bad address";
    case Reason::kBadHeader:
      return "bad header";
    case Reason::kBadTagBlock:
      return "bad TAG block";
    case Reason::kWrongSentence:
      return "wrong sentence";
    case Reason::kFieldCount:
      return "wrong field count";
    case Reason::kBadField:
      return "bad field";
    case Reason::kOutOfRange:
      return "out of range";
  }
  return "unknown";
}

std::uint8_t checksum(std::string_view body) {
  std::uint8_t sum = 0;
  for (char c : body) sum ^= static_cast<std::uint8_t>(c);
  return sum;
}

namespace {

bool is_upper(char c) { return c >= 'A' && c <= 'Z'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

/// Checks the address field; fills talker, formatter and proprietary.
std::optional<Rejection> split_address(std::string_view address, Sentence* s) {
  for (char c : address) {
    if (!is_upper(c) && !is_digit(c)) {
      return reject(Reason::kBadAddress,
                    "address '" + std::string(address) + "': not A-Z or 0-9: " + quote_char(c));
    }
  }
  if (!address.empty() && address[0] == 'P') {
    if (address.size() < 4) {
      return reject(Reason::kBadAddress, "proprietary address '" + std::string(address) +
                                             "': no manufacturer mnemonic (P + 3 characters)");
    }
    s->proprietary = true;
    s->talker = "P";
    s->formatter = std::string(address.substr(1));
    return std::nullopt;
  }
  if (address.size() != 5) {
    return reject(Reason::kBadAddress, "address '" + std::string(address) +
                                           "': not a talker (2) and a sentence formatter (3)");
  }
  for (std::size_t i = 2; i < 5; ++i) {
    if (!is_upper(address[i])) {
      return reject(Reason::kBadAddress,
                    "sentence formatter '" + std::string(address.substr(2)) + "': not A-Z");
    }
  }
  s->proprietary = false;
  s->talker = std::string(address.substr(0, 2));
  s->formatter = std::string(address.substr(2));
  return std::nullopt;
}

}  // namespace

Result<Sentence> parse_sentence(std::string_view line) {
  if (line.size() >= 2 && line.substr(line.size() - 2) == "\r\n") {
    line.remove_suffix(2);
  } else if (!line.empty() && line.back() == '\n') {
    line.remove_suffix(1);
  }
  if (line.empty()) return reject(Reason::kEmpty, "empty sentence");
  if (line.size() > kMaxSentenceLength - 2) {
    return reject(Reason::kTooLong, "sentence of " + std::to_string(line.size()) +
                                        " characters without CR LF (at most " +
                                        std::to_string(kMaxSentenceLength - 2) + ")");
  }
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (!is_printable(line[i])) {
      return reject(Reason::kNonPrintable,
                    "non-printable byte " + quote_char(line[i]) + " at " + std::to_string(i + 1));
    }
  }
  if (line[0] != '$' && line[0] != '!') {
    return reject(Reason::kNoStart, "does not begin with '$' or '!': " + quote_char(line[0]));
  }
  const std::size_t star = line.find('*', 1);
  if (star == std::string_view::npos) {
    return reject(Reason::kNoChecksum, "no '*hh' checksum");
  }
  const std::string_view body = line.substr(1, star - 1);
  const std::string_view sum_text = line.substr(star + 1);
  int sum = 0;
  if (sum_text.size() != 2 || !parse_hex_byte(sum_text, &sum)) {
    return reject(Reason::kBadChecksumSyntax,
                  "checksum '" + std::string(sum_text) + "' is not two hex digits at the end");
  }
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (is_reserved(body[i])) {
      return reject(Reason::kReservedCharacter,
                    "reserved character " + quote_char(body[i]) + " at " + std::to_string(i + 2));
    }
  }
  const std::uint8_t expected = checksum(body);
  if (expected != sum) {
    return reject(Reason::kChecksumMismatch,
                  "checksum " + hex_byte(sum) + ", characters give " + hex_byte(expected));
  }
  Sentence s;
  s.start = line[0];
  const std::size_t comma = body.find(',');
  const std::string_view address = body.substr(0, comma);
  if (auto bad = split_address(address, &s)) return *bad;
  if (comma != std::string_view::npos) s.fields = split(body.substr(comma + 1), ',');
  return s;
}

Result<std::string> format_sentence(const Sentence& s) {
  if (s.start != '$' && s.start != '!') {
    return reject(Reason::kNoStart, "start must be '$' or '!', not " + quote_char(s.start));
  }
  std::string body = s.proprietary ? "P" + s.formatter : s.talker + s.formatter;
  Sentence check;
  if (auto bad = split_address(body, &check)) return *bad;
  if (check.proprietary != s.proprietary ||
      (s.proprietary && s.talker != "P" && !s.talker.empty())) {
    return reject(Reason::kBadAddress, "talker '" + s.talker + "' and proprietary disagree");
  }
  for (std::size_t i = 0; i < s.fields.size(); ++i) {
    for (char c : s.fields[i]) {
      if (!is_printable(c) || is_reserved(c) || c == ',') {
        return reject(is_printable(c) ? Reason::kReservedCharacter : Reason::kNonPrintable,
                      "field " + std::to_string(i + 1) + ": character " + quote_char(c));
      }
    }
    body += ',';
    body += s.fields[i];
  }
  std::string out;
  out.reserve(body.size() + 6);
  out += s.start;
  out += body;
  out += '*';
  out += hex_byte(checksum(body));
  out += "\r\n";
  if (out.size() > kMaxSentenceLength) {
    return reject(Reason::kTooLong, "sentence of " + std::to_string(out.size()) +
                                        " characters with CR LF (at most 82)");
  }
  return out;
}

}  // namespace usvfdi::nmea
