// A vessel's recent detector statuses for the dashboard's vessel page (issue 13, section 1):
// per vessel, the last `capacity` FdiStatus samples shown, as columns the page's charts take as
// they are (uPlot's data: one array per series, time first). Thread-safe: the DDS thread adds,
// the HTTP threads read. No DDS, no HTTP.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>

#include <nlohmann/json.hpp>

#include "../monitor_model.hpp"

namespace usvfdi::app::dashboard {

class VesselHistory {
 public:
  /// The series kept, in the order of the JSON's "series" (besides "t").
  static constexpr const char* kSeries[] = {
      "j_a", "j_g", "raise_a", "raise_g", "leave_a", "leave_g",   "c_a",      "c_g",
      "a11", "a12", "a21",     "a22",     "armed",   "converged", "mismatch", "excitation"};
  static constexpr std::size_t kCount = sizeof(kSeries) / sizeof(kSeries[0]);

  explicit VesselHistory(std::size_t capacity = 300) : capacity_(capacity) {}
  /// Records a status shown on the board (its source time `v.written`); an older or repeated
  /// time than the vessel's last is not added (a writer's repeat, a late joiner's copy).
  void add(const VesselStatus& v);
  /// {"mmsi", "t": [...], "<series>": [...]...} of the points later than `since` [s]; NaN as
  /// null. False (out untouched) if the vessel has no point.
  bool to_json(std::uint32_t mmsi, double since, nlohmann::json* out) const;
  std::size_t vessels() const;

 private:
  struct Point {
    double t = 0.0;
    std::array<float, kCount> v{};
  };
  std::size_t capacity_;
  mutable std::mutex m_;
  std::map<std::uint32_t, std::deque<Point>> points_;
};

}  // namespace usvfdi::app::dashboard
