// Opening a subcommand's output file (io::OutputFile: written to a temporary beside it and
// renamed at the end; "-": stdout), shared by `replay` and the classic `sim` scenarios.
#pragma once

#include <spdlog/spdlog.h>

#include <memory>
#include <string>

#include "usv_fdi/io/output_file.hpp"

namespace usvfdi::app {

/// The opened output, or nullptr after logging why it cannot be created (exit kExitOutput).
inline std::unique_ptr<io::OutputFile> open_output(const std::string& path) {
  try {
    return std::make_unique<io::OutputFile>(path);
  } catch (const io::OutputError& e) {
    spdlog::error("{}", e.what());
    return nullptr;
  }
}

}  // namespace usvfdi::app
