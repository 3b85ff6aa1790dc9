// What the DDS probe (tests/dds/probe.cpp) and the DDS Security probe
// (tests/security/secure_probe.cpp) share: the stop flag set by SIGTERM/SIGINT, usage errors and
// the parsing of numeric option values, and deadlines. Header-only; each probe is one program.
#pragma once

#include <signal.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

namespace usvfdi::test_support::probe {

using Clock = std::chrono::steady_clock;

/// Set by SIGTERM/SIGINT once install_signal_handlers() ran.
inline std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "signal flag must be lock free");

extern "C" inline void on_signal(int) { g_stop.store(true); }  // no I/O, async-signal-safe

inline void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

/// A mistake on the command line (the probes exit 3 with its message).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline unsigned long parse_unsigned(const std::string& flag, const std::string& value) {
  try {
    std::size_t used = 0;
    const unsigned long v = std::stoul(value, &used);
    if (used != value.size()) throw std::invalid_argument(value);
    return v;
  } catch (const std::exception&) {
    throw UsageError(flag + ": not an unsigned integer: '" + value + "'");
  }
}

/// `seconds` from now.
inline Clock::time_point deadline_after(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace usvfdi::test_support::probe
