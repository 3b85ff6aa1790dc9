#include "usv_fdi/core/jump_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace usvfdi {
namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("jump.") + field + " = " + std::to_string(value) +
                                ": " + what);
  }
}

constexpr double kBlock = 10.0;       ///< length of a block of the healthy maxima [s]
constexpr int kIntervalSamples = 11;  ///< samples whose median interval sets dt
constexpr double kRebase = 100.0;     ///< re-base int(delta) beyond this [rad s]

}  // namespace

void JumpParams::validate() const {
  require(pre_window > 0, "pre_window", pre_window, "must be > 0");
  require(post_window > 0, "post_window", post_window, "must be > 0");
  require(min_samples >= 3, "min_samples", min_samples, "must be >= 3");
  require(persist_samples >= 1 && persist_samples <= min_samples, "persist_samples",
          persist_samples, "must lie in [1, min_samples]");
  require(persist_time >= 0 && persist_time < post_window, "persist_time", persist_time,
          "must lie in [0, post_window)");
  require(threshold > 1, "threshold", threshold, "must be > 1");
  require(noise_threshold > 1, "noise_threshold", noise_threshold, "must be > 1");
  require(margin >= 1, "margin", margin, "must be >= 1");
  require(noise_window > 0, "noise_window", noise_window, "must be > 0");
  require(learn_time >= 0, "learn_time", learn_time, "must be >= 0");
  require(history >= kBlock, "history", history, "must be >= 10 s");
  require(scale_time > 0, "scale_time", scale_time, "must be > 0");
  require(leave_time >= 0, "leave_time", leave_time, "must be >= 0");
  require(exit_ratio > 0 && exit_ratio <= 1, "exit_ratio", exit_ratio, "must lie in (0, 1]");
  require(hold_max > 0, "hold_max", hold_max, "must be > 0");
  require(max_gap > 0, "max_gap", max_gap, "must be > 0");
  require(b_uncertainty >= 0, "b_uncertainty", b_uncertainty, "must be >= 0");
  require(rudder_lag >= 0, "rudder_lag", rudder_lag, "must be >= 0");
}

JumpCheck::JumpCheck(const JumpParams& p, double b, double sigma_floor)
    : p_(p), b_(b), floor_(sigma_floor) {
  p_.validate();
  if (!std::isfinite(b)) throw std::invalid_argument("jump check: B must be finite");
  if (!(sigma_floor > 0)) throw std::invalid_argument("jump check: the scale floor must be > 0");
  const auto blocks = static_cast<std::size_t>(std::ceil(p_.history / kBlock));
  blocks_T_.assign(blocks, 0.0);
  blocks_N_.assign(blocks, 0.0);
}

void JumpCheck::restart() {
  head_ = 0;
  n_ = 0;
  I_ = 0.0;
  last_t_ = kNaN;
  last_z_ = kNaN;
  last_I_ = kNaN;
  last_d_ = kNaN;
  d2_n_ = 0;
  d2_next_ = 0;
}

void JumpCheck::resize_windows() {
  L_ = std::max(p_.min_samples, static_cast<int>(std::lround(p_.pre_window / dt_)));
  M_ = std::max(p_.min_samples, static_cast<int>(std::lround(p_.post_window / dt_)));
  persist_ = std::min(
      M_, std::max(p_.persist_samples, static_cast<int>(std::lround(p_.persist_time / dt_)) + 1));
  const auto cap = static_cast<std::size_t>(L_ + M_);
  z_.assign(cap, 0.0);
  i_.assign(cap, 0.0);
  d_.assign(cap, 0.0);
  ts_.assign(cap, 0.0);
  for (Prefix* q : {&pz_, &pi_, &pd_}) {
    q->p0.assign(cap + 1, 0.0);
    q->p1.assign(cap + 1, 0.0);
  }
  const auto w = static_cast<std::size_t>(
      std::max<long>(2L * p_.min_samples, std::lround(p_.noise_window / dt_)));
  d2_.assign(w, 0.0);
}

void JumpCheck::push(double t, double z, double I, double delta) {
  const std::size_t cap = z_.size();
  const std::size_t at = (head_ + n_) % cap;
  z_[at] = z;
  i_[at] = I;
  d_[at] = delta;
  ts_[at] = t;
  if (n_ < cap) {
    ++n_;
  } else {
    head_ = (head_ + 1) % cap;
  }
}

double JumpCheck::step_of(const Prefix& q, int m) const {
  // Logical positions 0 (oldest) .. n-1 (newest); pre window [a, b), post [b, n).
  const int n = static_cast<int>(n_);
  const int b = n - 1 - m, a = b - L_;
  const double S0 = q.p0[b] - q.p0[a], S1 = q.p1[b] - q.p1[a];
  const double jbar = 0.5 * (a + b - 1);
  const double Sjj = L_ * (static_cast<double>(L_) * L_ - 1.0) / 12.0;
  const double slope = (S1 - jbar * S0) / Sjj;
  const double post_mean = (q.p0[n] - q.p0[b]) / (m + 1);
  return post_mean - (S0 / L_ + slope * (0.5 * (b + n - 1) - jbar));
}

double JumpCheck::step_stat(int m, double* f) const {
  const int n = static_cast<int>(n_);
  const int b = n - 1 - m, a = b - L_;
  const double jbar = 0.5 * (a + b - 1);
  const double Sjj = L_ * (static_cast<double>(L_) * L_ - 1.0) / 12.0;
  const double lever = 0.5 * (b + n - 1) - jbar;
  *f = step_of(pz_, m);
  // What an error of B (relative b_uncertainty) and a rudder sensor lag (rudder_lag) could
  // make of the same window: the rudder's part of z is known only that well.
  const double doubt = std::abs(b_) * (p_.b_uncertainty * std::abs(step_of(pi_, m)) +
                                       p_.rudder_lag * std::abs(step_of(pd_, m)));
  const double excess = std::max(0.0, std::abs(*f) - doubt);
  const double c = 1.0 / (m + 1) + 1.0 / L_ + lever * lever / Sjj;
  return excess * excess / (sigma_ * sigma_ * c);
}

bool JumpCheck::persists(int m, double f) const {
  const int n = static_cast<int>(n_);
  const int b = n - 1 - m, a = b - L_;
  const double S0 = pz_.p0[b] - pz_.p0[a], S1 = pz_.p1[b] - pz_.p1[a];
  const double jbar = 0.5 * (a + b - 1);
  const double Sjj = L_ * (static_cast<double>(L_) * L_ - 1.0) / 12.0;
  const double slope = (S1 - jbar * S0) / Sjj;
  // The level before the onset is clean: no sample off the line by half the step (an
  // outlier at its end would tilt the line and fake a step the other way).
  for (int j = a; j < b; ++j) {
    const double dev = z_[(head_ + j) % z_.size()] - (S0 / L_ + slope * (j - jbar));
    if (std::abs(dev) > 0.5 * std::abs(f)) return false;
  }
  const double sign = f < 0 ? -1.0 : 1.0;
  int count = 0;
  double spread = 0.0;  // of the post samples about the step
  for (int j = b; j < n; ++j) {
    const double dev = z_[(head_ + j) % z_.size()] - (S0 / L_ + slope * (j - jbar));
    if (sign * dev > 0.5 * std::abs(f)) ++count;
    spread += (dev - f) * (dev - f);
  }
  // A level that moved and stays (not a noise burst whose mean happens to be off).
  return count >= persist_ && count >= 0.6 * (m + 1) &&
         std::sqrt(spread / (m + 1)) < 0.5 * std::abs(f);
}

double JumpCheck::healthy_max(const std::vector<double>& blocks, double current) const {
  double mx = current;
  for (double x : blocks) mx = std::max(mx, x);
  return mx;
}

void JumpCheck::learn(double t, double T, double N, double e2, double d2sq, bool learn_ok) {
  if (!learn_ok) return;
  // The innovation scales: the mean of the first squares, then an exponential average over
  // scale_time of squares winsorised at 4 sigma (a fault covering a few samples barely moves it).
  sigma_seen_ += 1.0;
  const double w = std::max(1.0 / sigma_seen_, std::min(1.0, dt_ / p_.scale_time));
  const auto average = [&](double* scale, double x2) {
    const double s2 = (*scale) * (*scale);
    const double x = sigma_seen_ > 20 ? std::min(x2, 16.0 * s2) : x2;
    *scale = std::max(std::sqrt(s2 + w * (x - s2)), floor_);
  };
  average(&sigma_, e2);
  average(&sigma2_, d2sq);
  learned_ += dt_;
  // Healthy maxima per block of kBlock seconds.
  if (std::isnan(block_start_)) block_start_ = t;
  // (once the scale has settled: the first samples' statistics say nothing of the hull)
  if (learned_ >= 0.5 * p_.learn_time) {
    block_T_ = std::max(block_T_, T);
    block_N_ = std::max(block_N_, N);
  }
  if (t - block_start_ >= kBlock) {
    blocks_T_[block_next_] = block_T_;
    blocks_N_[block_next_] = block_N_;
    block_next_ = (block_next_ + 1) % blocks_T_.size();
    block_T_ = block_N_ = 0.0;
    block_start_ = t;
  }
}

JumpVerdict JumpCheck::update(double t, double y, double delta, bool learn_ok) {
  JumpVerdict v = decide(t, y, delta, learn_ok);
  // Only what an armed check found is reported (and the end of what it reported).
  if (v.step == JumpVerdict::Change::kRaise) {
    step_reported_ = armed_;
  } else if (v.step == JumpVerdict::Change::kClear) {
    if (!step_reported_) v.step = JumpVerdict::Change::kNone;
    step_reported_ = false;
  }
  if (v.noise == JumpVerdict::Change::kRaise) {
    noise_reported_ = armed_;
  } else if (v.noise == JumpVerdict::Change::kClear) {
    if (!noise_reported_) v.noise = JumpVerdict::Change::kNone;
    noise_reported_ = false;
  }
  if (!armed_ && v.step != JumpVerdict::Change::kClear) v.step = JumpVerdict::Change::kNone;
  if (!armed_ && v.noise != JumpVerdict::Change::kClear) v.noise = JumpVerdict::Change::kNone;
  if (v.step == JumpVerdict::Change::kNone && v.noise == JumpVerdict::Change::kNone) {
    v.message.clear();
  }
  return v;
}

JumpVerdict JumpCheck::decide(double t, double y, double delta, bool learn_ok) {
  JumpVerdict v;
  if (std::isfinite(delta)) {
    if (std::isfinite(last_t_) && std::isfinite(last_delta_)) {
      I_ += 0.5 * (last_delta_ + delta) * (t - last_t_);
    }
    last_delta_ = delta;
  }
  if (!std::isfinite(y) || !std::isfinite(t)) return v;
  if (raised_ && t - raised_at_ >= p_.hold_max) {
    raised_ = false;
    v.step = JumpVerdict::Change::kClear;
    v.message = "no jump back within " + std::to_string(p_.hold_max) + " s";
  }
  // The sample interval, from the first samples.
  if (dt_seen_ < kIntervalSamples) {
    if (dt_seen_ == 0) ts_.clear();
    ts_.push_back(t);
    ++dt_seen_;
    if (dt_seen_ == kIntervalSamples) {
      for (std::size_t i = 0; i + 1 < ts_.size(); ++i) ts_[i] = ts_[i + 1] - ts_[i];
      ts_.pop_back();
      std::nth_element(ts_.begin(), ts_.begin() + ts_.size() / 2, ts_.end());
      dt_ = ts_[ts_.size() / 2];
      if (!(dt_ > 0)) {
        dt_seen_ = 0;
        return v;
      }
      resize_windows();
      restart();
    } else {
      return v;
    }
  }
  // Re-base the rudder integral now and then (only differences within the windows count).
  if (std::abs(I_) > kRebase) {
    for (std::size_t i = 0; i < n_; ++i) {
      z_[(head_ + i) % z_.size()] += b_ * I_;
      i_[(head_ + i) % z_.size()] -= I_;
    }
    if (std::isfinite(last_I_)) last_I_ -= I_;
    if (std::isfinite(last_z_)) last_z_ += b_ * I_;
    I_ = 0.0;
  }
  // A long gap restarts the windows (and the rudder integral, so z is computed after).
  if (std::isfinite(last_t_) && t - last_t_ > p_.max_gap) restart();
  const double z = y - b_ * I_;
  const double dl = std::isfinite(last_delta_) ? last_delta_ : 0.0;
  if (std::isfinite(last_t_)) {
    // Dropped samples: filled on the straight line between their neighbours.
    const double gap = t - last_t_;
    const long steps = std::max(1L, std::lround(gap / dt_));
    for (long j = 1; j < steps; ++j) {
      const double w = static_cast<double>(j) / static_cast<double>(steps);
      push(last_t_ + w * gap, last_z_ + w * (z - last_z_), last_I_ + w * (I_ - last_I_),
           last_d_ + w * (dl - last_d_));
    }
  }
  push(t, z, I_, dl);
  last_t_ = t;
  last_z_ = z;
  last_I_ = I_;
  last_d_ = dl;

  // Prefix sums in logical order.
  const auto sums = [&](const std::vector<double>& x, Prefix* q) {
    for (std::size_t i = 0; i < n_; ++i) {
      const double xi = x[(head_ + i) % x.size()];
      q->p0[i + 1] = q->p0[i] + xi;
      q->p1[i + 1] = q->p1[i] + static_cast<double>(i) * xi;
    }
  };
  sums(z_, &pz_);
  sums(i_, &pi_);
  sums(d_, &pd_);
  const int n = static_cast<int>(n_);
  if (n < L_ + 1 || n < 3) return v;
  // The one-step innovation (the step test's scale).
  double f0 = 0.0;
  if (sigma_ <= 0) sigma_ = floor_;
  if (sigma2_ <= 0) sigma2_ = floor_;
  step_stat(0, &f0);
  const double c0 = 1.0 + 1.0 / L_ + std::pow(0.5 * (L_ + 1), 2) / (L_ * (L_ * L_ - 1.0) / 12.0);
  const double e2 = f0 * f0 / c0;
  // The noise test's innovation: the second difference (a jump moves two of them only, an
  // outlier three; the motion and the waves barely move them).
  const auto zat = [&](int j) { return z_[(head_ + static_cast<std::size_t>(j)) % z_.size()]; };
  const double d2 = zat(n - 1) - 2.0 * zat(n - 2) + zat(n - 3);
  d2_[d2_next_] = d2 * d2;
  d2_next_ = (d2_next_ + 1) % d2_.size();
  d2_n_ = std::min(d2_n_ + 1, d2_.size());
  // Noise statistic: their mean square without the three largest.
  N_ = 0.0;
  if (d2_n_ == d2_.size()) {
    double sum = 0.0, top[3] = {0.0, 0.0, 0.0};
    for (double x : d2_) {
      sum += x;
      if (x > top[2]) {
        top[2] = x;
        if (top[2] > top[1]) std::swap(top[1], top[2]);
        if (top[1] > top[0]) std::swap(top[0], top[1]);
      }
    }
    const double kept = static_cast<double>(d2_.size()) - 3.0;
    N_ = (sum - top[0] - top[1] - top[2]) / kept / (sigma2_ * sigma2_);
  }
  // Step statistic over the onsets the windows hold.
  T_ = 0.0;
  double f_best = 0.0;
  int m_best = -1;
  for (int m = persist_ - 1; m < M_ && n >= L_ + m + 1; ++m) {
    double f = 0.0;
    const double Tm = step_stat(m, &f);
    if (Tm > T_) {
      T_ = Tm;
      f_best = f;
      m_best = m;
    }
  }
  // Learning trails the decisions by the post window: a fault's first samples, seen before
  // it is detected, are dropped with the detection.
  pending_.push_back(Pending{t, T_, N_, e2, d2 * d2, learn_ok && !raised_ && !noise_raised_});
  const auto lag = static_cast<std::size_t>(M_);
  if (pending_.size() > lag) {
    const Pending& old = pending_.front();
    learn(old.t, old.T, old.N, old.e2, old.d2sq, old.ok);
    pending_.erase(pending_.begin());
  }
  armed_ = p_.enabled && learned_ >= p_.learn_time;
  // Watched from half the learning on (the scales have settled), reported once armed: a
  // fault before arming is kept out of the learning, and its end is not taken for a new one.
  if (!p_.enabled || learned_ < 0.5 * p_.learn_time) return v;
  const double cur_T = healthy_max(blocks_T_, block_T_);
  const double cur_N = healthy_max(blocks_N_, block_N_);
  threshold_ = std::max(p_.threshold, p_.margin * cur_T);
  noise_threshold_ = std::max(p_.noise_threshold, p_.margin * cur_N);

  // Noise rise.
  if (!noise_raised_ && N_ > noise_threshold_) {
    noise_raised_ = true;
    noise_below_since_ = kNaN;
    v.noise = JumpVerdict::Change::kRaise;
    pending_.clear();
    char buf[160];
    std::snprintf(buf, sizeof buf, "noise: innovation mean square %.3g > %.3g (scale %.3g)", N_,
                  noise_threshold_, sigma_);
    v.message = buf;
    if (raised_ && t - raised_at_ <= 2.0 * p_.noise_window) {
      raised_ = false;  // the jump raised just before was the first samples of this noise
      v.message += "; the jump before it was this";
    }
    return v;
  }
  if (noise_raised_) {
    if (N_ < p_.exit_ratio * noise_threshold_) {
      if (std::isnan(noise_below_since_)) noise_below_since_ = t;
      if (t - noise_below_since_ >= p_.leave_time) {
        noise_raised_ = false;
        v.noise = JumpVerdict::Change::kClear;
        v.message = "noise back below " + std::to_string(p_.exit_ratio * noise_threshold_);
      }
    } else {
      noise_below_since_ = kNaN;
    }
    return v;
  }
  // Step.
  if (m_best < 0 || !(T_ > threshold_) || !persists(m_best, f_best)) return v;
  const double onset = ts_[(head_ + static_cast<std::size_t>(n - 1 - m_best)) % ts_.size()];
  char buf[200];
  pending_.clear();
  if (!raised_) {
    raised_ = true;
    offset_ = f_best;
    raised_at_ = t;
    v.step = JumpVerdict::Change::kRaise;
    v.onset = onset;
    v.size = f_best;
    std::snprintf(buf, sizeof buf, "jump of %+.4g at %.3f s: T %.3g > %.3g (scale %.3g)", f_best,
                  onset, T_, threshold_, sigma_);
    v.message = buf;
  } else if (f_best * offset_ > 0 || std::abs(f_best) < 0.5 * std::abs(offset_)) {
    offset_ += f_best;  // it grew, or came back part of the way
  } else {
    offset_ += f_best;
    raised_ = false;
    v.step = JumpVerdict::Change::kClear;
    v.onset = onset;
    v.size = f_best;
    std::snprintf(buf, sizeof buf, "jump back of %+.4g at %.3f s (offset left %+.3g)", f_best,
                  onset, offset_);
    v.message = buf;
  }
  // The step leaves every window: keep only the samples from its onset on.
  const auto keep = static_cast<std::size_t>(m_best + 1);
  head_ = (head_ + n_ - keep) % z_.size();
  n_ = keep;
  return v;
}

}  // namespace usvfdi
