// libFuzzer target: the NMEA 0183 / IEC 61162-450 parser (include/usv_fdi/nmea/).
//
// Contract under test: for ANY input bytes, parse_datagram() returns (never throws, never
// crashes, never reads out of bounds: ASan in the fuzz build). For every line it accepts:
// - the sentence re-formats (format_sentence) and parses back to the same Sentence;
// - a TAG block re-formats (refused only as too long, when several blocks were merged) and
//   parses back to the same TagBlock;
// - a sentence that its typed parser (ROT, RSA, HDT, THS, VBW, VTG, ALF, ALC, HBT, ARC, ACN)
//   accepts re-formats with the typed formatter to a sentence that parses to the same value.
// Every rejection has a non-empty text. Anything else is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "usv_fdi/nmea/alert.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea/navigation.hpp"

namespace {

using namespace usvfdi::nmea;

[[noreturn]] void contract_broken(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_nmea: contract broken: %s: %s\n", what, detail.c_str());
  std::abort();
}

void check_rejection(const Rejection& r, const std::string& where) {
  if (r.text.empty()) contract_broken("rejection without a text", where);
}

/// parse -> format -> parse gives the same value.
template <class Parse, class Format>
void round_trip(const Sentence& s, Parse parse, Format format) {
  const auto first = parse(s);
  if (!first) {
    check_rejection(first.rejection(), s.formatter);
    return;
  }
  const auto text = format(first.value());
  if (!text) contract_broken("accepted value does not format", text.rejection().text);
  const auto sentence = parse_sentence(text.value());
  if (!sentence) contract_broken("formatted sentence refused", text.value());
  const auto second = parse(sentence.value());
  if (!second) contract_broken("formatted value refused", text.value());
  if (!(second.value() == first.value())) contract_broken("value changed", text.value());
}

void check_typed(const Sentence& s) {
  const std::string& f = s.formatter;
  if (f == "ROT") round_trip(s, parse_rot, format_rot);
  if (f == "RSA") round_trip(s, parse_rsa, format_rsa);
  if (f == "HDT") round_trip(s, parse_hdt, format_hdt);
  if (f == "THS") round_trip(s, parse_ths, format_ths);
  if (f == "VBW") round_trip(s, parse_vbw, format_vbw);
  if (f == "VTG") round_trip(s, parse_vtg, format_vtg);
  if (f == "ALF") round_trip(s, parse_alf, format_alf);
  if (f == "ALC") round_trip(s, parse_alc, format_alc);
  if (f == "HBT") round_trip(s, parse_hbt, format_hbt);
  if (f == "ARC") round_trip(s, parse_arc, format_arc);
  if (f == "ACN") round_trip(s, parse_acn, format_acn);
}

void check_line(const TaggedSentence& line) {
  const auto text = format_sentence(line.sentence);
  if (!text) contract_broken("accepted sentence does not format", text.rejection().text);
  const auto again = parse_sentence(text.value());
  if (!again || !(again.value() == line.sentence)) {
    contract_broken("sentence changed", text.value());
  }
  if (line.tag) {
    const auto block = format_tag_block(*line.tag);
    if (!block && block.rejection().reason != Reason::kTooLong) {
      contract_broken("accepted TAG block does not format", block.rejection().text);
    }
    if (block) {
      const std::string& b = block.value();
      const auto back = parse_tag_block(std::string_view(b).substr(1, b.size() - 2));
      if (!back || !(back.value() == *line.tag)) contract_broken("TAG block changed", b);
    }
  }
  check_typed(line.sentence);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto datagram = parse_datagram(bytes);
  if (!datagram) {
    check_rejection(datagram.rejection(), "datagram");
    return 0;
  }
  for (const auto& line : datagram.value().lines) {
    if (line) {
      check_line(line.value());
    } else {
      check_rejection(line.rejection(), "line");
    }
  }
  // The sentence parser alone, on the whole input as one line.
  const auto one = parse_sentence(bytes);
  if (one) check_typed(one.value());
  return 0;
}
