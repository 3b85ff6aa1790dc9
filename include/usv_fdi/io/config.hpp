// YAML configuration of the FDI engine (config/default.yaml documents every key).
//
// `model.B: [b1, b2]` is the only required key; every other key defaults to the core
// parameter structs. A top-level `service:` mapping is accepted and left to the DDS
// service. Unknown keys, wrong types, wrong list lengths, YAML syntax errors and values
// that EngineConfig::validate() refuses all throw ConfigError, whose message names the
// file, the key path, the line and the offending value. yaml-cpp stays out of this header.
#pragma once

#include <stdexcept>
#include <string>

#include "usv_fdi/core/engine.hpp"

namespace usvfdi::io {

/// Any problem with a configuration file: "<file>:<line>: <key.path> = <value>: <reason>".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Loads and validates an engine configuration from a YAML file.
EngineConfig load_engine_config(const std::string& path);

/// Same, from YAML text; `name` stands for the file name in error messages.
EngineConfig load_engine_config_from_string(const std::string& yaml,
                                            const std::string& name = "<string>");

}  // namespace usvfdi::io
