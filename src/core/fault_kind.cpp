#include "usv_fdi/core/fault_kind.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

namespace usvfdi {

FaultKind energy_kind(const std::vector<double>& whitened) {
  if (whitened.empty()) return FaultKind::kUnknown;
  std::vector<double> sq;
  sq.reserve(whitened.size());
  double total = 0, sum = 0;
  for (const double x : whitened) {
    sq.push_back(x * x);
    total += x * x;
    sum += x;
  }
  // Spikes: the excess energy of the window sits in one or two samples.
  std::sort(sq.begin(), sq.end(), std::greater<double>());
  const double nw = static_cast<double>(whitened.size());
  const double top2 = sq[0] + (sq.size() > 1 ? sq[1] : 0.0);
  const double excess = total - nw;
  if (excess > 0 && top2 - 2.0 > 0.7 * excess) return FaultKind::kSpikes;
  // Noise increase: energy without a consistent sign.
  const double mean = sum / nw, ms = total / nw;
  if (mean * mean < 0.2 * ms) return FaultKind::kNoise;
  return FaultKind::kUnknown;
}

FaultKind shape_kind(const TimedValues& d, const TimedValues& x) {
  const std::size_t m = d.size();
  if (m < 8 || x.size() != m) return FaultKind::kBias;
  // Two-regressor least squares with intercept: SSE of d on [1, z].
  const auto sse2 = [&](const std::vector<double>& z) {
    double sz = 0, szz = 0, sd = 0, sdd = 0, szd = 0;
    for (std::size_t i = 0; i < m; ++i) {
      sz += z[i];
      szz += z[i] * z[i];
      sd += d[i].second;
      sdd += d[i].second * d[i].second;
      szd += z[i] * d[i].second;
    }
    const double n = static_cast<double>(m);
    const double vzz = szz - sz * sz / n, vdd = sdd - sd * sd / n, vzd = szd - sz * sd / n;
    return vzz > 0 ? vdd - vzd * vzd / vzz : vdd;
  };
  double best_step = 1e300, best_hinge = 1e300, best_scale = 1e300;
  std::vector<double> z(m);
  const std::size_t stride = std::max<std::size_t>(1, m / 100);
  for (std::size_t k = 1; k + 2 < m; k += stride) {
    const double tau = d[k].first;
    for (std::size_t i = 0; i < m; ++i) z[i] = i >= k ? 1.0 : 0.0;
    best_step = std::min(best_step, sse2(z));
    for (std::size_t i = 0; i < m; ++i) z[i] = std::max(0.0, d[i].first - tau);
    best_hinge = std::min(best_hinge, sse2(z));
    for (std::size_t i = 0; i < m; ++i) z[i] = i >= k ? x[i].second : 0.0;
    best_scale = std::min(best_scale, sse2(z));
  }
  // A scale error on a signal that moves like a ramp fits a hinge as well, and a drift
  // fits a scale: each needs to beat the other clearly, else the common offset (bias).
  if (best_scale < 0.6 * best_step && best_scale < 0.8 * best_hinge) return FaultKind::kScale;
  if (best_hinge < 0.8 * best_step && best_hinge < 0.8 * best_scale) return FaultKind::kDrift;
  return FaultKind::kBias;
}

bool noise_rise_like(const TimedValues& d, double t_raise, double sigma_d) {
  // d is zero-mean when healthy (and unaffected by the reconfiguration of the channel's
  // observer); its spread before the raise is learned from the seconds before it.
  double n0 = 0, s0 = 0, ss0 = 0, n1 = 0, s1 = 0, ss1 = 0;
  for (const auto& [t, x] : d) {
    if (t < t_raise - 1.0) {
      n0 += 1;
      s0 += x;
      ss0 += x * x;
    } else if (t >= t_raise - 0.5) {
      n1 += 1;
      s1 += x;
      ss1 += x * x;
    }
  }
  if (n0 < 10 || n1 < 10) return false;
  const double v0 = std::max(ss0 / n0 - (s0 / n0) * (s0 / n0), sigma_d * sigma_d);
  const double m1 = s1 / n1, v1 = ss1 / n1 - m1 * m1;
  return v1 > 2.0 * v0 && m1 * m1 < 0.2 * v1;
}

double abnormal_run_onset(const TimedValues& s, double t) {
  double onset = t;
  int quiet = 0;
  for (auto it = s.rbegin(); it != s.rend(); ++it) {
    if (std::abs(it->second) > 2.0) {
      onset = it->first;
      quiet = 0;
    } else if (++quiet > 2) {
      break;
    }
  }
  return onset;
}

}  // namespace usvfdi
