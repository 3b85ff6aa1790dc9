// IEC 61162-450 datagrams and NMEA 0183 TAG blocks (also plain NMEA 0183 over UDP).
//
// An IEC 61162-450 datagram (the "UdPbC" message type) is
//   'U' 'd' 'P' 'b' 'C' NUL, then lines, each: zero or more TAG blocks, one sentence, CR LF.
// A datagram without the header is read as plain NMEA 0183 over UDP: lines (CR LF or LF, the
// last may lack it), each optionally with TAG blocks. Other IEC 61162-450 headers ("RaUdP",
// "RrUdP", ... binary file transfer) are refused with kBadHeader.
//
// A TAG block (NMEA 0183 v4.x, IEC 61162-1 ed. 5) is  '\' param,param,...*hh '\'  where the
// checksum is the XOR of the characters between the opening '\' and '*', and every param is
// code:value. Codes read here:
//   s  source identification (IEC 61162-450: the sender's SFI, e.g. "GP0001")
//   d  destination identification
//   n  line count (IEC 61162-450: the sender's running sentence counter, 1..999)
//   c  UNIX time: read as SECONDS since 1970-01-01 UTC (NMEA 0183 v4.10); a value of 11 digits
//      or more (>= 1e10 s is after the year 2286) is read as MILLISECONDS, as some receivers
//      send. TagBlock::unix_time_ms holds milliseconds either way.
//   g  sentence grouping "number-total-id" (e.g. "1-2-17")
//   r  relative time (an integer), t  text
// Unknown single-letter codes are skipped. Consecutive TAG blocks before one sentence are
// merged (a later code overrides an earlier one). The unit of c (seconds) is from memory of
// NMEA 0183 v4.10; no source found with the search tool confirmed it: check it against the
// IEC 61162-450 text before relying on the millisecond rule.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "usv_fdi/nmea/result.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea {

/// Longest TAG block between the two '\' (NMEA 0183 v4.x).
constexpr std::size_t kMaxTagBlockLength = 80;
/// Longest datagram read (an Ethernet frame's UDP payload; IEC 61162-450 keeps below it).
constexpr std::size_t kMaxDatagramLength = 1472;
/// The IEC 61162-450 header of a sentence datagram ("UdPbC" and a NUL byte).
constexpr std::string_view kIec450Header{"UdPbC\0", 6};

/// Sentence grouping (g:): this sentence is `number` of `total` of group `id`.
struct TagGroup {
  std::int64_t number = 0;
  std::int64_t total = 0;
  std::int64_t id = 0;
  bool operator==(const TagGroup& o) const {
    return number == o.number && total == o.total && id == o.id;
  }
};

/// The parameters of the TAG blocks before one sentence; absent codes are empty.
struct TagBlock {
  std::optional<std::string> source;          ///< s:
  std::optional<std::string> destination;     ///< d:
  std::optional<std::int64_t> line_count;     ///< n:
  std::optional<std::int64_t> unix_time_ms;   ///< c: [ms since 1970-01-01 UTC]
  std::optional<TagGroup> group;              ///< g:
  std::optional<std::int64_t> relative_time;  ///< r:
  std::optional<std::string> text;            ///< t:
  bool operator==(const TagBlock& o) const {
    return source == o.source && destination == o.destination && line_count == o.line_count &&
           unix_time_ms == o.unix_time_ms && group == o.group && relative_time == o.relative_time &&
           text == o.text;
  }
};

/// One line of a datagram: its TAG block (if any) and its sentence.
struct TaggedSentence {
  std::optional<TagBlock> tag;
  Sentence sentence;
};

/// A datagram: each line is parsed on its own, so one bad line does not lose the others.
struct Datagram {
  bool iec450 = false;  ///< began with "UdPbC\0"
  std::vector<Result<TaggedSentence>> lines;
};

/// Parses the parameters between '\' and '\' (with "*hh"). Never throws.
Result<TagBlock> parse_tag_block(std::string_view block);

/// Parses one line: TAG blocks, then a sentence. Never throws.
Result<TaggedSentence> parse_tagged_sentence(std::string_view line);

/// Parses a UDP payload. Refused as a whole only when empty, too long, or with a foreign
/// IEC 61162-450 header; otherwise every non-blank line has its own Result. Never throws.
Result<Datagram> parse_datagram(std::string_view bytes);

/// "\s:SRC,n:12,c:1700000000*hh\" for the parameters present, in the order s d n c g r t;
/// c in seconds when unix_time_ms is a whole second (below 1e10 s), else in milliseconds (read
/// back as milliseconds only from 1e10 ms, 1970-04-26, on). Refused: a negative number, a
/// fraction of a second before 1970-04-26, a value with a reserved, non-printable or ','
/// character, or a block over kMaxTagBlockLength.
Result<std::string> format_tag_block(const TagBlock& tag);

/// An IEC 61162-450 datagram: the header, then each sentence (already formatted, with CR LF)
/// after the TAG block of `tag` (the TAG block before the first sentence only).
Result<std::string> format_iec450_datagram(const TagBlock& tag,
                                           const std::vector<std::string>& sentences);

}  // namespace usvfdi::nmea
