// Plausibility of a replay's input and result: warnings that name the likely mistake.
//
// PlausibilityCheck watches every row and reports, at the end:
//   - a column with no value at all (every field empty or nan), or with most values missing;
//   - |delta| beyond any rudder's range (pi/2 rad = 90 deg) in at least 1 % of the rows:
//     probably degrees given where radians are expected; likewise |r| above pi/2 rad/s
//     (no vessel turns at 90 deg/s): probably deg/s;
//   - a median sample interval above 1.5 s: at a plausible INS rate (1 Hz .. 1 kHz) in
//     milliseconds (or microseconds), probably the time column's unit.
// Memory is bounded: the median is taken over the first kIntervals intervals.
// convergence_report() says why an estimate has not converged, from its fields.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "usv_fdi/core/identification.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi::io {

class PlausibilityCheck {
 public:
  static constexpr std::size_t kIntervals = 1001;            ///< intervals kept for the median
  static constexpr double kMaxRudder = 1.5707963267948966;   ///< pi/2 [rad]
  static constexpr double kMaxYawRate = 1.5707963267948966;  ///< pi/2 [rad/s]
  static constexpr double kMaxInterval = 1.5;  ///< median sample interval above this [s]

  /// Every row read (rejected ones too).
  void add(const Sample& s);
  /// One message per implausible finding, each naming the column, what was seen and the
  /// likely mistake; empty when nothing is implausible.
  std::vector<std::string> warnings() const;

 private:
  struct Column {
    std::uint64_t finite = 0;
    std::uint64_t beyond = 0;  ///< |x| above its plausible limit
    double max_abs = 0.0;
  };
  std::uint64_t rows_ = 0;
  Column v_, r_, delta_;
  double last_t_ = kNaN;
  std::vector<double> intervals_;
};

/// Why `est` has not converged ("" once it has): every criterion of the convergence test
/// that failed, with the value and the limit from `p` (e.g. "excitation 0.002 below
/// identification.min_excitation = 0.01: the rudder did not move enough").
std::string convergence_report(const Estimate& est, const IdentificationParams& p);

}  // namespace usvfdi::io
