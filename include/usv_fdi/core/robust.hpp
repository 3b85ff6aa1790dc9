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

/// 1.4826 x the median absolute deviation: the standard deviation for Gaussian data, robust
/// to outliers and to a fault covering less than half of the data (0 for fewer than two).
inline double robust_std(std::vector<double>* v) {
  if (v->size() < 2) return 0.0;
  const double m = median_in_place(v);
  std::vector<double> dev(v->size());
  for (std::size_t i = 0; i < v->size(); ++i) dev[i] = std::abs((*v)[i] - m);
  return 1.4826 * median_in_place(&dev);
}

}  // namespace usvfdi
