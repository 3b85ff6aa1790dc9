// The vessel's speed as a scale of its dynamics (docs/design.md section 8.5).
//
// In the linear sway-yaw model with non-dimensional derivatives (v' = v/U, r' = r L/U,
// t' = t U/L), every entry of A grows with the speed U and both entries of B with U^2:
//   x' = s A0 x + s^2 B0 delta,   s = U / U0,
// A0 and B0 the matrices at the reference speed U0, the speed B is given at. With a speed
// input the engine identifies A0 (the regressor is s x, the known input s^2 B0 delta), and
// its observers run on A0 in the vessel's own time, t' = s t, with the input s delta: a
// change of speed is then no change of the model. Without one, s = 1 throughout.
#pragma once

#include <cmath>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

struct SpeedParams {
  /// U0, the surge speed at which model.B is given [m/s]; 0: the first measured speed.
  double reference_speed = 0.0;
  double min_ratio = 0.25;  ///< s is clamped to [min_ratio, max_ratio] [-]
  double max_ratio = 4.0;   ///< (a log that reads 0 or far too much cannot stop the model)
  /// The observers re-discretise their model when their step s dt moved by more than this
  /// (relative) since the last time, and correct it to first order in between (each
  /// re-discretisation is three 4x4 matrix exponentials); identification's instruments
  /// take s in steps of this [-]
  double quantum = 0.005;
  /// k in B = s^k B0: 2 for a rudder in the free stream; less where the propeller race,
  /// at constant propeller speed, keeps the rudder's inflow up as the vessel slows [-]
  double input_exponent = 2.0;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// s = u / U0 per sample: held over samples without a speed value, 1 before the first one.
class SpeedRatio {
 public:
  explicit SpeedRatio(const SpeedParams& p) : p_(p) { p_.validate(); }
  /// The ratio for this sample (u NaN: the last one).
  double update(const Sample& s) {
    if (std::isfinite(s.u)) {
      if (!(u0_ > 0)) u0_ = p_.reference_speed > 0 ? p_.reference_speed : std::abs(s.u);
      if (u0_ > 0) {
        ratio_ = std::min(p_.max_ratio, std::max(p_.min_ratio, s.u / u0_));
        measured_ = true;
      }
    }
    return ratio_;
  }
  double ratio() const { return ratio_; }
  /// s^k, the factor of B at ratio s (input_exponent k).
  double input_factor(double s) const {
    return p_.input_exponent == 2.0 ? s * s : std::pow(s, p_.input_exponent);
  }
  /// The reference speed in use [m/s] (NaN before the first speed value).
  double reference_speed() const { return u0_ > 0 ? u0_ : kNaN; }
  bool measured() const { return measured_; }
  const SpeedParams& params() const { return p_; }

 private:
  SpeedParams p_;
  double u0_ = 0.0;
  double ratio_ = 1.0;
  bool measured_ = false;
};

}  // namespace usvfdi
