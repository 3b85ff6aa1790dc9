// Helpers of the NMEA tests: sentences with computed checksums, rejection reasons.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea::test {

/// start + body + "*hh", the checksum by checksum() (itself checked against python3-computed
/// literals in test_sentence.cpp).
inline std::string with_checksum(const std::string& body, char start = '$') {
  char b[3];
  std::snprintf(b, sizeof b, "%02X", checksum(body));
  return start + body + "*" + b;
}

/// The Sentence of "$" + body + "*hh"; fails the test if the sentence layer refuses it.
inline Sentence sentence(const std::string& body) {
  auto r = parse_sentence(with_checksum(body));
  EXPECT_TRUE(r.ok()) << body << ": " << r.rejection().text;
  return r.ok() ? r.value() : Sentence{};
}

/// The reason a typed parser refuses "$" + body + "*hh"; fails the test if it accepts it.
template <class T, class Parse>
Reason reason(Parse parse, const std::string& body) {
  const Result<T> r = parse(sentence(body));
  EXPECT_FALSE(r.ok()) << body;
  return r.ok() ? Reason::kEmpty : r.rejection().reason;
}

}  // namespace usvfdi::nmea::test
