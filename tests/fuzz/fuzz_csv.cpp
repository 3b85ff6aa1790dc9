// libFuzzer target: the CSV sample reader (include/usv_fdi/io/csv.hpp).
//
// Contract under test: for ANY input bytes, CsvSampleReader either reads rows (each with the four
// required fields parsed) until the end, or throws InputError whose message starts with the name it
// was given and whose line() lies within the input. Any other exception, a crash, a sanitizer
// report or a hang is a bug. parse_csv_number() is checked on every field of every line too.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>

#include "usv_fdi/io/csv.hpp"

namespace {

[[noreturn]] void contract_broken(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_csv: contract broken: %s: %s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kName = "fuzz.csv";
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::size_t lines = 1;
  for (char c : text) lines += c == '\n' ? 1 : 0;

  // The number parser alone, on every comma-separated field.
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find_first_of(",\n", start);
    if (end == std::string::npos) end = text.size();
    double x = 0.0;
    (void)usvfdi::io::parse_csv_number(text.substr(start, end - start), &x);
    start = end + 1;
  }

  try {
    usvfdi::io::CsvSampleReader reader(std::make_unique<std::istringstream>(text), kName);
    usvfdi::Sample s;
    std::size_t rows = 0;
    while (reader.next(&s)) {
      if (++rows > lines) contract_broken("more rows than lines", std::to_string(rows));
    }
    if (reader.rows() != rows) contract_broken("rows() disagrees", std::to_string(reader.rows()));
  } catch (const usvfdi::io::InputError& e) {
    const std::string msg = e.what();
    if (msg.compare(0, kName.size(), kName) != 0 || e.file() != kName) {
      contract_broken("InputError does not name the file", msg);
    }
    if (e.line() > lines) {
      contract_broken("InputError line past the end of the input",
                      std::to_string(e.line()) + " > " + std::to_string(lines));
    }
  }
  return 0;
}
