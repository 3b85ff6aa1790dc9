// IEC 61162-450 datagrams and TAG blocks (include/usv_fdi/nmea/datagram.hpp).
#include "usv_fdi/nmea/datagram.hpp"

#include "text.hpp"

namespace usvfdi::nmea {

namespace {

constexpr std::int64_t kMillisecondThreshold = 10000000000;  // 1e10: 11 digits or more

Rejection bad_tag(const std::string& text) { return reject(Reason::kBadTagBlock, text); }

/// Reads one "code:value" parameter into *tag.
std::optional<Rejection> read_tag_param(std::string_view param, TagBlock* tag) {
  const std::size_t colon = param.find(':');
  if (colon != 1) {
    return bad_tag("TAG parameter '" + std::string(param) + "' is not code:value");
  }
  const char code = param[0];
  const std::string_view value = param.substr(2);
  std::int64_t number = 0;
  const auto need_number = [&](const char* what) -> std::optional<Rejection> {
    if (!parse_digits(value, &number)) {
      return bad_tag(std::string("TAG ") + code + ": (" + what + ") '" + std::string(value) +
                     "' is not a non-negative integer");
    }
    return std::nullopt;
  };
  switch (code) {
    case 's':
      tag->source = std::string(value);
      break;
    case 'd':
      tag->destination = std::string(value);
      break;
    case 't':
      tag->text = std::string(value);
      break;
    case 'n':
      if (auto bad = need_number("line count")) return bad;
      tag->line_count = number;
      break;
    case 'r':
      if (auto bad = need_number("relative time")) return bad;
      tag->relative_time = number;
      break;
    case 'c':
      if (auto bad = need_number("UNIX time")) return bad;
      if (number >= kMillisecondThreshold) {
        tag->unix_time_ms = number;
      } else {
        tag->unix_time_ms = number * 1000;
      }
      break;
    case 'g': {
      const auto parts = split(value, '-');
      TagGroup g;
      if (parts.size() != 3 || !parse_digits(parts[0], &g.number) ||
          !parse_digits(parts[1], &g.total) || !parse_digits(parts[2], &g.id)) {
        return bad_tag("TAG g: (grouping) '" + std::string(value) + "' is not number-total-id");
      }
      tag->group = g;
      break;
    }
    default:
      break;  // unknown codes are skipped
  }
  return std::nullopt;
}

}  // namespace

Result<TagBlock> parse_tag_block(std::string_view block) {
  if (block.size() > kMaxTagBlockLength) {
    return reject(Reason::kTooLong, "TAG block of " + std::to_string(block.size()) +
                                        " characters (at most " +
                                        std::to_string(kMaxTagBlockLength) + ")");
  }
  for (char c : block) {
    if (!is_printable(c)) return bad_tag("TAG block: non-printable byte " + quote_char(c));
    if (is_reserved(c) && c != '*')
      return bad_tag("TAG block: reserved character " + quote_char(c));
  }
  const std::size_t star = block.find('*');
  if (star == std::string_view::npos) return bad_tag("TAG block without '*hh' checksum");
  const std::string_view params = block.substr(0, star);
  int sum = 0;
  if (!parse_hex_byte(block.substr(star + 1), &sum)) {
    return bad_tag("TAG block checksum '" + std::string(block.substr(star + 1)) +
                   "' is not two hex digits");
  }
  if (checksum(params) != sum) {
    return bad_tag("TAG block checksum " + hex_byte(sum) + ", characters give " +
                   hex_byte(checksum(params)));
  }
  TagBlock tag;
  if (params.empty()) return tag;
  for (const auto& param : split(params, ',')) {
    if (auto bad = read_tag_param(param, &tag)) return *bad;
  }
  return tag;
}

Result<TaggedSentence> parse_tagged_sentence(std::string_view line) {
  TaggedSentence out;
  while (!line.empty() && line[0] == '\\') {
    const std::size_t close = line.find('\\', 1);
    if (close == std::string_view::npos) return bad_tag("TAG block without closing '\\'");
    auto tag = parse_tag_block(line.substr(1, close - 1));
    if (!tag) return tag.rejection();
    if (!out.tag) out.tag = TagBlock{};
    const TagBlock& t = tag.value();
    TagBlock& merged = *out.tag;
    if (t.source) merged.source = t.source;
    if (t.destination) merged.destination = t.destination;
    if (t.line_count) merged.line_count = t.line_count;
    if (t.unix_time_ms) merged.unix_time_ms = t.unix_time_ms;
    if (t.group) merged.group = t.group;
    if (t.relative_time) merged.relative_time = t.relative_time;
    if (t.text) merged.text = t.text;
    line.remove_prefix(close + 1);
  }
  auto sentence = parse_sentence(line);
  if (!sentence) return sentence.rejection();
  out.sentence = std::move(sentence.value());
  return out;
}

Result<Datagram> parse_datagram(std::string_view bytes) {
  if (bytes.empty()) return reject(Reason::kEmpty, "empty datagram");
  if (bytes.size() > kMaxDatagramLength) {
    return reject(Reason::kTooLong, "datagram of " + std::to_string(bytes.size()) +
                                        " bytes (at most " + std::to_string(kMaxDatagramLength) +
                                        ")");
  }
  Datagram d;
  if (bytes.substr(0, kIec450Header.size()) == kIec450Header) {
    d.iec450 = true;
    bytes.remove_prefix(kIec450Header.size());
  } else if (bytes[0] != '$' && bytes[0] != '!' && bytes[0] != '\\' && bytes[0] != '\r' &&
             bytes[0] != '\n') {
    std::string shown;
    for (std::size_t i = 0; i < bytes.size() && i < 6; ++i) {
      shown += is_printable(bytes[i]) ? std::string(1, bytes[i])
                                      : "\\x" + hex_byte(static_cast<unsigned char>(bytes[i]));
    }
    return reject(Reason::kBadHeader, "datagram begins with '" + shown +
                                          "': neither \"UdPbC\\0\" nor a sentence or TAG block");
  }
  std::size_t start = 0;
  while (start < bytes.size()) {
    std::size_t end = bytes.find('\n', start);
    if (end == std::string_view::npos) end = bytes.size();
    std::string_view line = bytes.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!line.empty()) d.lines.push_back(parse_tagged_sentence(line));
    start = end + 1;
  }
  if (d.lines.empty()) return reject(Reason::kEmpty, "datagram without a sentence");
  return d;
}

namespace {

bool tag_value_ok(const std::string& v) {
  for (char c : v) {
    if (!is_printable(c) || is_reserved(c) || c == ',') return false;
  }
  return true;
}

}  // namespace

Result<std::string> format_tag_block(const TagBlock& tag) {
  std::string params;
  const auto add = [&params](char code, const std::string& value) {
    if (!params.empty()) params += ',';
    params += code;
    params += ':';
    params += value;
  };
  const auto add_text = [&](char code, const std::optional<std::string>& v) -> bool {
    if (!v) return true;
    if (!tag_value_ok(*v)) return false;
    add(code, *v);
    return true;
  };
  const auto add_number = [&](char code, const std::optional<std::int64_t>& v) -> bool {
    if (!v) return true;
    if (*v < 0) return false;
    add(code, std::to_string(*v));
    return true;
  };
  if (!add_text('s', tag.source) || !add_text('d', tag.destination)) {
    return bad_tag("TAG s: or d: with a reserved, non-printable or ',' character");
  }
  if (!add_number('n', tag.line_count)) return bad_tag("TAG n: negative");
  if (tag.unix_time_ms) {
    const std::int64_t ms = *tag.unix_time_ms;
    // Whole seconds below the threshold are written in seconds; the rest in milliseconds,
    // which read back as milliseconds only from the threshold on.
    const bool seconds = ms % 1000 == 0 && ms / 1000 < kMillisecondThreshold;
    if (ms < 0 || (!seconds && ms < kMillisecondThreshold)) {
      return bad_tag("TAG c: " + std::to_string(ms) +
                     " ms is negative, or a fraction of a second before 1970-04-26");
    }
    add('c', seconds ? std::to_string(ms / 1000) : std::to_string(ms));
  }
  if (tag.group) {
    const TagGroup& g = *tag.group;
    if (g.number < 0 || g.total < 0 || g.id < 0) return bad_tag("TAG g: negative");
    add('g', std::to_string(g.number) + "-" + std::to_string(g.total) + "-" + std::to_string(g.id));
  }
  if (!add_number('r', tag.relative_time)) return bad_tag("TAG r: negative");
  if (!add_text('t', tag.text)) {
    return bad_tag("TAG t: with a reserved, non-printable or ',' character");
  }
  std::string block = params + "*" + hex_byte(checksum(params));
  if (block.size() > kMaxTagBlockLength) {
    return reject(Reason::kTooLong, "TAG block of " + std::to_string(block.size()) +
                                        " characters (at most " +
                                        std::to_string(kMaxTagBlockLength) + ")");
  }
  return "\\" + block + "\\";
}

Result<std::string> format_iec450_datagram(const TagBlock& tag,
                                           const std::vector<std::string>& sentences) {
  auto block = format_tag_block(tag);
  if (!block) return block.rejection();
  std::string out(kIec450Header);
  out += block.value();
  for (const auto& s : sentences) out += s;
  if (out.size() > kMaxDatagramLength) {
    return reject(Reason::kTooLong, "datagram of " + std::to_string(out.size()) + " bytes");
  }
  return out;
}

}  // namespace usvfdi::nmea
