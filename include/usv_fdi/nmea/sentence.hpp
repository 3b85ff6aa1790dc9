// NMEA 0183 (IEC 61162-1) sentence layer: split, check and build one sentence.
//
// A sentence is  start address,field,...,field*hh CR LF :
// - start '$' (parametric sentence) or '!' (encapsulated sentence, e.g. AIS !AIVDM);
// - address: a talker of two characters (A-Z or 0-9: "GP", "HE", "II", user talkers "U0".."U9")
//   followed by a three-letter sentence formatter (A-Z), e.g. "HEROT" -> talker "HE",
//   formatter "ROT"; or a proprietary address 'P' + manufacturer mnemonic (+ more), e.g.
//   "PSAT" -> talker "P", formatter "SAT" (proprietary == true);
// - fields separated by ',' (empty fields are null fields);
// - '*hh': the checksum, required here: two hex digits (either case) of the XOR of every
//   character strictly between the start character and '*';
// - at most 82 characters from the start character to LF inclusive (NMEA 0183 / IEC
//   61162-1), i.e. 80 without the CR LF.
// Accepted characters are printable ASCII 0x20..0x7E; '$', '!', '*', '\' and '~' are reserved
// and refused inside the fields ('^' hex escapes are left as they are; alert texts decode them).
// A line may end with CR LF, LF or nothing; a lone CR or any other control byte is refused.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "usv_fdi/nmea/result.hpp"

namespace usvfdi::nmea {

/// Longest sentence from the start character to LF inclusive (NMEA 0183).
constexpr std::size_t kMaxSentenceLength = 82;

/// One sentence split into its parts.
struct Sentence {
  char start = '$';                 ///< '$' or '!'
  std::string talker;               ///< two characters, or "P" for a proprietary sentence
  std::string formatter;            ///< "ROT", "RSA", ...; for "P": the rest of the address field
  bool proprietary = false;         ///< address begins with 'P' (talker "P")
  std::vector<std::string> fields;  ///< the data fields after the address, in order

  bool operator==(const Sentence& o) const {
    return start == o.start && talker == o.talker && formatter == o.formatter &&
           proprietary == o.proprietary && fields == o.fields;
  }
};

/// XOR of the characters of `body` (the characters between the start and '*').
std::uint8_t checksum(std::string_view body);

/// Parses one line. Never throws; never reads outside `line`.
Result<Sentence> parse_sentence(std::string_view line);

/// Builds "$TTFFF,f1,...,fn*hh\r\n". Refused (never throws): a malformed talker or formatter, a
/// field with a reserved, non-printable or ',' character, or a result over 82 characters.
Result<std::string> format_sentence(const Sentence& sentence);

}  // namespace usvfdi::nmea
