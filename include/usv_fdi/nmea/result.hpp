// Rejections and the result type of the NMEA 0183 / IEC 61162-450 library (usv_fdi::nmea).
//
// The library never throws on bad input: every parser returns a Result<T>, which holds either
// the parsed value or a Rejection (a Reason to count and switch on, and a text that names what
// was wrong, e.g. "field 1 (rate of turn): not a number: '3x.5'").
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace usvfdi::nmea {

/// Why an input was refused.
enum class Reason {
  kEmpty,              ///< nothing to parse
  kNoStart,            ///< a sentence does not begin with '$' or '!'
  kTooLong,            ///< longer than 82 characters (with CR LF), or a datagram/TAG too long
  kNonPrintable,       ///< a byte outside printable ASCII 0x20..0x7E (or CR/LF inside a line)
  kReservedCharacter,  ///< '$', '!', '*', '\' or '~' inside the fields
  kNoChecksum,         ///< no '*hh' checksum
  kBadChecksumSyntax,  ///< the checksum is not two hex digits at the end of the line
  kChecksumMismatch,   ///< the checksum does not match the characters
  kBadAddress,         ///< talker or sentence formatter malformed
  kBadHeader,          ///< an IEC 61162-450 header other than "UdPbC\0"
  kBadTagBlock,        ///< a TAG block that is malformed, unterminated or has a bad checksum
  kWrongSentence,      ///< a typed parser was given another sentence formatter
  kFieldCount,         ///< too few or too many fields for the sentence formatter
  kBadField,           ///< a field that cannot be read (not a number, an unknown status letter)
  kOutOfRange,         ///< a value outside its range or physically absurd
};

/// Short name of a reason ("checksum mismatch"), for counters and logs.
const char* to_string(Reason reason);

/// A refused input: the reason and a text that names what was wrong.
struct Rejection {
  Reason reason = Reason::kEmpty;
  std::string text;
};

/// Either a value or a Rejection. Accessing value() of a rejected result throws
/// std::bad_optional_access (a programming error, never caused by input).
template <class T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}                      // NOLINT: implicit by design
  Result(Rejection rejection) : rejection_(std::move(rejection)) {}  // NOLINT
  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const T& value() const { return value_.value(); }
  T& value() { return value_.value(); }
  const Rejection& rejection() const { return rejection_; }

 private:
  std::optional<T> value_;
  Rejection rejection_;
};

/// A rejection with its text.
inline Rejection reject(Reason reason, std::string text) { return {reason, std::move(text)}; }

}  // namespace usvfdi::nmea
