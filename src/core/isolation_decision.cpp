// The Isolator's decision: the levels of the statistics against their thresholds, a
// candidate sensor chosen and confirmed over enter_time, a raised fault held or cleared,
// its kind refined (core/fault_kind.hpp), and the conditions turned into Detections
// (docs/design.md section 8.3).
#include "usv_fdi/core/isolation.hpp"

#include "isolation_internal.hpp"
#include "usv_fdi/core/fault_kind.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace usvfdi {

using isolation_detail::channel_sensor;
using isolation_detail::kEpsT;
using isolation_detail::sensor_index;

Detection Isolator::make_detection(Sensor sensor, bool active, FaultKind kind, double t) const {
  Detection d;
  d.sensor = sensor;
  d.active = active;
  d.kind = kind;
  d.c_a = st_.c_a;
  d.c_g = st_.c_g;
  d.threshold = sensor == Sensor::kUnknown ? st_.threshold : st_.thresholds(sensor_index(sensor));
  if (sensor == Sensor::kAccelerometer) {
    d.statistic = active ? st_.J(0) : st_.D(0);
  } else if (sensor == Sensor::kGyro) {
    d.statistic = active ? st_.J(1) : st_.D(1);
  } else {
    d.statistic = st_.J.maxCoeff();
  }
  d.detection_time = t;
  d.onset_time = t;
  return d;
}

void Isolator::set_condition(Sensor sensor, Source src, bool on, FaultKind kind, double t,
                             const std::string& message, std::vector<Detection>* out) {
  Condition& c = sens_[sensor_index(sensor)].cond;
  const unsigned before = c.sources;
  c.sources = on ? (c.sources | src) : (c.sources & ~src);
  if (before == 0 && c.sources != 0) {
    pending_stats_.clear();  // the samples before a raise are not healthy
    pending_drift_.clear();
    c.active = true;
    c.kind = kind;
    if (sensor != Sensor::kUnknown) start_monitor(sensor_index(sensor));
    Detection d = make_detection(sensor, true, kind, t);
    if (src == kResidual && sensor != Sensor::kUnknown) {
      d.onset_time = abnormal_run_onset(chan_[sensor_index(sensor)].hist_s, t);
    }
    d.message = message;
    out->push_back(d);
  } else if (before != 0 && c.sources == 0) {
    c.active = false;
    if (sensor != Sensor::kUnknown) {
      chan_[sensor_index(sensor)].resync = true;
      chan_[sensor_index(sensor)].mon_on = false;
    }
    Detection d = make_detection(sensor, false, c.kind, t);
    d.message = message;
    out->push_back(d);
  } else if (on && !(before & src) && (src & (kStuck | kStale | kInvalid)) &&
             !(before & (kStuck | kStale | kInvalid)) && c.kind != kind) {
    // A sensor-level check names the fault better than the residuals or a jump that raised
    // it first (a frozen output is stuck, whatever moved first).
    Detection d = make_detection(sensor, true, kind, t);
    d.update = true;
    d.message = std::string("kind refined from ") + to_string(c.kind) + " to " + to_string(kind) +
                ": " + message;
    c.kind = kind;
    if (sensor != Sensor::kUnknown) chan_[sensor_index(sensor)].refine_at = kNaN;
    out->push_back(d);
  }
}

void Isolator::start_monitor(int ch) {
  // The observer in force is not reconfigured yet (that starts with the next step): the
  // monitor continues it, driven by its own sensor.
  chan_[ch].mon = ch == kV ? act_.v : act_.g;
  chan_[ch].mon_on = chan_[ch].mon.ready();
  chan_[ch].win_m = Window{};
  chan_[ch].win_ms = Window{};
  chan_[ch].mon_sign = act_.win_sl[ch].mean() < 0 ? -1.0 : 1.0;
  // After a constant fault f ends, the monitor's residual is c Ad^k e_ss, e_ss = -(I -
  // Ad)^-1 L f its steady error: with g_k = c Ad^k (I - Ad)^-1 L >= 0 for all k (real
  // poles; checked here) that transient opposes the fault, so a residual in the fault's
  // direction is the fault itself, never its aftermath.
  chan_[ch].mon_ok = false;
  const Mat2 Ad = chan_[ch].mon.Ad();
  const Mat2 I_Ad = Mat2::Identity() - Ad;
  if (chan_[ch].mon_on && std::abs(I_Ad.determinant()) > 1e-12 && chan_[ch].mon.Gy().allFinite()) {
    Vec2 e = I_Ad.partialPivLu().solve(chan_[ch].mon.Gy());
    const double e0 = e.norm();
    double lo = 0.0, hi = 0.0;
    for (int k = 0; k < 100000 && e.norm() > 1e-9 * e0; ++k) {
      lo = std::min(lo, e(ch));
      hi = std::max(hi, e(ch));
      e = Ad * e;
    }
    chan_[ch].mon_ok = e0 > 0 && lo >= -1e-3 * hi;
  }
}

void Isolator::refine_kinds(double t, std::vector<Detection>* out) {
  // Refine the kind once more data after the raise shows the fault's shape.
  for (int k = 0; k < 2; ++k) {
    if (std::isnan(chan_[k].refine_at) || t < chan_[k].refine_at) continue;
    chan_[k].refine_at = kNaN;
    Condition& c = sens_[k].cond;
    if (!(c.sources & kResidual)) continue;
    if (c.kind != FaultKind::kBias && c.kind != FaultKind::kDrift && c.kind != FaultKind::kScale) {
      continue;
    }
    // Half a classification window of the fault decides better than the raise's window (a
    // noise increase can look offset over the raise's few samples).
    const FaultKind refined = noise_rise_like(chan_[k].hist_d, sens_[k].raised_at, act_.sigma_d(k))
                                  ? FaultKind::kNoise
                                  : shape_kind(chan_[k].hist_d, chan_[k].hist_x);
    if (refined == c.kind) continue;
    Detection d = make_detection(static_cast<Sensor>(k), true, refined, t);
    d.update = true;
    d.message = std::string("kind refined from ") + to_string(c.kind) + " to " + to_string(refined);
    c.kind = refined;
    out->push_back(d);
  }
}

Isolator::Levels Isolator::levels(double t, double dt) const {
  // Residual evaluation with hysteresis, each channel against its own thresholds.
  Levels lv;
  lv.thr = st_.thresholds;
  lv.n_full = window_samples(dt);
  lv.ratio = st_.J.cwiseQuotient(lv.thr);  // > 1: above the enter threshold
  for (int c = 0; c < 2; ++c) {
    // refilling or settling after a fault cleared
    if (act_.win_s[c].size() < lv.n_full || t < chan_[c].resettle_until) {
      lv.ratio(c) = 0.0;
      lv.live[c] = false;
    }
  }
  lv.thr_exit_d = p_.exit_ratio * st_.thresholds_d;
  return lv;
}

void Isolator::await_onsets(Levels* lv) {
  // A channel whose statistic is above its bar from the moment detection went live has shown
  // no onset: nothing began that a sensor fault would have begun. It is what the model does
  // not hold in what the vessel was doing when it armed (the Otter armed in a zigzag, its yaw
  // residual pegged for a minute before arming, was raised 1.5 enter_time after it: 7 of the
  // proving ground's 46 false alarms). Such a channel raises nothing until it has been seen
  // at or below its bar once, as while it settles. A rise that began from a quiet learning
  // window within onset_lookback before going live is an onset all the same
  // (onset_before_live): the paper's gyro bias starts at 20.0 s, 0.9 s before learning ends.
  for (int c = 0; c < 2; ++c) {
    if (lv->live[c] && (lv->ratio(c) <= 1.0 || act_.onset_in_learning[c]))
      chan_[c].onset_seen = true;
    st_.awaiting_onset[c] = lv->live[c] && !chan_[c].onset_seen;
    if (!chan_[c].onset_seen) {
      lv->ratio(c) = 0.0;
      lv->live[c] = false;
    }
  }
}

Isolator::Candidate Isolator::choose_candidate(double t, const Levels& lv) {
  const bool a_res = sens_[0].cond.sources & kResidual, g_res = sens_[1].cond.sources & kResidual,
             u_res = sens_[2].cond.sources & kResidual;
  Candidate c;
  if (st_.model_mismatch) {
    // Detection resumes once the model holds again: every statistic below its leave
    // threshold for leave_time (and the verdict at least min_active_time old).
    const bool quiet = (st_.J.array() <= p_.exit_ratio * lv.thr.array()).all() &&
                       (st_.D.array() <= lv.thr_exit_d.array()).all();
    if (!quiet) {
      below_mm_since_ = kNaN;
    } else {
      if (std::isnan(below_mm_since_)) below_mm_since_ = t;
      if (t - below_mm_since_ + kEpsT >= p_.leave_time &&
          t - mismatch_since_ + kEpsT >= p_.min_active_time) {
        st_.model_mismatch = false;
        st_.mismatch_reason.clear();
        // A repeated rise's verdict keeps the suspicion on its channel going.
        if (mismatch_repeated_ >= 0) sens_[mismatch_repeated_].unheld_at = t;
        below_mm_since_ = kNaN;
      }
    }
  } else if (!a_res && !g_res && !u_res) {
    if (lv.ratio.maxCoeff() > 1.0) {
      if (st_.c_a >= p_.c_min && st_.c_a - st_.c_g >= p_.c_margin) {
        c.k = 0;
      } else if (st_.c_g >= p_.c_min && st_.c_g - st_.c_a >= p_.c_margin) {
        c.k = 1;
      } else {
        c.k = 2;  // both channels at once: the evidence singles out no sensor
      }
      // The same channel again, its rise begun soon after a raise that nothing held (a rise
      // that began in time stays one to its confirmation), and its cross residual showing
      // no fault: the model's mismatch.
      if (c.k < 2 && st_.D(c.k) <= lv.thr_exit_d(c.k) &&
          (t - sens_[c.k].unheld_at <= p_.mismatch_window || repeat_rise_ == c.k)) {
        c.repeated = c.k;
        c.k = 2;
      }
    }
  } else if (!u_res && a_res != g_res) {
    // One sensor raised: the other channel's structured residual is blind to its fault, so
    // a single sensor fault never lights it. Soon after the raise, it rising too says the
    // model, not the raised sensor, is wrong (the raise is withdrawn); later it is a second
    // fault, on its own channel.
    const int raised = a_res ? 0 : 1, other = 1 - raised;
    if (lv.ratio(other) > 1.0) {
      if (t - sens_[raised].raised_at <= p_.mismatch_window) {
        c.k = 2;
        c.reclassify = raised;
      } else {
        c.k = other;
      }
    }
  }
  repeat_rise_ = c.repeated;  // any other candidate (or none) ends the repeated rise
  return c;
}

void Isolator::confirm_candidate(double t, const Levels& lv, const Candidate& c,
                                 std::vector<Detection>* out) {
  const bool a_res = sens_[0].cond.sources & kResidual, g_res = sens_[1].cond.sources & kResidual;
  // (a sensor another check already raised, a jump for one, needs no longer confirmation)
  // (c.k is -1 when nothing is a candidate: no sensor to look at)
  const bool raised = c.k >= 0 && c.k < 2 && sens_[c.k].cond.sources != 0;
  const double own = raised ? p_.enter_time : sensor_enter_time();
  const double enter = c.k == 2           ? p_.enter_time
                       : (a_res || g_res) ? std::max(own, p_.second_fault_time)
                                          : own;
  for (int k = 0; k < 3; ++k) {
    if (k != c.k) {
      sens_[k].above_since = kNaN;
      continue;
    }
    if (std::isnan(sens_[k].above_since)) sens_[k].above_since = t;
    if (t - sens_[k].above_since + kEpsT < enter) continue;
    sens_[k].above_since = kNaN;
    if (k == 2) {
      // Model mismatch: a status with its reason, counted; never a latched sensor fault.
      const char* after = "";
      if (c.reclassify >= 0) {
        after = c.reclassify == 0 ? " after an accelerometer raise" : " after a gyro raise";
      } else if (c.repeated >= 0) {
        after = c.repeated == 0 ? " soon after an accelerometer raise that nothing held"
                                : " soon after a gyro raise that nothing held";
      }
      char buf[160];
      std::snprintf(
          buf, sizeof buf, "%s (J_N %.3g / %.3g against %.3g / %.3g)%s",
          c.repeated >= 0 ? "residual of one channel again" : "residuals of both channels",
          st_.J(0), st_.J(1), lv.thr(0), lv.thr(1), after);
      st_.model_mismatch = true;
      // (the statistics before the verdict stay pending for the healthy maxima: the rise
      // that led to it is the model's too)
      pending_drift_.clear();
      st_.mismatch_reason = buf;
      ++st_.mismatches;
      mismatch_since_ = t;
      mismatch_repeated_ = c.repeated;
      below_mm_since_ = kNaN;
      if (c.reclassify >= 0) {
        chan_[c.reclassify].refine_at = kNaN;
        set_condition(static_cast<Sensor>(c.reclassify), kResidual, false,
                      sens_[c.reclassify].cond.kind, t,
                      std::string("withdrawn: model mismatch, not a sensor fault: ") + buf, out);
        sens_[c.reclassify].below_since = kNaN;
      }
      continue;
    }
    const Sensor sensor = static_cast<Sensor>(k);
    const FaultKind kind = classify(k);
    chan_[k].refine_at = t + 0.5 * p_.classify_window;
    const std::string msg = std::string("residual of the ") + (k == 0 ? "accelerometer" : "gyro") +
                            " channel: J_N " + std::to_string(st_.J(k)) + " > " +
                            std::to_string(lv.thr(k));
    set_condition(sensor, kResidual, true, kind, t, msg, out);
    sens_[k].raised_at = t;
    sens_[k].below_since = kNaN;
  }
}

void Isolator::hold_or_clear(double t, const Levels& lv, int c, std::vector<Detection>* out) {
  // Hold / clear. While sensor i is faulty its dedicated observer is reconfigured (driven by
  // the other observer), so its structured entry takes the cross residual's scale; the cross
  // residual d_i = y_i - x_i(observer blind to i) carries the fault without absorption.
  for (int k = 0; k < 3; ++k) {
    if (!(sens_[k].cond.sources & kResidual) || k == c) continue;
    // The reconfigured observer's structured entry has about the cross residual's scale.
    const double rescale =
        k < 2 ? std::min(1.0, std::pow(st_.sigma_s(k) / st_.sigma_d(k), 2.0)) : 1.0;
    // In units of the leave threshold: below 1 the condition may clear.
    double hold = k < 2 ? std::max(st_.D(k), rescale * st_.J(k)) / lv.thr_exit_d(k)
                        : lv.ratio.maxCoeff() / p_.exit_ratio;
    if (k < 2) {
      // The monitor sees the fault with the structured residual's small noise: its offset
      // in the fault's direction (a fault that ended leaves an offset against it), or for
      // zero-mean faults its energy (their aftermath is as short as the observer's memory
      // of the noise). A scale error changes sign with the signal: the cross residual holds.
      if (chan_[k].mon_on && chan_[k].mon_ok && chan_[k].win_m.size() >= lv.n_full) {
        hold = std::max(hold, st_.M(k) / (p_.exit_ratio * lv.thr(k)));
      }
    }
    const double leave = k < 2 ? lv.thr_exit_d(k) : p_.exit_ratio * lv.thr.maxCoeff();
    if (hold < 1.0) {
      if (std::isnan(sens_[k].below_since)) sens_[k].below_since = t;
      if (t - sens_[k].below_since + kEpsT >= p_.leave_time &&
          t - sens_[k].raised_at + kEpsT >= p_.min_active_time) {
        // Cleared as soon as it could be: nothing held it (a residual raise only). The clear
        // restarts the channel's observer, which settles for settle_time: the window for the
        // channel's coming back counts from then.
        const bool unheld = k < 2 && sens_[k].cond.sources == kResidual &&
                            t - sens_[k].raised_at <= p_.min_active_time + p_.leave_time + kEpsT;
        if (unheld) sens_[k].unheld_at = t + settle_time_;
        set_condition(static_cast<Sensor>(k), kResidual, false, sens_[k].cond.kind, t,
                      "residual back below " + std::to_string(leave), out);
        sens_[k].below_since = kNaN;
      }
    } else {
      sens_[k].below_since = kNaN;
    }
  }
}

void Isolator::reset_drift(double t) {
  drift_hi_.fill(0.0);
  drift_lo_.fill(0.0);
  drift_from_hi_.fill(t);
  drift_from_lo_.fill(t);
  st_.drift_S = Vec2::Zero();
}

void Isolator::drift_checks(double t, double dt, const Statistics& x, bool learn_ok,
                            const Levels& lv, std::vector<Detection>* out) {
  // The CUSUMs run while nothing is raised, the model holds and the observers are live;
  // anything else starts them again from zero (a fault's evidence was used by its raise,
  // and a model mismatch is not a drift).
  // Samples the test did not see (a gap, settling, no rudder: residual_checks returned
  // before it) start it again too.
  bool any = false;
  for (const SensorState& x_s : sens_) any = any || x_s.cond.active;
  const bool run = p_.drift_check && model_live() && !any && !st_.model_mismatch &&
                   t - t_last_fault_ >= p_.resume_after_fault && dt > 0 &&
                   !(t - drift_last_t_ > p_.stale_timeout) && !(t < chan_[0].resettle_until) &&
                   !(t < chan_[1].resettle_until);
  st_.drift_threshold = Vec2::Zero();
  if (!run) {
    reset_drift(t);
    pending_drift_.clear();
    drift_last_t_ = t;
    return;
  }
  // A sample with an unusable channel is skipped (held), not a reason to start again.
  if (!x.sw.allFinite()) return;
  drift_last_t_ = t;
  double S[2];
  for (int c = 0; c < 2; ++c) {
    const double w = std::max(-p_.clip, std::min(x.sw(c), p_.clip));
    drift_hi_[c] = std::max(0.0, drift_hi_[c] + (w - p_.drift_k) * dt);
    drift_lo_[c] = std::max(0.0, drift_lo_[c] + (-w - p_.drift_k) * dt);
    if (drift_hi_[c] == 0.0) drift_from_hi_[c] = t;
    if (drift_lo_[c] == 0.0) drift_from_lo_[c] = t;
    S[c] = std::max(drift_hi_[c], drift_lo_[c]);
  }
  st_.drift_S = Vec2(S[0], S[1]);
  // Healthy maxima from values drift_lag old: a drift's own rise stays out of its bar.
  pending_drift_.push_back(PendingDrift{t, {S[0], S[1]}, learn_ok});
  while (!pending_drift_.empty() && t - pending_drift_.front().t > p_.drift_lag) {
    if (pending_drift_.front().ok) {
      drift_healthy_.add(pending_drift_.front().t, pending_drift_.front().x);
    }
    pending_drift_.pop_front();
  }
  if (drift_healthy_.empty() || drift_healthy_.covered() < p_.drift_min_history) return;
  Vec2 ratio;
  for (int c = 0; c < 2; ++c) {
    st_.drift_threshold(c) =
        std::max(p_.drift_threshold, p_.history_margin * drift_healthy_.extrapolated_max(c));
    ratio(c) = S[c] / st_.drift_threshold(c);
  }
  const int c = ratio(0) >= ratio(1) ? 0 : 1;
  // Channel j (the other) is blind to a fault of sensor c: its CUSUM and J_N stay quiet.
  if (!(ratio(c) > 1.0) || ratio(1 - c) > p_.exit_ratio || lv.ratio(1 - c) > p_.exit_ratio) {
    return;
  }
  const Vec2 e = ratio.cwiseSqrt();
  const double ca = e(0) / e.norm(), cg = e(1) / e.norm();
  const double ci = c == 0 ? ca : cg, co = c == 0 ? cg : ca;
  if (ci < p_.c_min || ci - co < p_.c_margin) return;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s channel drifts: CUSUM %.3g > %.3g (the other channel %.3g)",
                c == 0 ? "accelerometer" : "gyro", S[c], st_.drift_threshold(c), S[1 - c]);
  const std::size_t before = out->size();
  // The kind from the residuals' shape like any residual raise (a scale error on a slowly
  // turning vessel, or a small offset, also pile up in the CUSUM), refined later.
  const FaultKind kind = classify(c);
  set_condition(channel_sensor(c), kResidual, true,
                kind == FaultKind::kUnknown ? FaultKind::kDrift : kind, t, buf, out);
  if (out->size() > before && out->back().active) {
    Detection& d = out->back();
    d.statistic = S[c];
    d.threshold = st_.drift_threshold(c);
    d.c_a = ca;
    d.c_g = cg;
    // The onset: when the side of the CUSUM that raised last left zero.
    d.onset_time = drift_hi_[c] >= drift_lo_[c] ? drift_from_hi_[c] : drift_from_lo_[c];
  }
  sens_[c].raised_at = t;
  sens_[c].below_since = kNaN;
  chan_[c].refine_at = t + 0.5 * p_.classify_window;
  reset_drift(t);
}

FaultKind Isolator::classify(int ch) const {
  // Stuck: the channel repeats its value exactly (a healthy, noisy sensor never does).
  if (checks_.repeats(ch) >= 2) return FaultKind::kStuck;
  const Window& w = act_.win_sl[ch];
  if (w.empty()) return FaultKind::kUnknown;
  std::vector<double> whitened(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) whitened[i] = w.at(i);
  const FaultKind by_energy = energy_kind(whitened);
  if (by_energy != FaultKind::kUnknown) return by_energy;
  return shape_kind(chan_[ch].hist_d, chan_[ch].hist_x);
}

}  // namespace usvfdi
