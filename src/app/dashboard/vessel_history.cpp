#include "vessel_history.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace usvfdi::app::dashboard {
namespace {

/// A stored float as the double of its shortest decimal form (0.3f is sent as 0.3, not as
/// 0.30000001192092896); NaN and infinities as null.
nlohmann::json number(float x) {
  if (!std::isfinite(x)) return nullptr;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", static_cast<double>(x));
  return std::strtod(buf, nullptr);
}

}  // namespace

void VesselHistory::add(const VesselStatus& v) {
  const fdi::FdiStatus& s = v.st;
  Point p;
  p.t = v.written;
  const auto f = [](double x) { return static_cast<float>(x); };
  p.v = {f(s.j_peak()[0]),
         f(s.j_peak()[1]),
         f(s.j_raise()[0]),
         f(s.j_raise()[1]),
         f(s.j_leave()[0]),
         f(s.j_leave()[1]),
         f(s.c_a()),
         f(s.c_g()),
         f(s.a()[0]),
         f(s.a()[1]),
         f(s.a()[2]),
         f(s.a()[3]),
         s.armed() ? 1.0f : 0.0f,
         s.converged() ? 1.0f : 0.0f,
         s.model_mismatch() ? 1.0f : 0.0f,
         f(s.excitation())};
  std::lock_guard<std::mutex> l(m_);
  std::deque<Point>& d = points_[s.mmsi()];
  if (!d.empty() && !(p.t > d.back().t)) return;
  d.push_back(p);
  while (d.size() > capacity_) d.pop_front();
}

bool VesselHistory::to_json(std::uint32_t mmsi, double since, nlohmann::json* out) const {
  std::lock_guard<std::mutex> l(m_);
  const auto it = points_.find(mmsi);
  if (it == points_.end() || it->second.empty()) return false;
  nlohmann::json t = nlohmann::json::array();
  std::array<nlohmann::json, kCount> cols;
  for (auto& c : cols) c = nlohmann::json::array();
  for (const Point& p : it->second) {
    if (!(p.t > since)) continue;
    t.push_back(p.t);
    for (std::size_t i = 0; i < kCount; ++i) {
      cols[i].push_back(number(p.v[i]));
    }
  }
  nlohmann::json j{{"mmsi", mmsi}, {"capacity", capacity_}, {"t", std::move(t)}};
  for (std::size_t i = 0; i < kCount; ++i) j[kSeries[i]] = std::move(cols[i]);
  *out = std::move(j);
  return true;
}

std::size_t VesselHistory::vessels() const {
  std::lock_guard<std::mutex> l(m_);
  return points_.size();
}

}  // namespace usvfdi::app::dashboard
