// libFuzzer target: the YAML engine-config loader (include/usv_fdi/io/config.hpp).
//
// Contract under test: for ANY input text, load_engine_config_from_string() either returns a
// configuration that EngineConfig::validate() accepts, or throws ConfigError whose message starts
// with the file name it was given. Any other exception, a crash, a sanitizer report, a hang or
// unbounded memory is a bug (libFuzzer reports uncaught exceptions as a deadly signal).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "usv_fdi/io/config.hpp"

namespace {

[[noreturn]] void contract_broken(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_config: contract broken: %s: %s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kName = "fuzz.yaml";
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const usvfdi::EngineConfig cfg = usvfdi::io::load_engine_config_from_string(text, kName);
    try {
      cfg.validate();  // what the loader returns must be valid
    } catch (const std::exception& e) {
      contract_broken("loader returned a config that validate() refuses", e.what());
    }
  } catch (const usvfdi::io::ConfigError& e) {
    const std::string msg = e.what();
    if (msg.compare(0, kName.size(), kName) != 0) {
      contract_broken("ConfigError does not name the file", msg);
    }
  }
  return 0;
}
