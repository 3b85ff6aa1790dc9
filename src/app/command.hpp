// Subcommand plumbing of the usv-fdi executable. Each subcommand lives in its own file and
// exposes one registration function (declared in commands.hpp) that adds its options to
// the registry; main.cpp only calls the registration functions.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace usvfdi::app {

/// Process exit codes shared by every subcommand.
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,     ///< anything else (internal error, bad option value)
  kExitConfig = 2,      ///< configuration file missing or invalid
  kExitInput = 3,       ///< input data file missing or malformed
  kExitOutput = 4,      ///< output file cannot be written
  kExitRejected = 5,    ///< replay: the input was read, but most rows were rejected
  kExitIncomplete = 6,  ///< monitor --once --roster: a vessel of the roster was never heard
  kExitUsage = 64,      ///< command line not understood (EX_USAGE)
};

class CommandRegistry {
 public:
  explicit CommandRegistry(CLI::App& root) : root_(root) {}

  /// Adds a subcommand; `run` is called when it was selected and returns the exit code.
  CLI::App* add(const std::string& name, const std::string& description, std::function<int()> run) {
    CLI::App* sub = root_.add_subcommand(name, description);
    commands_.emplace_back(sub, std::move(run));
    return sub;
  }

  /// The root command line (global options such as --log-level).
  const CLI::App& root() const { return root_; }

  /// After a successful parse: runs the selected subcommand.
  int run_selected() const {
    for (const auto& [sub, run] : commands_) {
      if (sub->parsed()) return run();
    }
    return kExitUsage;
  }

 private:
  CLI::App& root_;
  std::vector<std::pair<CLI::App*, std::function<int()>>> commands_;
};

}  // namespace usvfdi::app
