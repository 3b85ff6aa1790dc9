// Exact sampled first-order filters used by the identification thread.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace usvfdi {

/// F(p) = eps / (p + eps) integrated exactly for an input that is linear between samples
/// (first-order hold). A zero-order hold biases m = A q by O(eps * dt); this does not.
///   z_{k+1} = e z_k + (1 - e - c) u_{k+1} + c u_k,  e = exp(-eps h),
///   c = (1 - e - eps h e) / (eps h).
/// step_curved() adds the exact response to the quadratic part of the input over the step,
///   u(s) = FOH(s) + u''/2 s (s - h),  w2 = int_0^h eps e^{-eps (h - s)} s (s - h) / 2 ds,
/// with u'' from the last three samples, which lowers the error from O(h^2) to O(h^3).
/// step_cubic() adds the cubic term of Newton's interpolation through the last four samples
/// (nodes 0, h, -hp, -hp - hpp, the step running from 0 to h),
///   u(s) = FOH(s) + u''/2 s (s - h) + c3 s (s - h) (s + hp),  c3 = u[t_-3, t_-2, t_-1, t_0],
///   w3 = int_0^h eps e^{-eps (h - s)} s (s - h) (s + hp) ds,
/// which lowers the error to O(h^4).
class FohLowPass {
 public:
  explicit FohLowPass(double eps = 1.0) : eps_(eps) {}

  double eps() const { return eps_; }

  /// Recomputes the coefficients for step h [s] after a step hp [s] (hp only matters to
  /// step_cubic()); cached while both are unchanged.
  void set_step(double h, double hp) {
    set_step(h);
    if (w3_valid_ && std::abs(hp - hp_) <= 1e-9 * hp) return;
    hp_ = hp;
    // w3 = -eps (I2 + hp I), I2 = int_0^h e^{-eps tau} tau (h - tau)^2 dtau.
    const double x = eps_ * h_;
    double I2;
    if (x < 1.0) {
      I2 = 0.0;
      double term = h_ * h_ * h_ * h_;  // (-eps)^n / n! h^{n+4}
      for (int n = 0; n < 30; ++n) {
        I2 += 2.0 * term / ((n + 2.0) * (n + 3.0) * (n + 4.0));
        term *= -x / (n + 1.0);
      }
    } else {
      // h^2 M1 - 2 h M2 + M3, M_k = int_0^h tau^k e^{-eps tau} dtau.
      const double e2 = eps_ * eps_;
      const double M1 = (1.0 - e_ * (1.0 + x)) / e2;
      const double M2 = 2.0 / (e2 * eps_) * (1.0 - e_ * (1.0 + x + 0.5 * x * x));
      const double M3 = 6.0 / (e2 * e2) * (1.0 - e_ * (1.0 + x + 0.5 * x * x + x * x * x / 6.0));
      I2 = h_ * h_ * M1 - 2.0 * h_ * M2 + M3;
    }
    w3_ = -eps_ * (I2 + hp_ * I_);
    w3_valid_ = true;
  }

  /// Recomputes the coefficients for step h [s]; cached while h is unchanged.
  void set_step(double h) {
    if (std::abs(h - h_) <= 1e-9 * h) return;  // timestamps jitter in the last bits
    h_ = h;
    w3_valid_ = false;
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
    I_ = I;
  }

  /// Curvature of the input over the last step from three samples (divided differences).
  static double curvature(double u_pp, double u_p, double u_n, double h_prev, double h) {
    return 2.0 * ((u_n - u_p) / h - (u_p - u_pp) / h_prev) / (h + h_prev);
  }

  /// Third divided difference u[t_-3, t_-2, t_-1, t_0] from two consecutive curvatures
  /// (u'' over [t_-2, t_0] and over [t_-3, t_-1]) and the span t_0 - t_-3.
  static double third_difference(double u_dd, double u_dd_prev, double span) {
    return 0.5 * (u_dd - u_dd_prev) / span;
  }

  /// step() plus the response to the input's curvature u'' over the step.
  double step_curved(double u_prev, double u_new, double u_dd, double z) const {
    return step(u_prev, u_new, z) + w2_ * u_dd;
  }

  /// step_curved() plus the cubic term (set_step(h, hp) first); c3 from third_difference().
  double step_cubic(double u_prev, double u_new, double u_dd, double c3, double z) const {
    return step(u_prev, u_new, z) + w2_ * u_dd + w3_ * c3;
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
  double I_ = 0.0;  ///< int_0^h e^{-eps tau} tau (h - tau) dtau
  double hp_ = -1.0;
  double w3_ = 0.0;
  bool w3_valid_ = false;
};

/// Identification's input prefilter: two cascaded first-order low-passes w/(p + w) on v, r
/// and delta alike. A linear filter applied to every signal of x' = A x + B delta leaves
/// that equation as it is, so the estimate is not biased; it only takes the INS noise and
/// the first-order wave motion above w out of the equation error that decides arming
/// (docs/design.md, "The input prefilter"). Each stage is exact for an input held over the
/// step; the first sample after reset() sets both stages to steady state, so a restart adds
/// no transient of its own.
class InputPrefilter {
 public:
  using Vec3 = Eigen::Matrix<double, 3, 1>;

  /// w: bandwidth [rad/s]; 0 passes the inputs through.
  explicit InputPrefilter(double w = 0.0) : w_(w) {}

  bool enabled() const { return w_ > 0.0; }
  double bandwidth() const { return w_; }
  /// The next step() starts again at steady state.
  void reset() { started_ = false; }

  /// Filters x over the step dt [s] since the previous call (ignored after a reset);
  /// returns the output of the second stage.
  Vec3 step(double dt, const Vec3& x) {
    if (!enabled()) return x;
    if (!started_) {
      s1_ = x;
      s2_ = x;
      started_ = true;
      return s2_;
    }
    if (!(std::abs(dt - dt_) <= 1e-9 * dt)) {
      dt_ = dt;
      alpha_ = -std::expm1(-w_ * dt);
    }
    s1_ += alpha_ * (x - s1_);
    s2_ += alpha_ * (s1_ - s2_);
    return s2_;
  }

 private:
  double w_;
  double dt_ = -1.0;
  double alpha_ = 0.0;
  bool started_ = false;
  Vec3 s1_ = Vec3::Zero();
  Vec3 s2_ = Vec3::Zero();
};

}  // namespace usvfdi
