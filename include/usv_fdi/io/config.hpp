// YAML configuration of the FDI engine (config/default.yaml documents every key).
//
// `model.B: [b1, b2]` is the only required key; every other key defaults to the core
// parameter structs. A top-level `service:` mapping is accepted and left to the DDS
// service. Unknown keys, wrong types, wrong list lengths, YAML syntax errors and values
// that EngineConfig::validate() refuses all throw ConfigError, whose message names the
// file, the key path, the line and the offending value. yaml-cpp stays out of this header.
#pragma once

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/core/engine.hpp"

namespace usvfdi::io {

/// Any problem with a configuration file: "<file>:<line>: <key.path> = <value>: <reason>".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One value of a YAML file, handed to the handler of a section that another module reads
/// (the DDS service's `service:`). Every accessor checks the value and throws ConfigError
/// "<file>:<line>: <key.path> = <value>: must be <what>" when it does not fit. yaml-cpp stays
/// inside config.cpp.
class ConfigValue {
 public:
  using Handler = std::function<void(const ConfigValue&)>;
  using Table = std::map<std::string, Handler>;

  const std::string& path() const;  ///< "service.mmsi"
  bool is_null() const;
  /// A finite number in [lo, hi]; `what` completes "must be ..." when it is no number (e.g.
  /// "a rate in Hz"), `range` when it is out of range ("" : `what`).
  double number(double lo, double hi, const std::string& what, const std::string& range = "") const;
  /// An integer in [lo, hi] (messages as for number()).
  long long integer(long long lo, long long hi, const std::string& what,
                    const std::string& range = "") const;
  bool boolean() const;                             ///< true or false
  std::string text(const std::string& what) const;  ///< a scalar (e.g. "a file path")
  std::vector<std::string> strings() const;         ///< a list of strings
  /// A mapping: calls the table's handler of each key, in the file's order. An unknown key
  /// is an error `unknown` (e.g. "unknown key") showing the key (`show_key`) or its value; a
  /// repeated key is an error.
  void section(const Table& table, const std::string& unknown = "unknown key",
               bool show_key = true) const;
  /// "<file>:<line>: <key.path> = <value>" (for a message built later).
  std::string where() const;
  [[noreturn]] void fail(const std::string& reason) const;

  struct Impl;
  explicit ConfigValue(const Impl* impl) : impl_(impl) {}

 private:
  const Impl* impl_;
};

/// Loads and validates an engine configuration from a YAML file.
EngineConfig load_engine_config(const std::string& path);

/// Same, reading the file once, with the top-level sections of `extra` (e.g. {"service",
/// handler}) read by their handlers instead of being accepted as any mapping.
EngineConfig load_engine_config(const std::string& path, const ConfigValue::Table& extra);

/// Same, from YAML text; `name` stands for the file name in error messages.
EngineConfig load_engine_config_from_string(const std::string& yaml,
                                            const std::string& name = "<string>");

}  // namespace usvfdi::io
