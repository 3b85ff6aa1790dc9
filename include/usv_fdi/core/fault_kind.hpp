// The kind of a fault (core/types.hpp FaultKind) from the residuals of the channel it was
// isolated to, over the isolation's classify_window: spikes or a noise rise from the energy
// of the whitened structured residual, bias, drift or scale from the shape of the cross
// residual (the fault's estimate), and the onset from the run of abnormal residuals before
// the raise. Pure functions of the histories the Isolator keeps. docs/design.md section 8.3.
#pragma once

#include <deque>
#include <utility>
#include <vector>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

/// (t [s], value) pairs, oldest first.
using TimedValues = std::deque<std::pair<double, double>>;

/// From a window of whitened structured residuals (unit variance when healthy): kSpikes
/// when the excess energy sits in one or two samples, kNoise when the energy has no
/// consistent sign, kUnknown when it is neither (the shape decides) or the window is empty.
FaultKind energy_kind(const std::vector<double>& whitened);

/// From the cross residual d (the fault's estimate plus noise) and the other observer's
/// estimate x of the channel, at the same times: the best of a step d = a + g 1(t >= tau)
/// (kBias), a hinge d = a + b max(0, t - tau) (kDrift) and a scale d = a + k x 1(t >= tau)
/// (kScale), each needing to beat the others clearly; kBias with fewer than 8 samples.
FaultKind shape_kind(const TimedValues& d, const TimedValues& x);

/// Whether the cross residual d since t_raise spreads without moving, against its spread
/// before (at least sigma_d): a noise rise rather than an offset.
bool noise_rise_like(const TimedValues& d, double t_raise, double sigma_d);

/// The start of the latest run of clearly abnormal (|s| > 2) whitened residuals s, walking
/// back from t over gaps of at most two quiet samples; t when there is none.
double abnormal_run_onset(const TimedValues& s, double t);

}  // namespace usvfdi
