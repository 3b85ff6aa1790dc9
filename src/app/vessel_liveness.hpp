// The monitor's "last heard" bookkeeping: per vessel (MMSI), the local receive time of the
// last sample of any kind from it, and whether it has been silent for longer than a threshold.
// Pure logic on a caller-supplied clock (seconds, monotonic), no DDS: the monitor feeds it
// receive times and calls evaluate() on every turn of its loop, so a vessel goes silent on time
// even when nothing arrives at all.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

namespace usvfdi::app {

class VesselLiveness {
 public:
  /// One change of a vessel's silence, to be printed once.
  struct Change {
    std::uint32_t mmsi = 0;
    bool silent = false;  ///< true: went silent; false: heard again
    double age = 0.0;     ///< seconds since it was last heard, when the change was noticed
    double gap = 0.0;     ///< heard again: how long nothing had been heard from it [s]
  };

  /// `silent_after` [s] > 0: a vessel not heard for longer than this is silent.
  explicit VesselLiveness(double silent_after) : silent_after_(silent_after) {}

  double silent_after() const { return silent_after_; }

  /// A sample from `mmsi` was received at `now`. If the vessel was silent, returns true and
  /// fills `*change` (heard again); otherwise returns false.
  bool heard(std::uint32_t mmsi, double now, Change* change) {
    auto [it, fresh] = vessels_.try_emplace(mmsi, Vessel{now, false});
    Vessel& v = it->second;
    if (fresh) return false;
    const bool was_silent = v.silent;
    const double gap = now - v.last;
    v.last = std::max(v.last, now);
    v.silent = false;
    if (!was_silent) return false;
    *change = Change{mmsi, false, 0.0, gap};
    return true;
  }

  /// The vessels that have gone silent since the last call (each change reported once).
  std::vector<Change> evaluate(double now) {
    std::vector<Change> out;
    for (auto& [mmsi, v] : vessels_) {
      const double age = now - v.last;
      if (!v.silent && age > silent_after_) {
        v.silent = true;
        out.push_back(Change{mmsi, true, age, 0.0});
      }
    }
    return out;
  }

  /// Seconds since `mmsi` was last heard, NaN if never.
  double age(std::uint32_t mmsi, double now) const {
    const auto it = vessels_.find(mmsi);
    return it == vessels_.end() ? std::numeric_limits<double>::quiet_NaN() : now - it->second.last;
  }
  /// True once evaluate() has found the vessel silent, until it is heard again.
  bool silent(std::uint32_t mmsi) const {
    const auto it = vessels_.find(mmsi);
    return it != vessels_.end() && it->second.silent;
  }
  /// Every vessel heard so far, in MMSI order.
  std::vector<std::uint32_t> vessels() const {
    std::vector<std::uint32_t> out;
    for (const auto& kv : vessels_) out.push_back(kv.first);
    return out;
  }

 private:
  struct Vessel {
    double last = 0.0;  ///< local receive time of the last sample [s]
    bool silent = false;
  };
  double silent_after_;
  std::map<std::uint32_t, Vessel> vessels_;
};

}  // namespace usvfdi::app
