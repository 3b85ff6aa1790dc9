#include "usv_fdi/core/isolation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace usvfdi {
namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("isolation.") + field + " = " + std::to_string(value) +
                                ": " + what);
  }
}

int sensor_index(Sensor s) { return static_cast<int>(s); }
Sensor channel_sensor(int ch) { return ch == kV ? Sensor::kAccelerometer : Sensor::kGyro; }

void prune(std::deque<double>* q, double t_min) {
  while (!q->empty() && q->front() < t_min) q->pop_front();
}
void prune(std::deque<std::pair<double, double>>* q, double t_min) {
  while (!q->empty() && q->front().first < t_min) q->pop_front();
}

double median(std::vector<double>* v) {
  if (v->empty()) return 0.0;
  auto mid = v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2);
  std::nth_element(v->begin(), mid, v->end());
  return *mid;
}

/// 1.4826 * median absolute deviation: the standard deviation for Gaussian data, robust to
/// outliers and to a fault covering less than half of the data.
double robust_std(std::vector<double>* v) {
  if (v->size() < 2) return 0.0;
  const double m = median(v);
  std::vector<double> dev(v->size());
  for (std::size_t i = 0; i < v->size(); ++i) dev[i] = std::abs((*v)[i] - m);
  return 1.4826 * median(&dev);
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
  require(min_active_time >= 0, "min_active_time", min_active_time, "must be >= 0");
  require(c_min > 0 && c_min <= 1, "c_min", c_min, "must lie in (0, 1]");
  require(c_margin >= 0 && c_margin < 1, "c_margin", c_margin, "must lie in [0, 1)");
  require(resume_time >= 0, "resume_time", resume_time, "must be >= 0");
  require(stale_timeout > 0, "stale_timeout", stale_timeout, "must be > 0");
  require(stuck_time > 0, "stuck_time", stuck_time, "must be > 0");
  require(stuck_min_samples >= 2, "stuck_min_samples", stuck_min_samples, "must be >= 2");
  require(max_abs_v > 0, "max_abs_v", max_abs_v, "must be > 0");
  require(max_abs_r > 0, "max_abs_r", max_abs_r, "must be > 0");
  require(max_abs_delta > 0, "max_abs_delta", max_abs_delta, "must be > 0");
  require(spike_gate > clip, "spike_gate", spike_gate, "must exceed clip");
  require(spike_window > 0, "spike_window", spike_window, "must be > 0");
  require(spike_count >= 1, "spike_count", spike_count, "must be >= 1");
  require(invalid_count >= 1, "invalid_count", invalid_count, "must be >= 1");
  require(classify_window > 0, "classify_window", classify_window, "must be > 0");
}

void Isolator::Window::push(double x, std::size_t n) {
  v.push_back(x);
  sum += x;
  while (v.size() > n) {
    sum -= v.front();
    v.pop_front();
  }
  if (v.size() == n && (n & 63) == 0) {  // bound round-off drift of the running sum
    sum = 0;
    for (double e : v) sum += e;
  }
}

Isolator::Isolator(const IsolationParams& params, const Vec2& B) : p_(params), B_(B) {
  p_.validate();
  if (!B.allFinite()) throw std::invalid_argument("model.B must be finite");
  obs_v_.set_channel(kV);
  obs_g_.set_channel(kR);
  scales_configured_ = p_.sigma_v > 0;
  floor_s_ = floor_d_ = Vec2(p_.sigma_floor_v, p_.sigma_floor_r);
  const double pmin = std::min(p_.poles_v.cwiseAbs().minCoeff(), p_.poles_g.cwiseAbs().minCoeff());
  settle_time_ = p_.settle_time >= 0 ? p_.settle_time : 3.0 / pmin;
}

bool Isolator::design(const Mat2& A) {
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
  obs_v_.set_design(dv, B_);
  obs_g_.set_design(dg, B_);
  st_.A_design = A;
  st_.k_v = dv.k;
  st_.k_g = dg.k;
  theory_scales_pending_ = scales_configured_;
  return true;
}

void Isolator::set_estimate(const Estimate& est) {
  if (!st_.armed) {
    if (!est.converged) return;
    if (!design(est.A)) return;
    st_.armed = true;
    t_armed_ = have_prev_ ? prev_.t : est.t;
    settle_until_ = t_armed_ + settle_time_;
    const Vec2 y0(std::isfinite(prev_.v) ? prev_.v : 0.0, std::isfinite(prev_.r) ? prev_.r : 0.0);
    obs_v_.reset(y0);
    obs_g_.reset(y0);
    return;
  }
  const double ref = st_.A_design.norm();
  if ((est.A - st_.A_design).norm() > p_.redesign_tolerance * ref) design(est.A);
}

double Isolator::learned_threshold(std::vector<double>* healthy) const {
  const double med = median(healthy);
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
  d.threshold = st_.threshold;
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
  Condition& c = cond_[sensor_index(sensor)];
  const unsigned before = c.sources;
  c.sources = on ? (c.sources | src) : (c.sources & ~src);
  if (before == 0 && c.sources != 0) {
    c.active = true;
    c.kind = kind;
    Detection d = make_detection(sensor, true, kind, t);
    if (src == kResidual && sensor != Sensor::kUnknown) {
      d.onset_time = onset_estimate(sensor_index(sensor), t);
    }
    d.message = message;
    out->push_back(d);
  } else if (before != 0 && c.sources == 0) {
    c.active = false;
    Detection d = make_detection(sensor, false, c.kind, t);
    d.message = message;
    out->push_back(d);
  }
}

bool Isolator::update(const Sample& s, std::vector<Detection>* out) {
  if (!std::isfinite(s.t)) {
    ++st_.input.invalid_values;
    return false;
  }
  if (have_prev_ && !(s.t > prev_.t)) {
    ++st_.input.rejected_time;
    ch_[2].invalids.push_back(prev_.t);  // timing errors count against "unknown"
    prune(&ch_[2].invalids, prev_.t - p_.spike_window);
    const bool on = static_cast<int>(ch_[2].invalids.size()) >= p_.invalid_count;
    if (on) {
      set_condition(Sensor::kUnknown, kInvalid, true, FaultKind::kInvalid, prev_.t,
                    "sample timestamps repeat or go backwards", out);
    }
    t_last_suspect_ = prev_.t;
    freeze_ = true;
    return false;
  }
  const double dt = have_prev_ ? s.t - prev_.t : 0.0;
  ++st_.samples;
  if (have_prev_ && dt > p_.stale_timeout) ++st_.input.gaps;
  sensor_checks(s, out);
  if (st_.armed) residual_checks(s, dt, out);

  // Freeze identification while anything is suspect, and for resume_time after.
  bool suspect = !st_.input.v_ok || !st_.input.r_ok || !st_.input.delta_ok || !std::isfinite(s.v) ||
                 !std::isfinite(s.r) || !std::isfinite(s.delta);
  for (const Condition& c : cond_) suspect = suspect || c.active;
  if (st_.armed && !st_.learning && !st_.settling) {
    suspect = suspect || st_.J.maxCoeff() > p_.exit_ratio * st_.threshold ||
              st_.D.maxCoeff() > p_.exit_ratio * st_.threshold_d;
  }
  if (suspect) t_last_suspect_ = s.t;
  freeze_ = s.t - t_last_suspect_ < p_.resume_time;
  prev_ = s;
  have_prev_ = true;
  return true;
}

void Isolator::sensor_checks(const Sample& s, std::vector<Detection>* out) {
  const double values[3] = {s.v, s.r, s.delta};
  const double limits[3] = {p_.max_abs_v, p_.max_abs_r, p_.max_abs_delta};
  bool ok[3];
  for (int c = 0; c < 3; ++c) {
    Channel& ch = ch_[c];
    if (std::isnan(ch.last_valid_t)) ch.last_valid_t = s.t;
    const double x = values[c];
    const bool missing = std::isnan(x);
    const bool absurd = !missing && !(std::abs(x) <= limits[c]);  // Inf or out of range
    if (absurd) {
      ++st_.input.invalid_values;
      ch.invalids.push_back(s.t);
    }
    prune(&ch.invalids, s.t - p_.spike_window);
    const bool valid = !missing && !absurd;
    if (valid) {
      if (x == ch.last_value) {
        if (ch.stuck_samples == 0) ch.stuck_since = ch.last_valid_t;
        ++ch.stuck_samples;
      } else {
        ch.stuck_samples = 0;
        ch.stuck_since = kNaN;
      }
      ch.last_value = x;
      ch.last_valid_t = s.t;
    }
    const bool stale = s.t - ch.last_valid_t > p_.stale_timeout;
    const bool stuck =
        ch.stuck_samples + 1 >= p_.stuck_min_samples && s.t - ch.stuck_since >= p_.stuck_time;
    const bool invalid = static_cast<int>(ch.invalids.size()) >= p_.invalid_count;
    ok[c] = !stale && !invalid;
    if (c == 2) continue;  // the rudder is not an INS sensor: it pauses FDI (status flag)
    const Sensor sensor = channel_sensor(c);
    const char* name = c == kV ? "accelerometer channel v" : "gyro channel r";
    const bool was_stale = cond_[c].sources & kStale;
    if (stale != was_stale) {
      set_condition(sensor, kStale, stale, FaultKind::kStale, s.t,
                    std::string(name) + (stale ? ": no valid value for " +
                                                     std::to_string(s.t - ch.last_valid_t) + " s"
                                               : ": valid values again"),
                    out);
    }
    const bool was_stuck = cond_[c].sources & kStuck;
    if (stuck != was_stuck) {
      set_condition(sensor, kStuck, stuck, FaultKind::kStuck, s.t,
                    std::string(name) + (stuck ? ": output frozen at " + std::to_string(x)
                                               : ": output moves again"),
                    out);
    }
    const bool was_invalid = cond_[c].sources & kInvalid;
    if (invalid != was_invalid) {
      set_condition(sensor, kInvalid, invalid, FaultKind::kInvalid, s.t,
                    std::string(name) + (invalid ? ": repeated non-finite or absurd values"
                                                 : ": values plausible again"),
                    out);
    }
  }
  st_.input.v_ok = ok[0] && !(cond_[0].sources & kStuck);
  st_.input.r_ok = ok[1] && !(cond_[1].sources & kStuck);
  st_.input.delta_ok = ok[2];
  if (std::isfinite(s.delta) && std::abs(s.delta) <= p_.max_abs_delta) last_delta_ = s.delta;
  // Timing errors age out of the unknown channel too.
  prune(&ch_[2].invalids, s.t - p_.spike_window);
  if ((cond_[2].sources & kInvalid) && ch_[2].invalids.empty()) {
    set_condition(Sensor::kUnknown, kInvalid, false, FaultKind::kInvalid, s.t,
                  "sample timestamps increase again", out);
  }
}

void Isolator::residual_checks(const Sample& s, double dt, std::vector<Detection>* out) {
  if (!obs_v_.ready() || !obs_g_.ready()) return;
  const auto usable = [&](double x, double lim) { return std::isfinite(x) && std::abs(x) <= lim; };
  const bool v_ok = usable(s.v, p_.max_abs_v);
  const bool r_ok = usable(s.r, p_.max_abs_r);
  // Propagate the observers over [t_{k-1}, t_k] with the previous inputs held.
  if (have_prev_ && dt > 0) {
    if (dt > p_.stale_timeout) {
      // A gap: restart the observers from the measurements and let them settle again.
      const Vec2 y0(v_ok ? s.v : obs_v_.x()(0), r_ok ? s.r : obs_g_.x()(1));
      obs_v_.reset(y0);
      obs_g_.reset(y0);
      settle_until_ = s.t + settle_time_;
    } else {
      const double d = usable(prev_.delta, p_.max_abs_delta) ? prev_.delta
                       : std::isfinite(last_delta_)          ? last_delta_
                                                             : 0.0;
      // While a sensor is faulty, its dedicated observer is driven by the other observer's
      // estimate of that channel instead (reconfiguration): it keeps tracking the vessel, so
      // the fault stays fully visible and the residual is clean the moment the fault ends.
      const bool fa = cond_[0].active, fg = cond_[1].active;
      const bool pv = usable(prev_.v, p_.max_abs_v) && !fa;
      const bool pr = usable(prev_.r, p_.max_abs_r) && !fg;
      const double yv = pv ? prev_.v : obs_g_.x()(0);
      const double yr = pr ? prev_.r : obs_v_.x()(1);
      const bool use_v = pv || (fa && !fg);
      const bool use_r = pr || (fg && !fa);
      obs_v_.step(dt, d, yv, use_v);
      obs_g_.step(dt, d, yr, use_r);
    }
  }
  st_.settling = s.t < settle_until_;
  if (st_.settling || !(dt > 0) || !st_.input.delta_ok) return;

  if (theory_scales_pending_) {
    // Innovation variance = sensor noise + observer error driven by the driving sensor.
    Mat2 Pv, Pg;
    const bool okv = discrete_lyapunov(obs_v_.Ad(), obs_v_.Gy(), &Pv);
    const bool okg = discrete_lyapunov(obs_g_.Ad(), obs_g_.Gy(), &Pg);
    if (okv && okg) {
      const double sv2 = p_.sigma_v * p_.sigma_v, sr2 = p_.sigma_r * p_.sigma_r;
      // Floors for the learned scales: what sensor noise alone would give.
      floor_s_ = Vec2(std::sqrt(sv2 + sv2 * Pv(0, 0)), std::sqrt(sr2 + sr2 * Pg(1, 1)));
      floor_d_ = Vec2(std::sqrt(sv2 + sr2 * Pg(0, 0)), std::sqrt(sr2 + sv2 * Pv(1, 1)));
    }
    theory_scales_pending_ = false;
  }

  const double raw[4] = {v_ok ? s.v - obs_v_.x()(0) : kNaN, r_ok ? s.r - obs_g_.x()(1) : kNaN,
                         v_ok ? s.v - obs_g_.x()(0) : kNaN, r_ok ? s.r - obs_v_.x()(1) : kNaN};

  // Learning: first half scales, second half the healthy distribution of J_N.
  const double t_learn0 = t_armed_ + settle_time_;
  st_.learning = !scales_learned_;
  if (!scales_learned_) {
    if (s.t - t_learn0 < 0.5 * p_.learn_time) {
      if (v_ok && r_ok) {
        for (int i = 0; i < 4; ++i) learn_raw_[i].push_back(raw[i]);
      }
      return;
    }
    if (st_.sigma_s(0) == 0.0) {
      st_.sigma_s(0) = std::max(robust_std(&learn_raw_[0]), floor_s_(0));
      st_.sigma_s(1) = std::max(robust_std(&learn_raw_[1]), floor_s_(1));
      st_.sigma_d(0) = std::max(robust_std(&learn_raw_[2]), floor_d_(0));
      st_.sigma_d(1) = std::max(robust_std(&learn_raw_[3]), floor_d_(1));
      for (auto& v : learn_raw_) std::vector<double>().swap(v);
    }
  }

  const std::size_t n = window_samples(dt);
  const double c2 = p_.clip * p_.clip;
  Vec2 sw(kNaN, kNaN);
  for (int c = 0; c < 2; ++c) {
    if (!std::isfinite(raw[c])) continue;
    sw(c) = raw[c] / st_.sigma_s(c);
    const double dw = raw[2 + c] / st_.sigma_d(c);
    win_s_[c].push(std::min(sw(c) * sw(c), c2), n);
    win_sl_[c].push(sw(c), n);
    win_d_[c].push(std::min(dw * dw, c2), n);
    hist_s_[c].emplace_back(s.t, sw(c));
    hist_d_[c].emplace_back(s.t, raw[2 + c]);
    hist_x_[c].emplace_back(s.t, c == kV ? obs_g_.x()(0) : obs_v_.x()(1));
    prune(&hist_s_[c], s.t - p_.classify_window);
    prune(&hist_d_[c], s.t - p_.classify_window);
    prune(&hist_x_[c], s.t - p_.classify_window);
  }
  st_.J = Vec2(win_s_[0].mean(), win_s_[1].mean());
  st_.D = Vec2(win_d_[0].mean(), win_d_[1].mean());
  const Vec2 e(std::sqrt(std::max(0.0, st_.J(0) - 1.0)), std::sqrt(std::max(0.0, st_.J(1) - 1.0)));
  const double en = e.norm();
  st_.c_a = en > 0 ? e(0) / en : 0.0;
  st_.c_g = en > 0 ? e(1) / en : 0.0;

  if (!scales_learned_) {
    if (win_s_[0].v.size() >= n && win_s_[1].v.size() >= n) {
      for (int c = 0; c < 2; ++c) {
        learn_J_.push_back(st_.J(c));
        learn_D_.push_back(st_.D(c));
      }
    }
    if (s.t - t_learn0 >= p_.learn_time) {
      st_.threshold = learned_threshold(&learn_J_);
      st_.threshold_d = learned_threshold(&learn_D_);
      std::vector<double>().swap(learn_J_);
      std::vector<double>().swap(learn_D_);
      scales_learned_ = true;
      st_.learning = false;
    }
    return;
  }

  // Spikes: runs of one or two outliers.
  for (int c = 0; c < 2; ++c) {
    if (!std::isfinite(sw(c))) continue;
    Channel& ch = ch_[c];
    // A spike is a run of one or two outliers with ordinary samples on both sides.
    const double a = std::abs(sw(c));
    if (a > p_.spike_gate) {
      if (ch.outlier_run++ == 0) {
        ch.outlier_start = s.t;
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
    prune(&ch.spikes, s.t - p_.spike_window);
    const int count = static_cast<int>(ch.spikes.size());
    const bool on = count >= p_.spike_count;
    const bool was = cond_[c].sources & kSpikes;
    if (on != was && (on || count == 0)) {
      set_condition(channel_sensor(c), kSpikes, on, FaultKind::kSpikes, s.t,
                    std::string(c == kV ? "accelerometer" : "gyro") +
                        (on ? ": " + std::to_string(count) + " spikes in " +
                                  std::to_string(p_.spike_window) + " s"
                            : ": no spikes in the window"),
                    out);
    }
  }

  // Residual evaluation with hysteresis.
  const double thr = st_.threshold, thr_exit = p_.exit_ratio * st_.threshold;
  const double thr_exit_d = p_.exit_ratio * st_.threshold_d;
  const double eps_t = 1e-9;
  const bool a_res = cond_[0].sources & kResidual, g_res = cond_[1].sources & kResidual,
             u_res = cond_[2].sources & kResidual;
  // Candidate raise.
  int candidate = -1;
  if (!a_res && !g_res && !u_res) {
    if (st_.J.maxCoeff() > thr) {
      if (st_.c_a >= p_.c_min && st_.c_a - st_.c_g >= p_.c_margin) {
        candidate = 0;
      } else if (st_.c_g >= p_.c_min && st_.c_g - st_.c_a >= p_.c_margin) {
        candidate = 1;
      } else {
        candidate = 2;
      }
    }
  } else if (!u_res) {
    // One sensor already raised: the other raises on its own channel (structured residual
    // entries are blind to each other's faults).
    if (a_res && !g_res && st_.J(1) > thr) candidate = 1;
    if (g_res && !a_res && st_.J(0) > thr) candidate = 0;
  }
  for (int k = 0; k < 3; ++k) {
    if (k == candidate) {
      if (std::isnan(above_since_[k])) above_since_[k] = s.t;
      if (s.t - above_since_[k] + eps_t >= p_.enter_time) {
        const Sensor sensor = static_cast<Sensor>(k);
        const FaultKind kind = k < 2 ? classify(k) : FaultKind::kUnknown;
        if (k < 2) refine_at_[k] = s.t + 0.5 * p_.classify_window;
        std::string msg =
            k < 2 ? std::string("residual of the ") + (k == 0 ? "accelerometer" : "gyro") +
                        " channel: J_N " + std::to_string(st_.J(k)) + " > " + std::to_string(thr)
                  : "residual on both channels, not isolated: J_N " +
                        std::to_string(st_.J.maxCoeff()) + " > " + std::to_string(thr);
        set_condition(sensor, kResidual, true, kind, s.t, msg, out);
        raised_at_[k] = s.t;
        above_since_[k] = kNaN;
        below_since_[k] = kNaN;
      }
    } else {
      above_since_[k] = kNaN;
    }
  }
  // Refine the kind once more data after the raise shows the fault's shape.
  for (int k = 0; k < 2; ++k) {
    if (std::isnan(refine_at_[k]) || s.t < refine_at_[k]) continue;
    refine_at_[k] = kNaN;
    Condition& c = cond_[k];
    if (!(c.sources & kResidual)) continue;
    if (c.kind != FaultKind::kBias && c.kind != FaultKind::kDrift && c.kind != FaultKind::kScale) {
      continue;
    }
    const FaultKind refined = classify_shape(k);
    if (refined == c.kind) continue;
    Detection d = make_detection(static_cast<Sensor>(k), true, refined, s.t);
    d.update = true;
    d.message = std::string("kind refined from ") + to_string(c.kind) + " to " + to_string(refined);
    c.kind = refined;
    out->push_back(d);
  }
  // Hold / clear. While sensor i is faulty its dedicated observer is reconfigured (driven by
  // the other observer), so its structured entry takes the cross residual's scale; the cross
  // residual d_i = y_i - x_i(observer blind to i) carries the fault without absorption.
  for (int k = 0; k < 3; ++k) {
    if (!(cond_[k].sources & kResidual) || k == candidate) continue;
    // The reconfigured observer's structured entry has about the cross residual's scale.
    const double rescale =
        k < 2 ? std::min(1.0, std::pow(st_.sigma_s(k) / st_.sigma_d(k), 2.0)) : 1.0;
    const double hold = k < 2 ? std::max(st_.D(k), rescale * st_.J(k)) : st_.J.maxCoeff();
    if (hold < (k < 2 ? thr_exit_d : thr_exit)) {
      if (std::isnan(below_since_[k])) below_since_[k] = s.t;
      if (s.t - below_since_[k] + eps_t >= p_.leave_time &&
          s.t - raised_at_[k] + eps_t >= p_.min_active_time) {
        set_condition(static_cast<Sensor>(k), kResidual, false, cond_[k].kind, s.t,
                      "residual back below " + std::to_string(k < 2 ? thr_exit_d : thr_exit), out);
        below_since_[k] = kNaN;
      }
    } else {
      below_since_[k] = kNaN;
    }
  }
}

double Isolator::onset_estimate(int ch, double t) const {
  // Walk back over the contiguous run of clearly abnormal structured residuals.
  const auto& h = hist_s_[ch];
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
  if (ch_[ch].stuck_samples >= 2) return FaultKind::kStuck;
  // 1. Spikes: the excess energy of the window sits in one or two samples.
  const auto& w = win_sl_[ch].v;
  if (w.empty()) return FaultKind::kUnknown;
  std::vector<double> sq;
  sq.reserve(w.size());
  double total = 0, sum = 0;
  for (double x : w) {
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
  const auto& d = hist_d_[ch];
  const auto& x = hist_x_[ch];
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
  if (best_scale < 0.6 * std::min(best_step, best_hinge)) return FaultKind::kScale;
  if (best_hinge < 0.8 * best_step) return FaultKind::kDrift;
  return FaultKind::kBias;
}

}  // namespace usvfdi
