// Robust statistics shared by the core's units.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace usvfdi {

/// The median of the values, reordering them (the upper one of an even count; 0 when there
/// are none).
inline double median_in_place(std::vector<double>* v) {
  if (v->empty()) return 0.0;
  const auto mid = v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2);
  std::nth_element(v->begin(), mid, v->end());
  return *mid;
}

/// 1.4826 x the median absolute deviation about m (the median of the values): the standard
/// deviation for Gaussian data, robust to outliers and to a fault covering less than half of
/// the data (0 for fewer than two). The values are kept; scratch holds the deviations.
inline double robust_std_about(const std::vector<double>& v, double m,
                               std::vector<double>* scratch) {
  if (v.size() < 2) return 0.0;
  scratch->resize(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) (*scratch)[i] = std::abs(v[i] - m);
  return 1.4826 * median_in_place(scratch);
}

/// robust_std_about the values' median, reordering them.
inline double robust_std(std::vector<double>* v) {
  if (v->size() < 2) return 0.0;
  std::vector<double> dev;
  return robust_std_about(*v, median_in_place(v), &dev);
}

/// The value of rank k (0-based) of the values, reordering them, when they were last
/// reordered by median_in_place: the search is confined to the upper half for k at or above
/// the median's rank (the same value std::sort would put at k).
inline double upper_rank_after_median(std::vector<double>* v, std::size_t k) {
  const std::size_t mid = v->size() / 2;
  const auto first = v->begin() + static_cast<std::ptrdiff_t>(k >= mid ? mid : 0);
  const auto kth = v->begin() + static_cast<std::ptrdiff_t>(k);
  std::nth_element(first, kth, v->end());
  return *kth;
}

}  // namespace usvfdi
