// How starved the machine is while a test measures a duration: a thread that sleeps 2 ms
// at a time and records by how much each sleep overshoots (the scheduling delay a runnable
// thread suffers), and the load average. Time limits of the end-to-end tests are derived
// from it (a design bound plus a multiple of the delay measured), and their failures say
// whether the machine was starved.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

namespace usvfdi::dds::test {

class StarvationMeter {
 public:
  StarvationMeter() : thread_([this] { run(); }) {}
  ~StarvationMeter() {
    stop_ = true;
    thread_.join();
  }
  StarvationMeter(const StarvationMeter&) = delete;
  StarvationMeter& operator=(const StarvationMeter&) = delete;

  /// The longest scheduling delay seen so far [s].
  double max_delay() const { return static_cast<double>(max_ns_.load()) * 1e-9; }
  /// The mean scheduling delay so far [s].
  double mean_delay() const {
    const auto n = samples_.load();
    return n == 0 ? 0.0 : static_cast<double>(sum_ns_.load()) * 1e-9 / static_cast<double>(n);
  }
  /// A time limit: `bound` (what the design promises on an idle machine) plus `factor`
  /// times the longest scheduling delay measured.
  double limit(double bound, double factor = 10.0) const { return bound + factor * max_delay(); }
  /// "load average 7.2 (2 CPUs), scheduling delay mean 3.1 ms, max 85.0 ms: starved".
  std::string report() const {
    double load = -1.0;
    std::ifstream("/proc/loadavg") >> load;
    const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "load average %.1f (%u CPUs), scheduling delay mean %.1f ms, max %.1f ms: %s",
                  load, cpus, 1e3 * mean_delay(), 1e3 * max_delay(),
                  max_delay() > 0.02 || load > cpus ? "the machine was starved"
                                                    : "the machine was not starved");
    return buf;
  }

 private:
  void run() {
    using Clock = std::chrono::steady_clock;
    const auto nap = std::chrono::milliseconds(2);
    while (!stop_) {
      const auto t0 = Clock::now();
      std::this_thread::sleep_for(nap);
      const auto late =
          std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0 - nap).count();
      const auto ns = static_cast<long long>(std::max<long long>(0, late));
      sum_ns_ += ns;
      ++samples_;
      long long m = max_ns_.load();
      while (ns > m && !max_ns_.compare_exchange_weak(m, ns)) {
      }
    }
  }
  std::atomic<bool> stop_{false};
  std::atomic<long long> max_ns_{0}, sum_ns_{0}, samples_{0};
  std::thread thread_;
};

}  // namespace usvfdi::dds::test
