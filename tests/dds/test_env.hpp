// Per-process DDS isolation for tests: a domain id and partition derived from the pid, so
// concurrently running test processes (ctest -j) neither match nor disturb each other.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <string>

namespace usvfdi::dds::test {

inline constexpr const char* kProfilesFile = USV_FDI_DDS_PROFILES;
inline constexpr const char* kProbe = USV_FDI_DDS_PROBE;

/// 1..200 (Fast DDS's default port mapping allows 0..232; 0 is left to real deployments).
inline std::uint32_t test_domain_id() { return 1 + static_cast<std::uint32_t>(::getpid()) % 200; }

/// A partition name unique to this process and call.
inline std::string unique_partition() {
  static std::atomic<unsigned> counter{0};
  return "usv_fdi_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

}  // namespace usvfdi::dds::test
