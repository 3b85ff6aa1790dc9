#include "usv_fdi/core/isolation.hpp"

#include "usv_fdi/core/robust.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace usvfdi {
namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("isolation.") + field + " = " + std::to_string(value) +
                                ": " + what);
  }
}

/// Finite and within the plausible limit.
bool within(double x, double lim) { return std::isfinite(x) && std::abs(x) <= lim; }

/// Slack of the time comparisons (hold, enter and leave times) [s].
constexpr double kEpsT = 1e-9;

int sensor_index(Sensor s) { return static_cast<int>(s); }
Sensor channel_sensor(int ch) { return ch == kV ? Sensor::kAccelerometer : Sensor::kGyro; }

void prune(std::deque<double>* q, double t_min) {
  while (!q->empty() && q->front() < t_min) q->pop_front();
}
void prune(std::deque<std::pair<double, double>>* q, double t_min) {
  while (!q->empty() && q->front().first < t_min) q->pop_front();
}

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
      healthy_(10.0, p_.history) {
  scales_configured_ = p_.sigma_v > 0;
  const double pmin = std::min(p_.poles_v.cwiseAbs().minCoeff(), p_.poles_g.cwiseAbs().minCoeff());
  settle_time_ = p_.settle_time >= 0 ? p_.settle_time : 3.0 / pmin;
}

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

double Isolator::history_lag() const {
  return p_.window + std::max(p_.enter_time, p_.second_fault_time) + 1.0;
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
          std::max(st_.thresholds(c), p_.history_margin * healthy_.extrapolated_max(c));
      st_.thresholds_d(c) =
          std::max(st_.thresholds_d(c), p_.history_margin * healthy_.extrapolated_max(2 + c));
    }
  }
  st_.threshold = act_.threshold.maxCoeff();
  st_.threshold_d = act_.threshold_d.maxCoeff();
  st_.relearning = has_shadow_;
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
    act_.settle_until = t_armed_ + settle_time_;
    const Vec2 y0(std::isfinite(prev_.v) ? prev_.v : 0.0, std::isfinite(prev_.r) ? prev_.r : 0.0);
    act_.v.reset(y0);
    act_.g.reset(y0);
    publish_bank();
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

double Isolator::learned_threshold(std::vector<double>* healthy) const {
  const double med = median_in_place(healthy);
  const double sd = robust_std(healthy);
  std::sort(healthy->begin(), healthy->end());
  const double q999 = healthy->empty() ? 0.0 : (*healthy)[healthy->size() * 999 / 1000];
  // A windowed mean of clipped squares cannot exceed clip^2: keep the threshold reachable.
  return std::min(std::max({p_.threshold, med + p_.threshold_k * sd, p_.threshold_margin * q999}),
                  0.75 * p_.clip * p_.clip);
}

std::size_t Isolator::window_samples(double dt) const {
  const double n = dt > 0 ? std::round(p_.window / dt) : p_.min_window_samples;
  return static_cast<std::size_t>(std::max<double>(n, p_.min_window_samples));
}

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
    c.active = true;
    c.kind = kind;
    if (sensor != Sensor::kUnknown) start_monitor(sensor_index(sensor));
    Detection d = make_detection(sensor, true, kind, t);
    if (src == kResidual && sensor != Sensor::kUnknown) {
      d.onset_time = onset_estimate(sensor_index(sensor), t);
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
  if (st_.armed) residual_checks(s, dt, out);

  // Freeze identification while anything is suspect, and for resume_time after.
  bool suspect = !st_.input.v_ok || !st_.input.r_ok || !st_.input.delta_ok || !std::isfinite(s.v) ||
                 !std::isfinite(s.r) || !std::isfinite(s.delta);
  bool faulty = false;
  for (const SensorState& x : sens_) faulty = faulty || x.cond.active;
  suspect = suspect || faulty;
  if (faulty) t_last_fault_ = s.t;
  if (st_.armed && !st_.learning && !st_.settling) {
    suspect = suspect || (st_.J.array() > p_.exit_ratio * st_.thresholds.array()).any() ||
              (st_.D.array() > p_.exit_ratio * st_.thresholds_d.array()).any();
  }
  if (suspect) t_last_suspect_ = s.t;
  freeze_ = s.t - t_last_suspect_ < p_.resume_time || s.t - t_last_fault_ < p_.resume_after_fault;
  prev_ = s;
  have_prev_ = true;
  return true;
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
    const std::string name = c == kV ? "accelerometer channel v" : "gyro channel r";
    const unsigned src = sens_[c].cond.sources;
    if (v.stale != static_cast<bool>(src & kStale)) {
      set_condition(sensor, kStale, v.stale, FaultKind::kStale, s.t,
                    name + (v.stale ? ": no valid value for " + std::to_string(v.since_valid) + " s"
                                    : ": valid values again"),
                    out);
    }
    if (v.stuck != static_cast<bool>(src & kStuck)) {
      set_condition(sensor, kStuck, v.stuck, FaultKind::kStuck, s.t,
                    name + (v.stuck ? ": output frozen at " + std::to_string(v.value)
                                    : ": output moves again"),
                    out);
    }
    if (v.invalid != static_cast<bool>(src & kInvalid)) {
      set_condition(sensor, kInvalid, v.invalid, FaultKind::kInvalid, s.t,
                    name + (v.invalid ? ": repeated non-finite or absurd values"
                                      : ": values plausible again"),
                    out);
    }
  }
  const auto ok = [&](int c) { return !checks_.verdict(c).stale && !checks_.verdict(c).invalid; };
  st_.input.v_ok = ok(0) && !(sens_[0].cond.sources & kStuck);
  st_.input.r_ok = ok(1) && !(sens_[1].cond.sources & kStuck);
  st_.input.delta_ok = ok(2);
  if (std::isfinite(s.delta) && std::abs(s.delta) <= p_.max_abs_delta) last_delta_ = s.delta;
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
  const double delta =
      std::isfinite(s.delta) && std::abs(s.delta) <= p_.max_abs_delta ? s.delta : kNaN;
  for (int c = 0; c < 2; ++c) {
    const double y =
        std::isfinite(values[c]) && std::abs(values[c]) <= limits[c] ? values[c] : kNaN;
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
  const std::string name = c == kV ? "accelerometer channel v: " : "gyro channel r: ";
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
    set_condition(sensor, kJump, false, FaultKind::kBias, t, name + "jump withdrawn", out);
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

void Isolator::hand_jump_to_observers(int c, const std::string& name, double t,
                                      std::vector<Detection>* out) {
  // Once the observers are live they hold a jump like any residual fault (their cross
  // residual sees whether the offset is still there, or has gone without a jump back).
  const Sensor sensor = channel_sensor(c);
  const bool held = sens_[c].cond.sources & kResidual;  // the observers hold it already
  set_condition(sensor, kResidual, true, FaultKind::kBias, t, name + "held by the observers", out);
  set_condition(sensor, kJump, false, FaultKind::kBias, t, "", out);
  if (!held) {
    sens_[c].raised_at = t;
    sens_[c].below_since = kNaN;
    // Its kind is refined from the residuals' shape like any other (a scale error jumps).
    if (sens_[c].cond.kind == FaultKind::kBias) chan_[c].refine_at = t + 0.5 * p_.classify_window;
  }
  jump_[c].release();
}

void Isolator::propagate(Bank* b, const Sample& s, double dt, bool v_ok, bool r_ok) {
  const auto usable = [&](double x, double lim) { return std::isfinite(x) && std::abs(x) <= lim; };
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
  const double d = usable(prev_.delta, p_.max_abs_delta) ? prev_.delta
                   : std::isfinite(last_delta_)          ? last_delta_
                                                         : 0.0;
  const double d_new = usable(s.delta, p_.max_abs_delta) ? s.delta : d;
  // While a sensor is faulty, its dedicated observer is driven by the other observer's
  // estimate of that channel instead (reconfiguration): it keeps tracking the vessel, so
  // the fault stays fully visible and the residual is clean the moment the fault ends.
  const bool fa = sens_[0].cond.active, fg = sens_[1].cond.active;
  const bool pv = usable(prev_.v, p_.max_abs_v) && !fa;
  const bool pr = usable(prev_.r, p_.max_abs_r) && !fg;
  const double yv = pv ? prev_.v : b->g.x()(0);
  const double yr = pr ? prev_.r : b->v.x()(1);
  const bool use_v = pv || (fa && !fg);
  const bool use_r = pr || (fg && !fa);
  // At speed ratio s: A0 over the vessel's own time s dt, driven by s^(k-1) delta.
  const double h = st_.speed_ratio * dt, k = in_obs_;
  b->v.step(h, k * d, k * d_new, yv, use_v);
  b->g.step(h, k * d, k * d_new, yr, use_r);
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
      for (int c = 0; c < 2; ++c) {
        b->threshold(c) = learned_threshold(&b->learn_J[c]);
        b->threshold_d(c) = learned_threshold(&b->learn_D[c]);
        std::vector<double>().swap(b->learn_J[c]);
        std::vector<double>().swap(b->learn_D[c]);
      }
      b->learned = true;
    }
  }
  return true;
}

void Isolator::residual_checks(const Sample& s, double dt, std::vector<Detection>* out) {
  if (!act_.v.ready() || !act_.g.ready()) return;
  const bool v_ok = within(s.v, p_.max_abs_v);
  const bool r_ok = within(s.r, p_.max_abs_r);
  if (have_prev_ && dt > 0) propagate_observers(s, dt, v_ok, r_ok);
  resync_observers(s, v_ok, r_ok);
  const bool learn_ok = healthy_for_learning(s.t, v_ok, r_ok);
  Statistics x;
  if (!evaluate_banks(s, dt, learn_ok, v_ok, r_ok, &x)) return;
  record_statistics(s.t, x, learn_ok);
  update_monitors(s, dt, v_ok, r_ok);
  update_confidences();
  if (!act_.learned) return;
  check_spikes(s.t, x.sw, out);
  const Levels lv = levels(s.t, dt);
  const Candidate c = choose_candidate(s.t, lv);
  confirm_candidate(s.t, lv, c, out);
  refine_kinds(s.t, out);
  hold_or_clear(s.t, lv, c.k, out);
}

void Isolator::propagate_observers(const Sample& s, double dt, bool v_ok, bool r_ok) {
  // Propagate the observers over [t_{k-1}, t_k]: the rudder linear between its samples, the
  // driving measurements those of t_{k-1}.
  propagate(&act_, s, dt, v_ok, r_ok);
  if (has_shadow_) propagate(&shadow_, s, dt, v_ok, r_ok);
  const double dp = std::isfinite(prev_.delta) && std::abs(prev_.delta) <= p_.max_abs_delta
                        ? prev_.delta
                    : std::isfinite(last_delta_) ? last_delta_
                                                 : 0.0;
  const double dn = within(s.delta, p_.max_abs_delta) ? s.delta : dp;
  for (int c = 0; c < 2; ++c) {
    if (!chan_[c].mon_on) continue;
    const double y = c == kV ? prev_.v : prev_.r;
    chan_[c].mon.step(st_.speed_ratio * dt, in_obs_ * dp, in_obs_ * dn, y,
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
      for (auto* w : {&b->win_s[c], &b->win_sl[c], &b->win_d[c]}) *w = Window{};
    }
    chan_[c].resync = false;
    chan_[c].resettle_until = s.t + settle_time_;
  }
}

bool Isolator::healthy_for_learning(double t, bool v_ok, bool r_ok) const {
  // Healthy data for learning: both channels usable, and no fault condition raised now or
  // within resume_after_fault (a fault that hides with the signal clears and re-raises).
  bool faulty = false;
  for (const SensorState& x : sens_) faulty = faulty || x.cond.active;
  // Nor while identification finds the data inconsistent with the vessel's dynamics (a
  // fault no residual sees yet, e.g. one that began while the first design was learning).
  return v_ok && r_ok && !faulty && !data_inconsistent_ && !st_.model_mismatch &&
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
      shadow_ = Bank{};
      has_shadow_ = false;
      // The healthy maxima carry over: the new design whitens its residuals with scales of
      // its own, so its statistics are comparable, and a manoeuvre met under the old one is
      // no less likely to come again.
      ++st_.designs;
      publish_bank();
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

void Isolator::record_statistics(double t, const Statistics& x, bool learn_ok) {
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
        PendingStat{t, {act_.J(0), act_.J(1), act_.D(0), act_.D(1)}, learn_ok});
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
    const FaultKind refined =
        noise_like(k, sens_[k].raised_at) ? FaultKind::kNoise : classify_shape(k);
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
    if (act_.win_s[c].size() < lv.n_full || t < chan_[c].resettle_until) lv.ratio(c) = 0.0;
  }
  lv.thr_exit_d = p_.exit_ratio * st_.thresholds_d;
  return lv;
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
  return c;
}

void Isolator::confirm_candidate(double t, const Levels& lv, const Candidate& c,
                                 std::vector<Detection>* out) {
  const bool a_res = sens_[0].cond.sources & kResidual, g_res = sens_[1].cond.sources & kResidual;
  const double enter =
      (a_res || g_res) && c.k != 2 ? std::max(p_.enter_time, p_.second_fault_time) : p_.enter_time;
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
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "residuals of both channels (J_N %.3g / %.3g against %.3g / %.3g)%s", st_.J(0),
                    st_.J(1), lv.thr(0), lv.thr(1),
                    c.reclassify >= 0 ? c.reclassify == 0 ? " after an accelerometer raise"
                                                          : " after a gyro raise"
                                      : "");
      st_.model_mismatch = true;
      pending_stats_.clear();
      st_.mismatch_reason = buf;
      ++st_.mismatches;
      mismatch_since_ = t;
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
        set_condition(static_cast<Sensor>(k), kResidual, false, sens_[k].cond.kind, t,
                      "residual back below " + std::to_string(leave), out);
        sens_[k].below_since = kNaN;
      }
    } else {
      sens_[k].below_since = kNaN;
    }
  }
}

double Isolator::onset_estimate(int ch, double t) const {
  // Walk back over the contiguous run of clearly abnormal structured residuals.
  const auto& h = chan_[ch].hist_s;
  double onset = t;
  int quiet = 0;
  for (auto it = h.rbegin(); it != h.rend(); ++it) {
    if (std::abs(it->second) > 2.0) {
      onset = it->first;
      quiet = 0;
    } else if (++quiet > 2) {
      break;
    }
  }
  return onset;
}

FaultKind Isolator::classify(int ch) const {
  // 0. Stuck: the channel repeats its value exactly (a healthy, noisy sensor never does).
  if (checks_.repeats(ch) >= 2) return FaultKind::kStuck;
  // 1. Spikes: the excess energy of the window sits in one or two samples.
  const Window& w = act_.win_sl[ch];
  if (w.empty()) return FaultKind::kUnknown;
  std::vector<double> sq;
  sq.reserve(w.size());
  double total = 0, sum = 0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double x = w.at(i);
    sq.push_back(x * x);
    total += x * x;
    sum += x;
  }
  std::sort(sq.begin(), sq.end(), std::greater<double>());
  const double nw = static_cast<double>(w.size());
  const double top2 = sq[0] + (sq.size() > 1 ? sq[1] : 0.0);
  const double excess = total - nw;
  if (excess > 0 && top2 - 2.0 > 0.7 * excess) return FaultKind::kSpikes;
  // 2. Noise increase: energy without a consistent sign.
  const double mean = sum / nw, ms = total / nw;
  if (mean * mean < 0.2 * ms) return FaultKind::kNoise;
  return classify_shape(ch);
}

FaultKind Isolator::classify_shape(int ch) const {
  // Bias, drift or scale from the cross residual d_i = f_i + noise (the fault estimate):
  // best step  d = a + g 1(t >= tau), best hinge d = a + b max(0, t - tau), best scale
  // d = a + k x 1(t >= tau) (x: the other observer's estimate of the channel).
  const auto& d = chan_[ch].hist_d;
  const auto& x = chan_[ch].hist_x;
  const std::size_t m = d.size();
  if (m < 8 || x.size() != m) return FaultKind::kBias;
  // Two-regressor least squares with intercept: SSE of d on [1, z].
  const auto sse2 = [&](const std::vector<double>& z) {
    double sz = 0, szz = 0, sd = 0, sdd = 0, szd = 0;
    for (std::size_t i = 0; i < m; ++i) {
      sz += z[i];
      szz += z[i] * z[i];
      sd += d[i].second;
      sdd += d[i].second * d[i].second;
      szd += z[i] * d[i].second;
    }
    const double n = static_cast<double>(m);
    const double vzz = szz - sz * sz / n, vdd = sdd - sd * sd / n, vzd = szd - sz * sd / n;
    return vzz > 0 ? vdd - vzd * vzd / vzz : vdd;
  };
  double best_step = 1e300, best_hinge = 1e300, best_scale = 1e300;
  std::vector<double> z(m);
  const std::size_t stride = std::max<std::size_t>(1, m / 100);
  for (std::size_t k = 1; k + 2 < m; k += stride) {
    const double tau = d[k].first;
    for (std::size_t i = 0; i < m; ++i) z[i] = i >= k ? 1.0 : 0.0;
    best_step = std::min(best_step, sse2(z));
    for (std::size_t i = 0; i < m; ++i) z[i] = std::max(0.0, d[i].first - tau);
    best_hinge = std::min(best_hinge, sse2(z));
    for (std::size_t i = 0; i < m; ++i) z[i] = i >= k ? x[i].second : 0.0;
    best_scale = std::min(best_scale, sse2(z));
  }
  // A scale error on a signal that moves like a ramp fits a hinge as well, and a drift
  // fits a scale: each needs to beat the other clearly, else the common offset (bias).
  if (best_scale < 0.6 * best_step && best_scale < 0.8 * best_hinge) return FaultKind::kScale;
  if (best_hinge < 0.8 * best_step && best_hinge < 0.8 * best_scale) return FaultKind::kDrift;
  return FaultKind::kBias;
}

bool Isolator::noise_like(int ch, double t_raise) const {
  // The cross residual d_i (unaffected by the reconfiguration of observer i; zero-mean when
  // healthy) since the raise, against its healthy spread (learned, or the seconds before
  // the raise if larger): a noise increase spreads d without moving it.
  double n0 = 0, s0 = 0, ss0 = 0, n1 = 0, s1 = 0, ss1 = 0;
  for (const auto& [t, d] : chan_[ch].hist_d) {
    if (t < t_raise - 1.0) {
      n0 += 1;
      s0 += d;
      ss0 += d * d;
    } else if (t >= t_raise - 0.5) {
      n1 += 1;
      s1 += d;
      ss1 += d * d;
    }
  }
  if (n0 < 10 || n1 < 10) return false;
  const double sd = act_.sigma_d(ch);
  const double v0 = std::max(ss0 / n0 - (s0 / n0) * (s0 / n0), sd * sd);
  const double m1 = s1 / n1, v1 = ss1 / n1 - m1 * m1;
  return v1 > 2.0 * v0 && m1 * m1 < 0.2 * v1;
}

}  // namespace usvfdi
