#include "usv_fdi/io/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace usvfdi::io {
namespace {

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

std::string percent(std::uint64_t n, std::uint64_t of) {
  return format("%.1f %%", 100.0 * static_cast<double>(n) / static_cast<double>(of));
}

}  // namespace

void PlausibilityCheck::add(const Sample& s) {
  ++rows_;
  const auto watch = [](Column* c, double x, double limit) {
    if (!std::isfinite(x)) return;
    ++c->finite;
    c->max_abs = std::max(c->max_abs, std::abs(x));
    if (std::abs(x) > limit) ++c->beyond;
  };
  watch(&v_, s.v, INFINITY);
  watch(&r_, s.r, kMaxYawRate);
  watch(&delta_, s.delta, kMaxRudder);
  if (!std::isfinite(s.t)) return;
  if (std::isfinite(last_t_) && s.t > last_t_ && intervals_.size() < kIntervals) {
    intervals_.push_back(s.t - last_t_);
  }
  if (!std::isfinite(last_t_) || s.t > last_t_) last_t_ = s.t;
}

std::vector<std::string> PlausibilityCheck::warnings() const {
  std::vector<std::string> out;
  if (rows_ == 0) return out;
  const std::string rows = std::to_string(rows_);
  const struct {
    const char* name;
    const Column& c;
    const char* role;
  } columns[] = {
      {"v", v_, "the sway velocity [m/s]"},
      {"r", r_, "the yaw rate [rad/s]"},
      {"delta", delta_, "the rudder angle [rad]"},
  };
  for (const auto& col : columns) {
    const std::uint64_t missing = rows_ - col.c.finite;
    if (col.c.finite == 0) {
      out.push_back(std::string("column '") + col.name + "': no value in any of the " + rows +
                    " rows (every field empty or nan); it must hold " + col.role +
                    ": identification and isolation cannot work without it");
    } else if (2 * missing > rows_) {
      out.push_back(std::string("column '") + col.name + "': " + std::to_string(missing) + " of " +
                    rows + " values (" + percent(missing, rows_) + ") missing (empty or nan)");
    }
  }
  // At least 1 % of the values beyond the limit: a unit, not a few wild values.
  if (delta_.beyond > 0 && 100 * delta_.beyond >= delta_.finite) {
    out.push_back("column 'delta': |delta| reaches " + format("%.4g", delta_.max_abs) + " rad (" +
                  format("%.0f", delta_.max_abs * 180.0 / M_PI) + " deg) and exceeds " +
                  format("%.4g", kMaxRudder) + " rad (90 deg, beyond any rudder's range) in " +
                  percent(delta_.beyond, delta_.finite) +
                  " of the rows: the column is probably in degrees (" +
                  format("%.4g deg = %.4g rad", delta_.max_abs, delta_.max_abs * M_PI / 180.0) +
                  "); the engine expects radians");
  }
  if (r_.beyond > 0 && 100 * r_.beyond >= r_.finite) {
    out.push_back("column 'r': |r| reaches " + format("%.4g", r_.max_abs) + " rad/s and exceeds " +
                  format("%.4g", kMaxYawRate) +
                  " rad/s (90 deg/s, beyond any vessel's turn rate) in " +
                  percent(r_.beyond, r_.finite) +
                  " of the rows: the column is probably in degrees per second; the engine expects "
                  "rad/s");
  }
  if (intervals_.size() >= 3) {
    std::vector<double> d = intervals_;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    const double median = d[d.size() / 2];
    if (median > kMaxInterval) {
      std::string m = "column 't': the median sample interval is " + format("%.4g", median) +
                      " s (" + format("%.3g", 1.0 / median) + " Hz)";
      if (median * 1e-3 >= 1e-3 && median * 1e-3 <= 1.0) {
        m += ": the column is probably in milliseconds (" +
             format("%.4g ms = %.4g Hz", median, 1e3 / median) + "); the engine expects seconds";
      } else if (median * 1e-6 >= 1e-3 && median * 1e-6 <= 1.0) {
        m += ": the column is probably in microseconds (" +
             format("%.4g us = %.4g Hz", median, 1e6 / median) + "); the engine expects seconds";
      } else {
        m += ": far too slow for the observers; the engine expects seconds";
      }
      out.push_back(m);
    }
  }
  return out;
}

std::string convergence_report(const Estimate& est, const IdentificationParams& p) {
  if (est.converged) return "";
  std::string s = to_string(est.status);
  std::vector<std::string> why;
  if (est.warming_up) {
    why.push_back(
        "the filters need identification.warmup_time of continuous valid data; a gap above "
        "identification.max_gap = " +
        format("%g", p.max_gap) + " s or an invalid sample restarts them");
  }
  if (est.frozen) why.push_back("identification was frozen at the end (a fault suspected)");
  if (est.excitation < p.min_excitation) {
    why.push_back(
        format("excitation %.3g below identification.min_excitation = %g: the rudder did "
               "not move v and r independently enough (delta constant, missing or too "
               "small, or the recording too short)",
               est.excitation, p.min_excitation));
  }
  if (!(est.settling < p.settle_tolerance)) {
    why.push_back(
        format("the estimate still moved by %.3g %% per window (identification."
               "settle_tolerance = %g %%)",
               100.0 * est.settling, 100.0 * p.settle_tolerance));
  }
  if (p.method == IdentMethod::kKreisselmeier) {
    const bool prediction = p.precision == Precision::kPrediction;
    const double limit = prediction ? p.max_prediction_error : p.max_std_error;
    if (!std::isfinite(est.uncertainty)) {
      why.push_back("standard errors not known yet (fewer than three batches of data)");
    } else if (est.uncertainty > limit || est.status == IdentStatus::kImprecise) {
      if (prediction) {
        why.push_back(
            format("the standard errors of A allow an error of %.3g %% in the model's "
                   "prediction (its upper 90 %% confidence bound must be below "
                   "identification.max_prediction_error = %g %%)",
                   100.0 * est.uncertainty, 100.0 * limit));
      } else {
        // Name the a_n whose relative standard error is the largest.
        int worst_n = 0;
        double worst = -1.0;
        for (int n = 0; n < 4; ++n) {
          const double rel =
              est.std_error(n) / std::max(std::abs(to_params(est.A)(n)), p.settle_floor);
          if (rel > worst) {
            worst = rel;
            worst_n = n;
          }
        }
        why.push_back(
            format("the largest standard error, of a%.0f, is %.3g %% of its value (its "
                   "upper 90 %% confidence bound must be below identification."
                   "max_std_error = %g %%)",
                   worst_n + 1.0, 100.0 * worst, 100.0 * limit));
      }
    }
  }
  if (est.status == IdentStatus::kUncertain) {
    why.push_back(format("it had converged, and lost convergence %.0f time(s) since: its "
                         "uncertainty stayed above identification.uncertain_ratio = %g times "
                         "its limit for identification.uncertain_time = %g s",
                         static_cast<double>(est.unconvergences), p.uncertain_ratio,
                         p.uncertain_time) +
                  " (the data no longer supported it; isolation.on_lost_convergence says what "
                  "detection does meanwhile, by default it is off)");
  }
  if (!est.consistent || est.inconsistent_time > 0.0) {
    why.push_back(
        format("the data contradicted the memory for the last %.3g s (consistency "
               "statistic %.3g, identification.guard_threshold = %g)",
               est.inconsistent_time, est.consistency, p.guard_threshold));
  }
  for (const std::string& w : why) s += "; " + w;
  return s;
}

}  // namespace usvfdi::io
