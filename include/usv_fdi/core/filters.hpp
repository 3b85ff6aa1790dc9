// Exact sampled first-order filters used by the identification thread.
#pragma once

#include <cmath>

namespace usvfdi {

/// F(p) = eps / (p + eps) integrated exactly for an input that is linear between samples
/// (first-order hold). A zero-order hold biases m = A q by O(eps * dt); this does not.
///   z_{k+1} = e z_k + (1 - e - c) u_{k+1} + c u_k,  e = exp(-eps h),
///   c = (1 - e - eps h e) / (eps h).
/// step_curved() adds the exact response to the quadratic part of the input over the step,
///   u(s) = FOH(s) + u''/2 s (s - h),  w2 = int_0^h eps e^{-eps (h - s)} s (s - h) / 2 ds,
/// with u'' from the last three samples, which lowers the error from O(h^2) to O(h^3).
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
    // I = int_0^h e^{-eps tau} tau (h - tau) dtau; w2 = -eps I / 2.
    double I;
    if (x < 1.0) {
      I = 0.0;
      double term = h * h * h;  // (-eps)^n / n! h^{n+3}
      for (int n = 0; n < 30; ++n) {
        I += term / ((n + 2.0) * (n + 3.0));
        term *= -x / (n + 1.0);
      }
    } else {
      const double e2 = eps_ * eps_;
      const double I1 = (1.0 - e_ * (1.0 + x)) / e2;
      const double I2 = 2.0 / (e2 * eps_) * (1.0 - e_ * (1.0 + x + 0.5 * x * x));
      I = h * I1 - I2;
    }
    w2_ = -0.5 * eps_ * I;
  }

  /// Curvature of the input over the last step from three samples (divided differences).
  static double curvature(double u_pp, double u_p, double u_n, double h_prev, double h) {
    return 2.0 * ((u_n - u_p) / h - (u_p - u_pp) / h_prev) / (h + h_prev);
  }

  /// step() plus the response to the input's curvature u'' over the step.
  double step_curved(double u_prev, double u_new, double u_dd, double z) const {
    return step(u_prev, u_new, z) + w2_ * u_dd;
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
  double w2_ = 0.0;
};

}  // namespace usvfdi
