// The Isolator's observer banks: their design on an estimate of A, propagation and restarts,
// the residuals' learned scales and thresholds, the windowed statistics J_N and D_N, the
// monitors, the confidences and the spikes (docs/design.md section 8.3).
#include "usv_fdi/core/isolation.hpp"

#include "isolation_internal.hpp"
#include "usv_fdi/core/robust.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace usvfdi {

using isolation_detail::channel_sensor;
using isolation_detail::prune;
using isolation_detail::within;

namespace {

/// Time after a restart from the measurements until the restart's transient has faded
/// from the observer's residual: the initial error is the noise of the measurements it
/// was restarted from (up to 3 sigma in either state, either sign), and its residual c e_k
/// (e_{k+1} = Ad e_k, steps of dt) must stay below half a sigma of the channel's residual
/// from then on. The unmeasured state's error reaches the residual only through the
/// coupling (and is corrected as slowly): for a weak coupling against noisy data this
/// takes longer than the settling after arming, which learning follows.
double restart_transient(const DedicatedObserver& o, double dt, const Vec2& sigma) {
  const int c = o.channel();
  const int horizon = static_cast<int>(std::ceil(120.0 / dt));
  int last_above = -1;
  for (const double sv : {-1.0, 1.0}) {
    Vec2 e(3.0 * sigma(0), sv * 3.0 * sigma(1));
    for (int k = 0; k < horizon; ++k) {
      if (!e.allFinite()) return 120.0;
      if (std::abs(e(c)) > 0.5 * sigma(c)) last_above = k;
      e = o.Ad() * e;
    }
  }
  return last_above < 0 ? 0.0 : (last_above + 1) * dt;
}

}  // namespace

bool Isolator::design(const Mat2& A, Bank* b) {
  const double sv = scales_configured_ ? p_.sigma_v : 10.0 * p_.sigma_floor_v;
  const double sr = scales_configured_ ? p_.sigma_r : 10.0 * p_.sigma_floor_r;
  const ObserverDesign dv =
      place_poles(A, kV, p_.poles_v(0), p_.poles_v(1), sv, sr, p_.min_observability);
  const ObserverDesign dg =
      place_poles(A, kR, p_.poles_g(0), p_.poles_g(1), sv, sr, p_.min_observability);
  if (!dv.ok || !dg.ok) {
    st_.observer_problem = !dv.ok ? dv.reason : dg.reason;
    return false;
  }
  st_.observer_problem.clear();
  *b = Bank{};
  b->v.set_channel(kV);
  b->g.set_channel(kR);
  b->v.set_design(dv, B_);
  b->g.set_design(dg, B_);
  const double band = speed_.measured() ? speed_.params().quantum : 0.0;
  b->v.set_step_band(band);
  b->g.set_step_band(band);
  b->A = A;
  b->k_v = dv.k;
  b->k_g = dg.k;
  b->floor_s = b->floor_d = Vec2(p_.sigma_floor_v, p_.sigma_floor_r);
  b->theory_scales_pending = scales_configured_;
  return true;
}

double Isolator::sensor_enter_time() const {
  return healthy_.covered() < p_.history ? p_.young_enter_ratio * p_.enter_time : p_.enter_time;
}

double Isolator::history_lag() const {
  return p_.window + std::max(sensor_enter_time(), p_.second_fault_time) + 1.0;
}

void Isolator::publish_bank() {
  st_.A_design = act_.A;
  st_.k_v = act_.k_v;
  st_.k_g = act_.k_g;
  st_.sigma_s = act_.sigma_s;
  st_.sigma_d = act_.sigma_d;
  st_.thresholds = act_.threshold;
  st_.thresholds_d = act_.threshold_d;
  if (!healthy_.empty()) {
    for (int c = 0; c < 2; ++c) {
      st_.thresholds(c) =
          std::max(st_.thresholds(c), history_threshold(healthy_.extrapolated_max(c)));
      st_.thresholds_d(c) =
          std::max(st_.thresholds_d(c), history_threshold(healthy_.extrapolated_max(2 + c)));
    }
  }
  for (int c = 0; c < 2; ++c) {
    st_.bar_unreachable[c] = act_.learned && st_.thresholds(c) >= p_.clip * p_.clip;
  }
  st_.threshold = act_.threshold.maxCoeff();
  st_.threshold_d = act_.threshold_d.maxCoeff();
  st_.relearning = has_shadow_;
}

void Isolator::restart_learning(Bank* b) {
  b->learned_time = 0.0;
  b->scales_learned = false;
  for (auto& v : b->learn_raw) std::vector<double>().swap(v);
  for (auto& v : b->learn_J) std::vector<double>().swap(v);
  for (auto& v : b->learn_D) std::vector<double>().swap(v);
  // Its windows too: they hold samples from before the raise, whitened by the scales just
  // forgotten, and would be the first of the next learning.
  for (int c = 0; c < 2; ++c) b->clear_windows(c);
}

double Isolator::reachable_threshold() const { return 0.75 * p_.clip * p_.clip; }

double Isolator::learned_threshold(std::vector<double>* healthy) const {
  // The median, the MAD about it and the 99.9 % quantile (the value a sort would put at rank
  // n 999/1000), by selection: this runs at every relearning.
  const double med = median_in_place(healthy);
  std::vector<double> dev;
  const double sd = robust_std_about(*healthy, med, &dev);
  const double q999 =
      healthy->empty() ? 0.0 : upper_rank_after_median(healthy, healthy->size() * 999 / 1000);
  // A windowed mean of clipped squares cannot exceed clip^2: keep the threshold reachable.
  return std::min(std::max({p_.threshold, med + p_.threshold_k * sd, p_.threshold_margin * q999}),
                  reachable_threshold());
}

bool onset_before_live(const std::vector<double>& J, std::size_t back, double threshold) {
  // J_N at or below the threshold within the last `back` samples, and the samples before
  // them quiet (at most 1 % above it): a rise began from a quiet state just before going
  // live (the paper's gyro bias 0.9 s before). A channel the waves take over the threshold
  // again and again while it learns (the 3-DOF Otter in sea state 3: pegged at the clip
  // every few seconds, its threshold capped at 0.75 clip^2) has no quiet state to begin from.
  if (J.empty()) return false;
  const std::size_t from = J.size() > back ? J.size() - back : 0;
  bool below = false;
  for (std::size_t i = from; i < J.size(); ++i) below = below || J[i] <= threshold;
  std::size_t above = 0;
  for (std::size_t i = 0; i < from; ++i) above += J[i] > threshold ? 1 : 0;
  return below && 100 * above <= from;
}

double history_bar(double healthy_max, double margin, double clip) {
  // A windowed mean of clipped squares saturates at clip^2; a bar at or above it made the
  // channel blind without a word (a gyro drift of 10 sigma in 10 s on the Otter was never
  // raised, J at 16 against 16.1). So the bar is margin x the maximum only up to a knee that
  // leaves the statistic a quarter of the bar above it (0.8 clip^2); above it the bar is the
  // larger of the knee and kMinHistoryMargin x the maximum: a fault that pegs the statistic
  // is seen.
  // (Before, margin x the maximum ran on to 0.98 clip^2 and then fell to 0.75 clip^2: with
  // clip 4 and a margin of 1.5 the bar dropped from 15.7 to 12 as the maximum rose past
  // 10.45, and the drop restarted the confirmation of a rising gyro drift. Knees of 0.75,
  // 0.85 and 0.9 clip^2 each fail a guard test: docs/benchmark.md, "The history bar".)
  constexpr double kMinHistoryMargin = 1.05;
  const double knee = 0.8 * clip * clip;
  const double bar = margin * healthy_max;
  if (bar <= knee) return bar;
  return std::max(knee, kMinHistoryMargin * healthy_max);
}

double Isolator::history_threshold(double healthy_max) const {
  return history_bar(healthy_max, p_.history_margin, p_.clip);
}

std::size_t Isolator::window_samples(double dt) const {
  const double n = dt > 0 ? std::round(p_.window / dt) : p_.min_window_samples;
  return static_cast<std::size_t>(std::max<double>(n, p_.min_window_samples));
}

void Isolator::propagate(Bank* b, const Sample& s, double dt, bool v_ok, bool r_ok,
                         const Vec2& rudder) {
  if (dt > p_.stale_timeout) {
    // A gap: restart the observers from the measurements and let them settle again (the
    // monitors stop: the cross residual alone holds a raised fault after a gap).
    for (ChannelState& c : chan_) c.mon_on = false;
    const Vec2 y0(v_ok ? s.v : b->v.x()(0), r_ok ? s.r : b->g.x()(1));
    b->v.reset(y0);
    b->g.reset(y0);
    // Detection pauses until that restart has settled (at least settle_time): the step
    // length of the observers' discretisation is the sample interval before the gap.
    const Vec2 sigma = b->scales_learned ? b->sigma_s : b->floor_s;
    double settle = settle_time_;
    if (b->v.dt() > 0 && b->g.dt() > 0 && sigma.allFinite() && (sigma.array() > 0).all()) {
      settle = std::max({settle, restart_transient(b->v, b->v.dt(), sigma),
                         restart_transient(b->g, b->g.dt(), sigma)});
    }
    b->settle_until = s.t + settle;
    return;
  }
  // While a sensor is faulty, its dedicated observer is driven by the other observer's
  // estimate of that channel instead (reconfiguration): it keeps tracking the vessel, so
  // the fault stays fully visible and the residual is clean the moment the fault ends.
  const bool fa = sens_[0].cond.active, fg = sens_[1].cond.active;
  const bool pv = within(prev_.v, p_.max_abs_v) && !fa;
  const bool pr = within(prev_.r, p_.max_abs_r) && !fg;
  const double yv = pv ? prev_.v : b->g.x()(0);
  const double yr = pr ? prev_.r : b->v.x()(1);
  const bool use_v = pv || (fa && !fg);
  const bool use_r = pr || (fg && !fa);
  // At speed ratio s: A0 over the vessel's own time s dt, driven by s^(k-1) delta.
  const double h = st_.speed_ratio * dt, k = in_obs_;
  b->v.step(h, k * rudder(0), k * rudder(1), yv, use_v);
  b->g.step(h, k * rudder(0), k * rudder(1), yr, use_r);
}

bool Isolator::evaluate(Bank* b, const Sample& s, double dt, bool learn_ok, bool v_ok, bool r_ok,
                        double raw[4], Vec2* sw) {
  *sw = Vec2(kNaN, kNaN);
  if (s.t < b->settle_until) return false;
  if (b->theory_scales_pending) {
    // Innovation variance = sensor noise + observer error driven by the driving sensor.
    Mat2 Pv, Pg;
    const bool okv = discrete_lyapunov(b->v.Ad(), b->v.Gy(), &Pv);
    const bool okg = discrete_lyapunov(b->g.Ad(), b->g.Gy(), &Pg);
    if (okv && okg) {
      const double sv2 = p_.sigma_v * p_.sigma_v, sr2 = p_.sigma_r * p_.sigma_r;
      // Floors for the learned scales: what sensor noise alone would give.
      b->floor_s = Vec2(std::sqrt(sv2 + sv2 * Pv(0, 0)), std::sqrt(sr2 + sr2 * Pg(1, 1)));
      b->floor_d = Vec2(std::sqrt(sv2 + sr2 * Pg(0, 0)), std::sqrt(sr2 + sv2 * Pv(1, 1)));
    }
    b->theory_scales_pending = false;
  }
  raw[0] = v_ok ? s.v - b->v.x()(0) : kNaN;
  raw[1] = r_ok ? s.r - b->g.x()(1) : kNaN;
  raw[2] = v_ok ? s.v - b->g.x()(0) : kNaN;
  raw[3] = r_ok ? s.r - b->v.x()(1) : kNaN;

  // Learning, on healthy data only: first half scales, second half the distribution of J_N.
  if (!b->scales_learned) {
    if (learn_ok) {
      for (int i = 0; i < 4; ++i) b->learn_raw[i].push_back(raw[i]);
      b->learned_time += dt;
    }
    if (b->learned_time < 0.5 * p_.learn_time) return true;
    b->sigma_s(0) = std::max(robust_std(&b->learn_raw[0]), b->floor_s(0));
    b->sigma_s(1) = std::max(robust_std(&b->learn_raw[1]), b->floor_s(1));
    b->sigma_d(0) = std::max(robust_std(&b->learn_raw[2]), b->floor_d(0));
    b->sigma_d(1) = std::max(robust_std(&b->learn_raw[3]), b->floor_d(1));
    for (auto& v : b->learn_raw) std::vector<double>().swap(v);
    b->scales_learned = true;
    b->learned_time = 0.0;
  }

  const std::size_t n = window_samples(dt);
  const double c2 = p_.clip * p_.clip;
  for (int c = 0; c < 2; ++c) {
    if (!std::isfinite(raw[c])) continue;
    (*sw)(c) = raw[c] / b->sigma_s(c);
    const double dw = raw[2 + c] / b->sigma_d(c);
    b->win_s[c].push(std::min((*sw)(c) * (*sw)(c), c2), n);
    b->win_sl[c].push((*sw)(c), n);
    b->win_d[c].push(std::min(dw * dw, c2), n);
  }
  b->J = Vec2(b->win_s[0].mean(), b->win_s[1].mean());
  b->D = Vec2(b->win_d[0].mean(), b->win_d[1].mean());

  if (!b->learned) {
    if (learn_ok && b->win_s[0].size() >= n && b->win_s[1].size() >= n) {
      for (int c = 0; c < 2; ++c) {
        b->learn_J[c].push_back(b->J(c));
        b->learn_D[c].push_back(b->D(c));
      }
      b->learned_time += dt;
    }
    if (b->learned_time >= 0.5 * p_.learn_time) {
      // The last learning samples that count as just before going live.
      const std::size_t back =
          static_cast<std::size_t>(std::ceil(p_.onset_lookback / std::max(dt, 1e-6)));
      for (int c = 0; c < 2; ++c) {
        // A copy in learning order: learned_threshold reorders the samples.
        const std::vector<double> J = b->learn_J[c];
        b->threshold(c) = learned_threshold(&b->learn_J[c]);
        // A bar that had to be capped to stay within J_N's reach belongs to a residual the
        // model does not explain: its healthy J_N already went where a fault would take it.
        // Such a channel is closed (bar_unreachable) until a new design learns again: capped,
        // it was raised at the hull's next excursion (the Otter in sea state 3, 30-60 s after
        // going live; a Mariner at 50 Hz whose accelerometer J_N sat at the clip for 216 s).
        // Judged on the learning before the onset look-back: a fault that began in the last
        // seconds of learning (the paper's gyro bias) caps the bar too, and keeps its onset.
        // (A floor, threshold, at or above the cap would cap every bar: not the data's doing.)
        if (p_.close_capped_bars && b->threshold(c) >= reachable_threshold() &&
            p_.threshold < reachable_threshold() && J.size() > back) {
          std::vector<double> past(J.begin(), J.end() - static_cast<std::ptrdiff_t>(back));
          if (learned_threshold(&past) >= reachable_threshold()) {
            b->threshold(c) = kClosedBar * p_.clip * p_.clip;
          }
        }
        b->onset_in_learning[c] = onset_before_live(J, back, b->threshold(c));
        b->threshold_d(c) = learned_threshold(&b->learn_D[c]);
        std::vector<double>().swap(b->learn_J[c]);
        std::vector<double>().swap(b->learn_D[c]);
      }
      b->learned = true;
    }
  }
  return true;
}

void Isolator::propagate_observers(const Sample& s, double dt, bool v_ok, bool r_ok) {
  // Propagate the observers over [t_{k-1}, t_k]: the rudder linear between its samples, the
  // driving measurements those of t_{k-1}.
  // The rudder at t_{k-1} and t_k; one that is missing or implausible holds the last usable
  // value (0 before any).
  const double dp = within(prev_.delta, p_.max_abs_delta) ? prev_.delta
                    : std::isfinite(last_delta_)          ? last_delta_
                                                          : 0.0;
  const Vec2 rudder(dp, within(s.delta, p_.max_abs_delta) ? s.delta : dp);
  propagate(&act_, s, dt, v_ok, r_ok, rudder);
  if (has_shadow_) propagate(&shadow_, s, dt, v_ok, r_ok, rudder);
  for (int c = 0; c < 2; ++c) {
    if (!chan_[c].mon_on) continue;
    const double y = c == kV ? prev_.v : prev_.r;
    chan_[c].mon.step(st_.speed_ratio * dt, in_obs_ * rudder(0), in_obs_ * rudder(1), y,
                      within(y, c == kV ? p_.max_abs_v : p_.max_abs_r));
  }
}

void Isolator::resync_observers(const Sample& s, bool v_ok, bool r_ok) {
  // A sensor whose fault cleared drives its dedicated observer again. While it was faulty
  // that observer followed the other observer's estimate of the channel, whose error is the
  // cross residual's (several times the structured one's): restart it from the measurement
  // and the healthy observer's state, and its evaluation windows from empty (they hold the
  // faulty period), or the first healthy seconds would look like a new fault. The restarted
  // observer has its own transient (the other channel's state it is given carries that
  // observer's error, which the coupling turns into a drift of this channel's prediction):
  // the channel may raise again once it has settled (settle_time) and its window is full.
  for (int c = 0; c < 2; ++c) {
    const double y = c == kV ? s.v : s.r;
    if (!chan_[c].resync || !(c == kV ? v_ok : r_ok)) continue;
    for (Bank* b : {&act_, &shadow_}) {
      // The other channel's state from the healthy observer (the reconfigured one inferred
      // it from the cross estimate, through the coupling a2 or a3), this one measured.
      DedicatedObserver& o = c == kV ? b->v : b->g;
      const DedicatedObserver& healthy = c == kV ? b->g : b->v;
      Vec2 x = healthy.x();
      x(c) = y;
      o.reset(x);
      b->clear_windows(c);
    }
    chan_[c].resync = false;
    chan_[c].resettle_until = s.t + settle_time_;
  }
}

bool Isolator::healthy_for_maxima(double t, bool v_ok, bool r_ok) const {
  // Both channels usable, and no fault condition raised now or within resume_after_fault (a
  // fault that hides with the signal clears and re-raises).
  bool faulty = false;
  for (const SensorState& x : sens_) faulty = faulty || x.cond.active;
  // Nor while identification finds the data inconsistent with the vessel's dynamics (a
  // fault no residual sees yet, e.g. one that began while the first design was learning).
  return v_ok && r_ok && !faulty && !data_inconsistent_ &&
         t - t_last_fault_ >= p_.resume_after_fault;
}

bool Isolator::evaluate_banks(const Sample& s, double dt, bool learn_ok, bool v_ok, bool r_ok,
                              Statistics* x) {
  bool swapped = false;
  if (has_shadow_ && dt > 0 && st_.input.delta_ok) {
    evaluate(&shadow_, s, dt, learn_ok, v_ok, r_ok, x->raw, &x->sw);
    if (shadow_.learned) {
      swapped = true;  // this sample is already in its windows
      // The redesign has learned its own statistics: it takes over.
      act_ = std::move(shadow_);
      drop_shadow();
      // The healthy maxima carry over: the new design whitens its residuals with scales of
      // its own, so its statistics are comparable, and a manoeuvre met under the old one is
      // no less likely to come again.
      ++st_.designs;
      publish_bank();
      // The drift test's CUSUMs carry over (a redesign follows A by a few per cent; starting
      // them again at every redesign let a drift that moves A^ escape them).
    }
  }
  st_.settling = s.t < act_.settle_until;
  if (st_.settling || !(dt > 0) || !st_.input.delta_ok) return false;

  if (!swapped) evaluate(&act_, s, dt, learn_ok, v_ok, r_ok, x->raw, &x->sw);
  st_.learning = !act_.learned;
  if (!act_.scales_learned) return false;
  publish_bank();
  return true;
}

void Isolator::record_statistics(double t, const Statistics& x, bool maxima_ok) {
  for (int c = 0; c < 2; ++c) {
    if (!std::isfinite(x.sw(c))) continue;
    chan_[c].hist_s.emplace_back(t, x.sw(c));
    chan_[c].hist_d.emplace_back(t, x.raw[2 + c]);
    chan_[c].hist_x.emplace_back(t, c == kV ? act_.g.x()(0) : act_.v.x()(1));
    prune(&chan_[c].hist_s, t - p_.classify_window);
    prune(&chan_[c].hist_d, t - p_.classify_window);
    prune(&chan_[c].hist_x, t - p_.classify_window);
  }
  st_.J = act_.J;
  st_.D = act_.D;
  if (act_.learned) {
    // Healthy maxima, learned from samples older than a raise could be late.
    pending_stats_.push_back(
        PendingStat{t, {act_.J(0), act_.J(1), act_.D(0), act_.D(1)}, maxima_ok});
    while (!pending_stats_.empty() && t - pending_stats_.front().t > history_lag()) {
      if (pending_stats_.front().ok)
        healthy_.add(pending_stats_.front().t, pending_stats_.front().x);
      pending_stats_.pop_front();
    }
  }
  st_.s = Vec2(x.raw[0], x.raw[1]);
  st_.d = Vec2(x.raw[2], x.raw[3]);
}

void Isolator::update_monitors(const Sample& s, double dt, bool v_ok, bool r_ok) {
  // Monitors of raised channels: whitened like the structured residual they continue.
  for (int c = 0; c < 2; ++c) {
    const double y = c == kV ? s.v : s.r;
    if (!chan_[c].mon_on || !(c == kV ? v_ok : r_ok)) continue;
    const double w = (y - chan_[c].mon.x()(c)) / act_.sigma_s(c);
    chan_[c].win_m.push(std::min(w * w, p_.clip * p_.clip), window_samples(dt));
    chan_[c].win_ms.push(std::max(-p_.clip, std::min(w, p_.clip)), window_samples(dt));
    const FaultKind kind = sens_[c].cond.kind;
    const double m = std::max(0.0, chan_[c].mon_sign * chan_[c].win_ms.mean());
    // Scale errors change sign with the signal; stuck, stale and invalid channels are
    // held by their sensor-level checks, which see exactly when they end.
    const bool none = kind == FaultKind::kScale || kind == FaultKind::kStuck ||
                      kind == FaultKind::kStale || kind == FaultKind::kInvalid;
    st_.M(c) = none                                                      ? 0.0
               : kind == FaultKind::kNoise || kind == FaultKind::kSpikes ? chan_[c].win_m.mean()
                                                                         : 1.0 + m * m;
  }
}

void Isolator::update_confidences() {
  // C_i = |l_i^T e| / (|l_i| |e|) on the excess of each channel's statistic over its mean.
  const Vec2 e(std::sqrt(std::max(0.0, st_.J(0) - 1.0)), std::sqrt(std::max(0.0, st_.J(1) - 1.0)));
  const double en = e.norm();
  st_.c_a = en > 0 ? e(0) / en : 0.0;
  st_.c_g = en > 0 ? e(1) / en : 0.0;
}

void Isolator::check_spikes(double t, const Vec2& sw, std::vector<Detection>* out) {
  // Spikes: runs of one or two outliers.
  for (int c = 0; c < 2; ++c) {
    if (!std::isfinite(sw(c))) continue;
    ChannelState& ch = chan_[c];
    // A spike is a run of one or two outliers with ordinary samples on both sides.
    const double a = std::abs(sw(c));
    if (a > p_.spike_gate) {
      if (ch.outlier_run++ == 0) {
        ch.outlier_start = t;
        ch.run_isolated = ch.last_ordinary;
      }
    } else {
      const bool ordinary = a < 0.5 * p_.spike_gate;
      if (ch.outlier_run >= 1 && ch.outlier_run <= 2 && ch.run_isolated && ordinary) {
        ch.spikes.push_back(ch.outlier_start);
      }
      ch.outlier_run = 0;
    }
    ch.last_ordinary = a < 0.5 * p_.spike_gate;
    prune(&ch.spikes, t - p_.spike_window);
    const int count = static_cast<int>(ch.spikes.size());
    const bool on = count >= p_.spike_count;
    const bool was = sens_[c].cond.sources & kSpikes;
    if (on != was && (on || count == 0)) {
      set_condition(channel_sensor(c), kSpikes, on, FaultKind::kSpikes, t,
                    std::string(c == kV ? "accelerometer" : "gyro") +
                        (on ? ": " + std::to_string(count) + " spikes in " +
                                  std::to_string(p_.spike_window) + " s"
                            : ": no spikes in the window"),
                    out);
    }
  }
}

}  // namespace usvfdi
