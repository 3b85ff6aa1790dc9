#include "usv_fdi/core/isolation.hpp"

#include "isolation_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace usvfdi {

using isolation_detail::channel_sensor;
using isolation_detail::within;

namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("isolation.") + field + " = " + std::to_string(value) +
                                ": " + what);
  }
}

const IsolationParams& validated(const IsolationParams& p) {
  p.validate();
  return p;
}

const Vec2& finite_B(const Vec2& B) {
  if (!B.allFinite()) throw std::invalid_argument("model.B must be finite");
  return B;
}

}  // namespace

void IsolationParams::validate() const {
  require(poles_v.allFinite() && (poles_v.array() < 0).all(), "poles_v", poles_v(0),
          "both poles must be negative");
  require(poles_g.allFinite() && (poles_g.array() < 0).all(), "poles_g", poles_g(0),
          "both poles must be negative");
  require(min_observability >= 0, "min_observability", min_observability, "must be >= 0");
  require(redesign_tolerance > 0, "redesign_tolerance", redesign_tolerance, "must be > 0");
  require(sigma_v >= 0 && std::isfinite(sigma_v), "sigma_v", sigma_v, "must be >= 0");
  require(sigma_r >= 0 && std::isfinite(sigma_r), "sigma_r", sigma_r, "must be >= 0");
  require((sigma_v > 0) == (sigma_r > 0), "sigma_r", sigma_r,
          "give both sigma_v and sigma_r, or neither (learned)");
  require(sigma_floor_v > 0, "sigma_floor_v", sigma_floor_v, "must be > 0");
  require(sigma_floor_r > 0, "sigma_floor_r", sigma_floor_r, "must be > 0");
  require(learn_time > 0, "learn_time", learn_time, "must be > 0");
  require(window > 0, "window", window, "must be > 0");
  require(min_window_samples >= 1, "min_window_samples", min_window_samples, "must be >= 1");
  require(clip > 1, "clip", clip, "must be > 1");
  require(threshold > 1, "threshold", threshold, "must be > 1 (healthy J_N is about 1)");
  require(threshold_k > 0, "threshold_k", threshold_k, "must be > 0");
  require(threshold_margin >= 1, "threshold_margin", threshold_margin, "must be >= 1");
  require(exit_ratio > 0 && exit_ratio <= 1, "exit_ratio", exit_ratio, "must lie in (0, 1]");
  require(exit_ratio * threshold > 1, "exit_ratio", exit_ratio,
          "exit_ratio * threshold must exceed 1 (healthy J_N is about 1)");
  require(enter_time >= 0, "enter_time", enter_time, "must be >= 0");
  require(young_enter_ratio >= 1, "young_enter_ratio", young_enter_ratio, "must be >= 1");
  require(onset_lookback >= 0 && onset_lookback <= 600, "onset_lookback", onset_lookback,
          "must be in [0, 600] s");
  require(leave_time >= 0, "leave_time", leave_time, "must be >= 0");
  require(second_fault_time >= 0, "second_fault_time", second_fault_time, "must be >= 0");
  require(mismatch_window >= 0, "mismatch_window", mismatch_window, "must be >= 0");
  require(min_active_time >= 0, "min_active_time", min_active_time, "must be >= 0");
  require(c_min > 0 && c_min <= 1, "c_min", c_min, "must lie in (0, 1]");
  require(c_margin >= 0 && c_margin < 1, "c_margin", c_margin, "must lie in [0, 1)");
  require(resume_time >= 0, "resume_time", resume_time, "must be >= 0");
  require(resume_after_fault >= 0, "resume_after_fault", resume_after_fault, "must be >= 0");
  require(stale_timeout > 0, "stale_timeout", stale_timeout, "must be > 0");
  require(stuck_time > 0, "stuck_time", stuck_time, "must be > 0");
  require(stuck_min_samples >= 2, "stuck_min_samples", stuck_min_samples, "must be >= 2");
  require(stuck_probability > 0 && stuck_probability < 1, "stuck_probability", stuck_probability,
          "must lie in (0, 1)");
  require(stuck_learn_time > 0, "stuck_learn_time", stuck_learn_time, "must be > 0");
  require(stuck_time_max >= stuck_time, "stuck_time_max", stuck_time_max, "must be >= stuck_time");
  require(max_abs_v > 0, "max_abs_v", max_abs_v, "must be > 0");
  require(max_abs_r > 0, "max_abs_r", max_abs_r, "must be > 0");
  require(max_abs_delta > 0, "max_abs_delta", max_abs_delta, "must be > 0");
  require(spike_gate > clip, "spike_gate", spike_gate, "must exceed clip");
  require(spike_window > 0, "spike_window", spike_window, "must be > 0");
  require(spike_count >= 1, "spike_count", spike_count, "must be >= 1");
  require(invalid_count >= 1, "invalid_count", invalid_count, "must be >= 1");
  require(classify_window > 0, "classify_window", classify_window, "must be > 0");
  require(history_margin >= 1, "history_margin", history_margin, "must be >= 1");
  require(history >= 10, "history", history, "must be >= 10 s");
  require(drift_k > 0, "drift_k", drift_k, "must be > 0");
  require(drift_threshold > 0, "drift_threshold", drift_threshold, "must be > 0");
  require(drift_lag >= 0, "drift_lag", drift_lag, "must be >= 0");
  require(drift_min_history >= 0 && (!drift_check || drift_min_history <= history),
          "drift_min_history", drift_min_history,
          "must lie in [0, history] (the healthy maxima cover at most history)");
  jump.validate();
}

void Isolator::Window::push(double x, std::size_t n) {
  if (count_ == buf_.size()) {  // full: grow, oldest first
    std::vector<double> grown(std::max<std::size_t>({2 * buf_.size(), n + 1, 16}));
    for (std::size_t i = 0; i < count_; ++i) grown[i] = at(i);
    buf_.swap(grown);
    head_ = 0;
  }
  std::size_t tail = head_ + count_;
  if (tail >= buf_.size()) tail -= buf_.size();
  buf_[tail] = x;
  ++count_;
  sum_ += x;
  while (count_ > n) {
    sum_ -= buf_[head_];
    if (++head_ == buf_.size()) head_ = 0;
    --count_;
  }
  if (count_ == n && (n & 63) == 0) {  // bound round-off drift of the running sum
    sum_ = 0;
    for (std::size_t i = 0; i < count_; ++i) sum_ += at(i);
  }
}

Isolator::Isolator(const IsolationParams& params, const Vec2& B, const SpeedParams& speed)
    : p_(validated(params)),
      B_(finite_B(B)),
      speed_(speed),
      checks_(p_),
      jump_{JumpCheck(p_.jump, B_(0), p_.sigma_floor_v),
            JumpCheck(p_.jump, B_(1), p_.sigma_floor_r)},
      healthy_(10.0, p_.history),
      drift_healthy_(10.0, p_.history) {
  scales_configured_ = p_.sigma_v > 0;
  const double pmin = std::min(p_.poles_v.cwiseAbs().minCoeff(), p_.poles_g.cwiseAbs().minCoeff());
  settle_time_ = p_.settle_time >= 0 ? p_.settle_time : 3.0 / pmin;
}

void Isolator::set_estimate(const Estimate& est) {
  const double t_now = have_prev_ ? prev_.t : est.t;
  data_inconsistent_ = !est.consistent || est.inconsistent_time > 0.0;
  if (!st_.armed) {
    if (!est.converged) return;
    if (!design(est.A, &act_)) return;
    st_.armed = true;
    ++st_.designs;
    t_armed_ = t_now;
    for (ChannelState& ch : chan_) ch.onset_seen = false;
    act_.settle_until = t_armed_ + settle_time_;
    const Vec2 y0(std::isfinite(prev_.v) ? prev_.v : 0.0, std::isfinite(prev_.r) ? prev_.r : 0.0);
    act_.v.reset(y0);
    act_.g.reset(y0);
    publish_bank();
    return;
  }
  if (p_.on_lost_convergence == LostConvergence::kUnarm) {
    // The data no longer support the estimate: the residual checks stop at the next sample
    // (update has the detections' output), and arm again once it has converged anew.
    unarm_pending_ = !est.converged;
    if (unarm_pending_) return;
  }
  st_.design_held = p_.on_lost_convergence == LostConvergence::kHold && !est.converged;
  if (st_.design_held) {
    // The data no longer support the estimate: keep the design in force, and drop a
    // redesign made on an estimate that was already losing its footing.
    drop_shadow();
    return;
  }
  // One redesign learns at a time; the design in force keeps detecting meanwhile.
  if (has_shadow_) return;
  const double ref = act_.A.norm();
  if (!((est.A - act_.A).norm() > p_.redesign_tolerance * ref)) return;
  if (!design(est.A, &shadow_)) return;
  shadow_.v.reset(act_.v.x());
  shadow_.g.reset(act_.g.x());
  shadow_.settle_until = t_now + settle_time_;
  has_shadow_ = true;
  st_.relearning = true;
}

bool Isolator::update(const Sample& s, std::vector<Detection>* out) {
  if (!std::isfinite(s.t)) {
    ++st_.input.invalid_values;
    return false;
  }
  if (have_prev_ && !(s.t > prev_.t)) return reject_timestamp(out);
  const double dt = have_prev_ ? s.t - prev_.t : 0.0;
  ++st_.samples;
  const bool had_speed = speed_.measured();
  st_.speed_ratio = speed_.update(s);
  in_obs_ = speed_.input_factor(st_.speed_ratio) / st_.speed_ratio;
  if (speed_.measured() && !had_speed) {
    // The observers' step (the vessel's own time) now moves a little on every sample.
    for (Bank* b : {&act_, &shadow_}) {
      b->v.set_step_band(speed_.params().quantum);
      b->g.set_step_band(speed_.params().quantum);
    }
  }
  if (have_prev_ && dt > p_.stale_timeout) ++st_.input.gaps;
  sensor_checks(s, out);
  jump_checks(s, out);
  if (unarm_pending_) unarm(s.t, out);
  if (st_.armed) residual_checks(s, dt, out);

  // Freeze identification while anything is suspect, and for resume_time after.
  bool suspect = !st_.input.v_ok || !st_.input.r_ok || !st_.input.delta_ok || !std::isfinite(s.v) ||
                 !std::isfinite(s.r) || !std::isfinite(s.delta);
  bool faulty = false;
  for (const SensorState& x : sens_) faulty = faulty || x.cond.active;
  suspect = suspect || faulty;
  if (faulty) t_last_fault_ = s.t;
  if (faulty && !was_faulty_ && has_shadow_ && !shadow_.learned && p_.relearn_after_raise) {
    // A redesign still learning restarts: what it learned just before this raise may hold
    // the fault's onset (a drift grows for seconds before it is raised), and a learned bar
    // or scale on it hides the next faults until the design after.
    restart_learning(&shadow_);
  }
  was_faulty_ = faulty;
  if (st_.armed && !st_.learning && !st_.settling) {
    suspect = suspect || (st_.J.array() > p_.exit_ratio * st_.thresholds.array()).any() ||
              (st_.D.array() > p_.exit_ratio * st_.thresholds_d.array()).any() ||
              (st_.drift_S.array() > p_.exit_ratio * st_.drift_threshold.array() &&
               st_.drift_threshold.array() > 0)
                  .any();
  }
  if (suspect) t_last_suspect_ = s.t;
  freeze_ = s.t - t_last_suspect_ < p_.resume_time || s.t - t_last_fault_ < p_.resume_after_fault;
  prev_ = s;
  have_prev_ = true;
  return true;
}

void Isolator::unarm(double t, std::vector<Detection>* out) {
  unarm_pending_ = false;
  if (!st_.armed) return;
  const std::string why = "estimate of A lost convergence: residual checks off until it converges";
  for (int k = 0; k < 3; ++k) {
    // The residual path's own raises (its spike test included) end with it.
    for (const Source src : {kResidual, kSpikes}) {
      if (!(sens_[k].cond.sources & src)) continue;
      set_condition(static_cast<Sensor>(k), src, false, sens_[k].cond.kind, t, why, out);
    }
    sens_[k].above_since = sens_[k].below_since = kNaN;
    sens_[k].raised_at = sens_[k].unheld_at = kNaN;
  }
  for (ChannelState& ch : chan_) {
    // What the residual path kept of the channel goes; the jump check's time of its raise
    // stays (a raised jump is no longer handed to observers that are gone: a new design
    // takes it over).
    ChannelState fresh;
    fresh.jump_at = ch.jump_at;
    ch = std::move(fresh);
  }
  act_ = Bank{};
  drop_shadow();
  // The healthy maxima were learned on a design the data no longer support: a new one starts
  // without them, as the first did.
  healthy_.clear();
  pending_stats_.clear();
  drift_healthy_.clear();
  pending_drift_.clear();
  st_.armed = st_.learning = st_.settling = false;
  st_.model_mismatch = false;
  st_.mismatch_reason.clear();
  mismatch_since_ = below_mm_since_ = kNaN;
  mismatch_repeated_ = repeat_rise_ = -1;
  st_.awaiting_onset = {};
  st_.J = st_.D = st_.M = st_.s = st_.d = Vec2::Zero();
  st_.c_a = st_.c_g = 0.0;
  reset_drift(t);
  st_.drift_S = st_.drift_threshold = Vec2::Zero();
  publish_bank();  // the design's figures go with it (A_design, scales, bars, relearning)
  ++st_.unarms;
}

void Isolator::drop_shadow() {
  shadow_ = Bank{};
  has_shadow_ = false;
  st_.relearning = false;
}

bool Isolator::reject_timestamp(std::vector<Detection>* out) {
  ++st_.input.rejected_time;
  if (!have_prev_) return false;
  // Timing errors count against "unknown", at the last good time.
  if (checks_.timing_error(prev_.t)) {
    set_condition(Sensor::kUnknown, kInvalid, true, FaultKind::kInvalid, prev_.t,
                  "sample timestamps repeat, go backwards or jump", out);
  }
  t_last_suspect_ = prev_.t;
  freeze_ = true;
  return false;
}

void Isolator::sensor_checks(const Sample& s, std::vector<Detection>* out) {
  // A channel taken for stuck does not learn its repeat fraction from its frozen output.
  checks_.update(s, {!(sens_[0].cond.sources & kStuck), !(sens_[1].cond.sources & kStuck)},
                 &st_.input);
  for (int c = 0; c < 2; ++c) {  // the rudder is not an INS sensor: it pauses FDI (status flag)
    const SensorChecks::Verdict& v = checks_.verdict(c);
    const Sensor sensor = channel_sensor(c);
    const char* name = c == kV ? "accelerometer channel v" : "gyro channel r";
    const unsigned src = sens_[c].cond.sources;
    if (v.stale != static_cast<bool>(src & kStale)) {
      set_condition(sensor, kStale, v.stale, FaultKind::kStale, s.t,
                    std::string(name) +
                        (v.stale ? ": no valid value for " + std::to_string(v.since_valid) + " s"
                                 : ": valid values again"),
                    out);
    }
    if (v.stuck != static_cast<bool>(src & kStuck)) {
      set_condition(sensor, kStuck, v.stuck, FaultKind::kStuck, s.t,
                    std::string(name) + (v.stuck ? ": output frozen at " + std::to_string(v.value)
                                                 : ": output moves again"),
                    out);
    }
    if (v.invalid != static_cast<bool>(src & kInvalid)) {
      set_condition(sensor, kInvalid, v.invalid, FaultKind::kInvalid, s.t,
                    std::string(name) + (v.invalid ? ": repeated non-finite or absurd values"
                                                   : ": values plausible again"),
                    out);
    }
  }
  const auto ok = [&](int c) { return !checks_.verdict(c).stale && !checks_.verdict(c).invalid; };
  st_.input.v_ok = ok(0) && !(sens_[0].cond.sources & kStuck);
  st_.input.r_ok = ok(1) && !(sens_[1].cond.sources & kStuck);
  st_.input.delta_ok = ok(2);
  if (within(s.delta, p_.max_abs_delta)) last_delta_ = s.delta;
  // Timing errors age out of the unknown channel too.
  if ((sens_[2].cond.sources & kInvalid) && checks_.timing_clear(s.t)) {
    set_condition(Sensor::kUnknown, kInvalid, false, FaultKind::kInvalid, s.t,
                  "sample timestamps increase again", out);
  }
}

bool Isolator::model_live() const {
  return st_.armed && act_.learned && !st_.settling && act_.v.ready() && act_.g.ready();
}

void Isolator::jump_checks(const Sample& s, std::vector<Detection>* out) {
  JumpVerdict verdict[2];
  update_jump_checks(s, verdict);
  // The isolation confidence of a jump: C_i on the excess evidence of both channels.
  const Vec2 e(std::sqrt(std::max(0.0, st_.jump_T(0) / std::max(st_.jump_threshold(0), 1.0))),
               std::sqrt(std::max(0.0, st_.jump_T(1) / std::max(st_.jump_threshold(1), 1.0))));
  for (int c = 0; c < 2; ++c) apply_jump_verdict(c, verdict[c], e, s.t, out);
}

void Isolator::update_jump_checks(const Sample& s, JumpVerdict verdict[2]) {
  const double values[2] = {s.v, s.r};
  const double limits[2] = {p_.max_abs_v, p_.max_abs_r};
  const double delta = within(s.delta, p_.max_abs_delta) ? s.delta : kNaN;
  for (int c = 0; c < 2; ++c) {
    const double y = within(values[c], limits[c]) ? values[c] : kNaN;
    // Learns from a channel no condition is raised on, with the rudder known.
    const bool learn_ok =
        !sens_[c].cond.active && st_.input.delta_ok && (c == kV ? st_.input.v_ok : st_.input.r_ok);
    verdict[c] = jump_[c].update(s.t, y, delta, learn_ok);
    st_.jump_T(c) = jump_[c].statistic();
    st_.jump_threshold(c) = jump_[c].threshold();
    st_.noise_N(c) = jump_[c].noise_statistic();
    st_.noise_threshold(c) = jump_[c].noise_threshold();
  }
  st_.jump_armed = jump_[0].armed() && jump_[1].armed();
}

void Isolator::apply_jump_verdict(int c, const JumpVerdict& v, const Vec2& e, double t,
                                  std::vector<Detection>* out) {
  const Sensor sensor = channel_sensor(c);
  const char* name = c == kV ? "accelerometer channel v: " : "gyro channel r: ";
  // The detection just emitted (if any) gets the check's onset, statistic and confidence.
  const auto patch = [&](std::size_t before, double onset, double stat, double thr) {
    if (out->size() == before || !out->back().active) return;
    Detection& d = out->back();
    if (std::isfinite(onset)) d.onset_time = onset;
    d.statistic = stat;
    d.threshold = thr;
    const Vec2 ec = stat > 0 && e.norm() > 0 ? e : (c == kV ? Vec2(1, 0) : Vec2(0, 1));
    d.c_a = ec(0) / ec.norm();
    d.c_g = ec(1) / ec.norm();
  };
  if (!(sens_[c].cond.sources & kJump)) chan_[c].jump_handed = false;
  if (v.step == JumpVerdict::Change::kRaise) chan_[c].jump_at = t;
  if (v.noise == JumpVerdict::Change::kRaise && sens_[c].cond.active &&
      sens_[c].cond.kind == FaultKind::kBias &&
      t - chan_[c].jump_at <= 2.0 * p_.jump.noise_window) {
    jump_was_noise(c, name + v.message, t, out);
    return;
  }
  if (v.step != JumpVerdict::Change::kNone) {
    const std::size_t before = out->size();
    set_condition(sensor, kJump, v.step == JumpVerdict::Change::kRaise, FaultKind::kBias, t,
                  name + v.message, out);
    patch(before, v.onset, st_.jump_T(c), st_.jump_threshold(c));
  }
  if ((sens_[c].cond.sources & kJump) && model_live()) hand_jump_to_observers(c, name, t, out);
  if (v.noise != JumpVerdict::Change::kNone) {
    const std::size_t before = out->size();
    set_condition(sensor, kNoiseRise, v.noise == JumpVerdict::Change::kRaise, FaultKind::kNoise, t,
                  name + v.message, out);
    patch(before, kNaN, st_.noise_N(c), st_.noise_threshold(c));
  }
  // A jump the check no longer holds (withdrawn as the first samples of a noise rise) is
  // no source of this condition either.
  if ((sens_[c].cond.sources & kJump) && !jump_[c].jump_raised()) {
    set_condition(sensor, kJump, false, FaultKind::kBias, t, std::string(name) + "jump withdrawn",
                  out);
  }
  // The check holds an offset until it jumps back. A fault the observers hold and have named
  // otherwise (a scale error, a drift, a frozen output) has no jump back to wait for: its
  // own detectors decide when it ends.
  if ((sens_[c].cond.sources & kJump) && chan_[c].jump_handed &&
      sens_[c].cond.kind != FaultKind::kBias) {
    set_condition(sensor, kJump, false, FaultKind::kBias, t,
                  std::string(name) + "the fault is no offset", out);
    jump_[c].release();
  }
}

void Isolator::jump_was_noise(int c, const std::string& message, double t,
                              std::vector<Detection>* out) {
  // The jump raised just before was the first samples of a noise rise: one condition, its
  // kind refined.
  const Sensor sensor = channel_sensor(c);
  set_condition(sensor, kNoiseRise, true, FaultKind::kNoise, t, message, out);
  set_condition(sensor, kJump, false, FaultKind::kBias, t, message, out);
  jump_[c].release();
  Condition& cd = sens_[c].cond;
  if (cd.active && cd.kind != FaultKind::kNoise) {
    Detection d = make_detection(sensor, true, FaultKind::kNoise, t);
    d.update = true;
    d.message = std::string("kind refined from ") + to_string(cd.kind) + " to noise: " + message;
    cd.kind = FaultKind::kNoise;
    out->push_back(d);
  }
}

void Isolator::hand_jump_to_observers(int c, const char* name, double t,
                                      std::vector<Detection>* out) {
  // Once the observers are live they hold a jump like any residual fault, and the jump check
  // goes on holding it too: the condition clears when both let go. The observers' residual
  // alone let a bias in a seaway go within seconds while it was still there (the model's
  // residual is only so sensitive); the jump check lets go at the jump back, or hold_max.
  const Sensor sensor = channel_sensor(c);
  if (chan_[c].jump_handed) return;
  if (sens_[c].cond.sources & kResidual) {
    // The observers hold a fault on this channel already and decide when it ends (a jump
    // now may be that fault's end, a drift's fall back to the truth).
    set_condition(sensor, kJump, false, FaultKind::kBias, t, "", out);
    jump_[c].release();
    return;
  }
  chan_[c].jump_handed = true;
  set_condition(sensor, kResidual, true, FaultKind::kBias, t,
                std::string(name) + "held by the observers", out);
  sens_[c].raised_at = t;
  sens_[c].below_since = kNaN;
  // Its kind is refined from the residuals' shape like any other (a scale error jumps).
  if (sens_[c].cond.kind == FaultKind::kBias) chan_[c].refine_at = t + 0.5 * p_.classify_window;
}

void Isolator::residual_checks(const Sample& s, double dt, std::vector<Detection>* out) {
  if (!act_.v.ready() || !act_.g.ready()) return;
  const bool v_ok = within(s.v, p_.max_abs_v);
  const bool r_ok = within(s.r, p_.max_abs_r);
  if (have_prev_ && dt > 0) propagate_observers(s, dt, v_ok, r_ok);
  resync_observers(s, v_ok, r_ok);
  // The maxima the bars follow learn through a model-mismatch verdict too, the scales and the
  // rest not: a manoeuvre the model does not hold, kept out of the maxima, met the same bar
  // the next time and was raised or judged again (the Otter's course changes, every 20 s).
  const bool maxima_ok = healthy_for_maxima(s.t, v_ok, r_ok);
  const bool learn_ok = maxima_ok && !st_.model_mismatch;
  Statistics x;
  if (!evaluate_banks(s, dt, learn_ok, v_ok, r_ok, &x)) return;
  record_statistics(s.t, x, maxima_ok);
  update_monitors(s, dt, v_ok, r_ok);
  update_confidences();
  if (!act_.learned) return;
  check_spikes(s.t, x.sw, out);
  Levels lv = levels(s.t, dt);
  await_onsets(&lv);
  const Candidate c = choose_candidate(s.t, lv);
  confirm_candidate(s.t, lv, c, out);
  drift_checks(s.t, dt, x, learn_ok, lv, out);
  refine_kinds(s.t, out);
  hold_or_clear(s.t, lv, c.k, out);
}

}  // namespace usvfdi
