// Exact sampled first-order filters used by the identification thread.
#pragma once

#include <cmath>

namespace usvfdi {

/// F(p) = eps / (p + eps) integrated exactly for an input that is linear between samples
/// (first-order hold). A zero-order hold biases m = A q by O(eps * dt); this does not.
///   z_{k+1} = e z_k + (1 - e - c) u_{k+1} + c u_k,  e = exp(-eps h),
///   c = (1 - e - eps h e) / (eps h).
class FohLowPass {
 public:
  explicit FohLowPass(double eps = 1.0) : eps_(eps) {}

  double eps() const { return eps_; }

  /// Recomputes the coefficients for step h [s]; cached while h is unchanged.
  void set_step(double h) {
    if (std::abs(h - h_) <= 1e-9 * h) return;  // timestamps jitter in the last bits
    h_ = h;
    const double x = eps_ * h;
    e_ = std::exp(-x);
    // 1 - e - x e, computed without cancellation for small x: x^2/2 - x^3/3 + x^4/8 ...
    double num;
    if (x < 1e-3) {
      num = x * x * (0.5 - x / 3.0 + x * x / 8.0);
    } else {
      num = -std::expm1(-x) - x * e_;
    }
    c_ = num / x;
    w_new_ = -std::expm1(-x) - c_;
  }

  /// Advances the state by one step; u_prev is the input at the previous sample.
  double step(double u_prev, double u_new, double z) const {
    return e_ * z + w_new_ * u_new + c_ * u_prev;
  }

 private:
  double eps_;
  double h_ = -1.0;
  double e_ = 1.0;
  double c_ = 0.0;
  double w_new_ = 0.0;
};

}  // namespace usvfdi
