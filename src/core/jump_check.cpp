#include "usv_fdi/core/jump_check.hpp"

#include "usv_fdi/core/robust.hpp"

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
constexpr double kRebase = 1e4;       ///< restart the windows when int(delta) grows beyond [rad s]
constexpr int kExact = 128;           ///< sliding sums are recomputed exactly this often
/// Below this fraction of the threshold's floor a step statistic needs no discount for the
/// rudder (it cannot matter): most samples skip that work.
constexpr double kDiscountFrom = 0.25;

const JumpParams& validated(const JumpParams& p) {
  p.validate();
  return p;
}

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
  require(noise_min_samples >= 4, "noise_min_samples", noise_min_samples, "must be >= 4");
  require(learn_time >= 0, "learn_time", learn_time, "must be >= 0");
  require(history >= kBlock, "history", history, "must be >= 10 s");
  require(scale_time > 0, "scale_time", scale_time, "must be > 0");
  require(leave_time >= 0, "leave_time", leave_time, "must be >= 0");
  require(exit_ratio > 0 && exit_ratio <= 1, "exit_ratio", exit_ratio, "must lie in (0, 1]");
  require(hold_max > 0, "hold_max", hold_max, "must be > 0");
  require(max_gap > 0, "max_gap", max_gap, "must be > 0");
  require(b_uncertainty >= 0, "b_uncertainty", b_uncertainty, "must be >= 0");
  require(rudder_lag >= 0, "rudder_lag", rudder_lag, "must be >= 0");
  require(bend_margin >= 0, "bend_margin", bend_margin, "must be >= 0");
  require(bend_rate >= 0, "bend_rate", bend_rate, "must be >= 0");
}

// ------------------------------------------------------------------------------ Series

void JumpCheck::SlidingRange::reset(int w) {
  w_ = std::max(1, w);
  for (Queue* q : {&lo_, &hi_}) q->ring.assign(static_cast<std::size_t>(w_ + 1), {0, 0.0});
  clear();
}

void JumpCheck::SlidingRange::clear() {
  n_ = 0;
  for (Queue* q : {&lo_, &hi_}) q->head = q->size = 0;
}

template <typename Keep>
void JumpCheck::SlidingRange::add(Queue* q, double x, Keep keep) {
  const int cap = static_cast<int>(q->ring.size());
  // Values older than the window leave at the front; values that x outdoes at the back.
  while (q->size > 0 && q->at(0).first <= n_ - w_) {
    q->head = (q->head + 1) % cap;
    --q->size;
  }
  while (q->size > 0 && !keep(q->at(q->size - 1).second, x)) --q->size;
  q->ring[static_cast<std::size_t>((q->head + q->size) % cap)] = {n_, x};
  ++q->size;
}

void JumpCheck::SlidingRange::push(double x) {
  ++n_;
  add(&lo_, x, [](double back, double v) { return back < v; });
  add(&hi_, x, [](double back, double v) { return back > v; });
}

void JumpCheck::Series::reset(int L, int M) {
  L_ = L;
  M_ = M;
  cap_ = L + M + 1;
  x_.assign(static_cast<std::size_t>(cap_), 0.0);
  mean_.assign(x_.size(), 0.0);
  slope_.assign(x_.size(), 0.0);
  clear();
}

void JumpCheck::Series::clear() {
  newest_ = -1;
  count_ = 0;
  S0_ = S1_ = 0.0;
  since_exact_ = 0;
}

void JumpCheck::Series::push(double x) {
  newest_ = newest_ + 1 == cap_ ? 0 : newest_ + 1;
  x_[static_cast<std::size_t>(newest_)] = x;
  if (count_ >= L_) {
    const double out = at(L_);  // leaves the window of the newest L
    S1_ += -(S0_ - out) + (L_ - 1) * x;
    S0_ += x - out;
  } else {
    S1_ += count_ * x;
    S0_ += x;
  }
  if (count_ < (1 << 30)) ++count_;  // only compared with the windows' lengths
  if (count_ < L_) return;
  if (++since_exact_ >= kExact) {  // bound the round-off of the sliding sums
    since_exact_ = 0;
    S0_ = S1_ = 0.0;
    for (int j = 0; j < L_; ++j) {
      const double v = at(L_ - 1 - j);
      S0_ += v;
      S1_ += j * v;
    }
  }
  const double jbar = 0.5 * (L_ - 1);
  const double Sjj = L_ * (static_cast<double>(L_) * L_ - 1.0) / 12.0;
  mean_[static_cast<std::size_t>(newest_)] = S0_ / L_;
  slope_[static_cast<std::size_t>(newest_)] = (S1_ - jbar * S0_) / Sjj;
}

void JumpCheck::Series::steps(int m_hi, double* f) const {
  // Walks back from the newest sample (and the fit before it) without a modulo per step.
  int k = newest_, kf = newest_ == 0 ? cap_ - 1 : newest_ - 1;
  double post = 0.0;
  for (int m = 0; m <= m_hi; ++m) {
    post += x_[static_cast<std::size_t>(k)];
    const double lever = 0.5 * (L_ + 1) + 0.5 * m;  // post positions' mean - pre window's
    f[m] = post / (m + 1) -
           (mean_[static_cast<std::size_t>(kf)] + slope_[static_cast<std::size_t>(kf)] * lever);
    k = kf;
    kf = kf == 0 ? cap_ - 1 : kf - 1;
  }
}

double JumpCheck::Series::line(int m, int back) const {
  const auto k = static_cast<std::size_t>((newest_ + cap_ - (m + 1)) % cap_);
  // Local index in the fit's window (0 its oldest, L - 1 its newest).
  const double j = (L_ - 1) + (m + 1 - back);
  return mean_[k] + slope_[k] * (j - 0.5 * (L_ - 1));
}

// --------------------------------------------------------------------------- JumpCheck

JumpCheck::JumpCheck(const JumpParams& p, double b, double sigma_floor)
    : p_(validated(p)), b_(b), floor_(sigma_floor), healthy_(kBlock, p_.history) {
  if (!std::isfinite(b)) throw std::invalid_argument("jump check: B must be finite");
  if (!(sigma_floor > 0)) throw std::invalid_argument("jump check: the scale floor must be > 0");
}

void JumpCheck::resize_windows() {
  L_ = std::max(p_.min_samples, static_cast<int>(std::lround(p_.pre_window / dt_)));
  M_ = std::max(p_.min_samples, static_cast<int>(std::lround(p_.post_window / dt_)));
  persist_ = std::min(
      M_, std::max(p_.persist_samples, static_cast<int>(std::lround(p_.persist_time / dt_)) + 1));
  for (Series* s : {&z_, &i_, &d_}) s->reset(L_, M_);
  d_range_.reset(L_ + M_);
  ts_.assign(static_cast<std::size_t>(L_ + M_ + 1), 0.0);
  c_.resize(static_cast<std::size_t>(M_));
  const double Sjj = L_ * (static_cast<double>(L_) * L_ - 1.0) / 12.0;
  for (int m = 0; m < M_; ++m) {
    const double lever = 0.5 * (L_ + 1) + 0.5 * m;
    c_[static_cast<std::size_t>(m)] = 1.0 / (m + 1) + 1.0 / L_ + lever * lever / Sjj;
  }
  // f_m of t^2 / 2 (the same for any time origin: a line absorbs the rest of a shift).
  Series bend;
  bend.reset(L_, M_);
  for (int j = 0; j <= L_ + M_; ++j) bend.push(0.5 * (j * dt_) * (j * dt_));
  bend_.assign(static_cast<std::size_t>(M_), 0.0);
  bend.steps(M_ - 1, bend_.data());
  for (double& g : bend_) g = std::abs(g);
  inv_c_.resize(c_.size());
  for (std::size_t m = 0; m < c_.size(); ++m) inv_c_[m] = 1.0 / c_[m];
  f_.assign(static_cast<std::size_t>(M_), 0.0);
  fi_ = fd_ = f_;
  pending_.assign(static_cast<std::size_t>(M_), Pending{});
  pending_head_ = pending_n_ = 0;
  const auto w = static_cast<std::size_t>(
      std::max<long>({2L * p_.min_samples, static_cast<long>(p_.noise_min_samples),
                      std::lround(p_.noise_window / dt_)}));
  d2_.assign(w, 0.0);
}

void JumpCheck::restart() {
  for (Series* s : {&z_, &i_, &d_}) s->clear();
  d_range_.clear();
  I_ = 0.0;
  last_t_ = last_z_ = last_I_ = last_d_ = kNaN;
  d2_n_ = d2_next_ = 0;
  d2_sum_ = 0.0;
}

void JumpCheck::push(double t, double z, double I, double delta) {
  z_.push(z);
  i_.push(I);
  d_.push(delta);
  d_range_.push(delta);  // the range over the newest L + M: the samples the statistics use
  ts_[static_cast<std::size_t>(z_.newest())] = t;
}

void JumpCheck::keep_newest(int keep) {
  std::vector<double> t(keep), z(keep), I(keep), d(keep);
  const int cap = static_cast<int>(ts_.size());
  for (int k = 0; k < keep; ++k) {
    const int back = keep - 1 - k;
    t[k] = ts_[static_cast<std::size_t>((z_.newest() - back + cap) % cap)];
    z[k] = z_.at(back);
    I[k] = i_.at(back);
    d[k] = d_.at(back);
  }
  for (Series* s : {&z_, &i_, &d_}) s->clear();
  d_range_.clear();
  for (int k = 0; k < keep; ++k) push(t[k], z[k], I[k], d[k]);
}

void JumpCheck::step_statistics(int* m_best, double* f_best) {
  T_ = T_learn_ = swing_ = 0.0;
  *m_best = -1;
  *f_best = 0.0;
  const int m_hi = std::min(M_ - 1, z_.count() - L_ - 1);
  if (m_hi < 0) return;
  z_.steps(m_hi, f_.data());
  if (m_hi < persist_ - 1) return;
  // The rudder's range over the samples held (learned with the step statistic: how far the
  // rudder swung in the healthy past that set the bar).
  const double delta_max = std::max(std::abs(d_range_.lo()), std::abs(d_range_.hi()));
  swing_ = d_range_.hi() - d_range_.lo();
  const double s2 = sigma_ * sigma_;
  double raw = 0.0;
  for (int m = persist_ - 1; m <= m_hi; ++m) raw = std::max(raw, f_[m] * f_[m] * inv_c_[m]);
  raw /= s2;
  if (raw <= kDiscountFrom * p_.threshold) {
    T_ = T_learn_ = raw;  // an upper bound, far below any threshold
    return;
  }
  // What an error of B (b_uncertainty) and a lagging rudder sensor (rudder_lag) could make
  // of the same windows: the rudder's part of z is known only that well.
  i_.steps(m_hi, fi_.data());
  d_.steps(m_hi, fd_.data());
  // The largest bend the rudder can drive in these windows: |z''| = |a_row . x'| with x'
  // driven by b delta, so at most bend_rate |b| max(max|delta|, swing) (a hull whose rudder is
  // near midships, holding a course in waves, bends z with the waves, which the bar learned).
  const double bend_cap = p_.bend_rate * std::abs(b_) * std::max(delta_max, swing_);
  // A rudder swinging further than in the healthy past the bar was learned from (the first
  // zigzag execute after course keeping) changes x' by about B times the extra swing, and z''
  // by up to bend_rate |b| times it, a bend not yet under way before the onset. (A swing the
  // bar has seen is in the bar already: course keeping and course changes lose nothing.)
  const double new_swing = std::max(0.0, swing_ - healthy_.max(2));
  const double swing_bend = p_.bend_rate * std::abs(b_) * new_swing;
  for (int m = persist_ - 1; m <= m_hi; ++m) {
    // z's bend before the onset: the change of its slope from the pre window before the
    // last to the last [per s^2] (when the samples held reach back that far).
    const double zdd = z_.count() >= 2 * L_ + m + 1
                           ? (z_.slope_before(m) - z_.slope_before(m + L_)) / (L_ * dt_ * dt_)
                           : 0.0;
    const double rudder_doubt =
        std::abs(b_) * (p_.b_uncertainty * std::abs(fi_[m]) + p_.rudder_lag * std::abs(fd_[m]));
    // The healthy maximum is learned without the bend's discount: the bar stays where the
    // hull's bends put it, and the discount only keeps a bend under way from crossing it.
    const double learn_excess = std::max(0.0, std::abs(f_[m]) - rudder_doubt);
    T_learn_ = std::max(T_learn_, learn_excess * learn_excess / (s2 * c_[m]));
    const double bend = std::min(p_.bend_margin * std::abs(zdd) + swing_bend, bend_cap);
    const double excess =
        std::max(0.0, std::abs(f_[m]) - rudder_doubt - bend * bend_[static_cast<std::size_t>(m)]);
    const double Tm = excess * excess / (s2 * c_[m]);
    if (Tm > T_) {
      T_ = Tm;
      *f_best = f_[m];
      *m_best = m;
    }
  }
}

bool JumpCheck::persists(int m, double f) const {
  // The level before the onset is clean: no sample off its line by half the step (an
  // outlier at its end would tilt the line and fake a step the other way).
  for (int back = m + 1; back <= m + L_; ++back) {
    if (std::abs(z_.at(back) - z_.line(m, back)) > 0.5 * std::abs(f)) return false;
  }
  // A level that moved and stays: enough post samples off the line by half the step, in its
  // direction, and spread about the new level by less than half of it (not a noise burst
  // whose mean happens to be off).
  const double sign = f < 0 ? -1.0 : 1.0;
  int count = 0;
  double spread = 0.0, sum = 0.0, sum2 = 0.0, sum_j = 0.0, first = 0.0;
  for (int back = 0; back <= m; ++back) {
    const double dev = z_.at(back) - z_.line(m, back);
    if (sign * dev > 0.5 * std::abs(f)) ++count;
    spread += (dev - f) * (dev - f);
    const int j = m + 1 - back;  // samples after the onset (the first post sample: 1)
    sum += dev;
    sum2 += dev * dev;
    sum_j += dev * j;
    if (j == 1) first = dev;
  }
  return count >= persist_ && count >= 0.6 * (m + 1) &&
         std::sqrt(spread / (m + 1)) < 0.5 * std::abs(f) &&
         level_not_bend(m + 1, spread, sum, sum2, sum_j, first);
}

bool JumpCheck::level_not_bend(int n, double spread, double sum, double sum2, double sum_j,
                               double first) {
  // A step, not a bend: a new level fits the post samples better than a new slope does, each
  // starting at the onset or a sample later (the onset found may be a sample early; one
  // parameter each). The crest of a wave, the yaw rate of a hull in a seaway turning from
  // rising to falling, leaves the extrapolated line as a slope; a bias leaves it as a level.
  // Sums over the n post samples of dev, dev^2 and j dev (j = 1 .. n), and the first dev;
  // spread, the squares about the new level from the onset, is the level's fit from it.
  if (n < 3) return true;  // too few to tell (persist_samples may be as low as 1)
  const auto squares = [](double k) { return k * (k + 1) * (2 * k + 1) / 6; };  // 1^2+..+k^2
  const double level_now = spread;
  const double bend_now = sum2 - sum_j * sum_j / squares(n);
  // Without the first sample, counted from it (j - 1 = 1 .. n - 1).
  const double rest = sum - first, rest2 = sum2 - first * first;
  const double rest_j = sum_j - first - rest;
  const double level_later = first * first + rest2 - rest * rest / (n - 1);
  const double bend_later = first * first + rest2 - rest_j * rest_j / squares(n - 1);
  return std::min(level_now, level_later) < std::min(bend_now, bend_later);
}

void JumpCheck::noise_statistic(double d2sq) {
  const std::size_t W = d2_.size();
  if (d2_n_ == W) d2_sum_ -= d2_[d2_next_];
  d2_[d2_next_] = d2sq;
  d2_sum_ += d2sq;
  d2_next_ = (d2_next_ + 1) % W;
  d2_n_ = std::min(d2_n_ + 1, W);
  if (++d2_since_exact_ >= kExact) {
    d2_since_exact_ = 0;
    d2_sum_ = 0.0;
    for (std::size_t i = 0; i < d2_n_; ++i) d2_sum_ += d2_[i];
  }
  N_ = 0.0;
  if (d2_n_ < W) return;
  const double kept = static_cast<double>(W) - 3.0, s2 = sigma2_ * sigma2_;
  const double bound = std::max(0.0, d2_sum_) / kept / s2;
  if (bound <= kDiscountFrom * 2.0 * p_.noise_threshold) {
    N_ = bound;  // an upper bound, far below any threshold
    return;
  }
  // The mean square without the three largest (a jump moves two, an outlier three).
  double top[3] = {0.0, 0.0, 0.0};
  for (double x : d2_) {
    if (x > top[2]) {
      top[2] = x;
      if (top[2] > top[1]) std::swap(top[1], top[2]);
      if (top[1] > top[0]) std::swap(top[0], top[1]);
    }
  }
  N_ = std::max(0.0, d2_sum_ - top[0] - top[1] - top[2]) / kept / s2;
}

void JumpCheck::learn(const Pending& s) {
  if (!s.ok) return;
  // The scales: the mean of the first squares, then an exponential average over
  // scale_time of squares winsorised at 4 sigma (a fault of a few samples barely moves it).
  sigma_seen_ += 1.0;
  const double w = std::max(1.0 / sigma_seen_, std::min(1.0, dt_ / p_.scale_time));
  const auto average = [&](double* scale, double x2) {
    const double s2 = (*scale) * (*scale);
    const double x = sigma_seen_ > 20 ? std::min(x2, 16.0 * s2) : x2;
    *scale = std::max(std::sqrt(s2 + w * (x - s2)), floor_);
  };
  average(&sigma_, s.e2);
  average(&sigma2_, s.d2sq);
  learned_ += dt_;
  // The healthy maxima, once the scales have settled.
  if (learned_ >= 0.5 * p_.learn_time) healthy_.add(s.t, {s.T, s.N, s.swing});
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
  if (!std::isfinite(t)) return v;
  integrate_rudder(t, delta);
  if (!std::isfinite(y)) return v;
  if (raised_ && t - raised_at_ >= p_.hold_max) {
    raised_ = false;
    let_go_offset_ = offset_;
    let_go_at_ = t;
    v.step = JumpVerdict::Change::kClear;
    v.message = "no jump back within " + std::to_string(p_.hold_max) + " s";
  }
  if (!learn_interval(t)) return v;
  if (!take_sample(t, y)) return v;

  if (sigma_ <= 0) sigma_ = floor_;
  if (sigma2_ <= 0) sigma2_ = floor_;
  int m_best = -1;
  double f_best = 0.0;
  step_statistics(&m_best, &f_best);
  // The innovation (the one-step prediction error) and the second difference.
  const double e2 = f_[0] * f_[0] / c_[0];
  const double d2 = z_.at(0) - 2.0 * z_.at(1) + z_.at(2);
  noise_statistic(d2 * d2);
  queue_for_learning(
      Pending{t, T_learn_, N_, e2, d2 * d2, swing_, learn_ok && !raised_ && !noise_raised_});
  armed_ = p_.enabled && learned_ >= p_.learn_time;
  // Watched from half the learning on (the scales have settled), reported once armed: a
  // fault before arming is kept out of the learning, and its end is not taken for a new one.
  if (!p_.enabled || learned_ < 0.5 * p_.learn_time) return v;
  threshold_ = std::max(p_.threshold, p_.margin * healthy_.extrapolated_max(0));
  noise_threshold_ = std::max(p_.noise_threshold, p_.margin * healthy_.extrapolated_max(1));
  if (decide_noise(t, &v)) return v;
  decide_step(t, m_best, f_best, &v);
  return v;
}

void JumpCheck::integrate_rudder(double t, double delta) {
  // The rudder integral over every interval, once (the angle held over a missing one),
  // whether or not this sample's y is usable. Once the interval is learned (dt_ > 0), a step
  // is a whole number of intervals: the samples are taken as equally spaced (z's windows
  // count samples), and the jitter of a stamp (a receive time) would otherwise move I by
  // delta times it and z by b delta times it, in a hard turn more than the gyro's noise.
  const double d_now = std::isfinite(delta) ? delta : last_delta_;
  if (std::isfinite(int_t_) && std::isfinite(last_delta_) && std::isfinite(d_now)) {
    const double gap = t - int_t_;
    const double step = dt_ > 0 ? dt_ * static_cast<double>(intervals(gap)) : gap;
    I_ += 0.5 * (last_delta_ + d_now) * step;
  }
  int_t_ = t;
  last_delta_ = d_now;
}

bool JumpCheck::learn_interval(double t) {
  // The sample interval, from the first samples.
  if (dt_seen_ >= kIntervalSamples) return true;
  first_t_.push_back(t);
  if (++dt_seen_ < kIntervalSamples) return false;
  std::vector<double> d(first_t_.size() - 1);
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = first_t_[i + 1] - first_t_[i];
  dt_ = median_in_place(&d);
  std::vector<double>().swap(first_t_);
  if (!(dt_ > 0)) {
    dt_seen_ = 0;
    return false;
  }
  resize_windows();
  restart();
  return true;
}

long JumpCheck::intervals(double gap) const { return std::max(1L, std::lround(gap / dt_)); }

bool JumpCheck::take_sample(double t, double y) {
  // A long gap restarts the windows (and the rudder integral, so z is computed after), as
  // does a rudder integral grown too large for its round-off.
  if (std::isfinite(last_t_) && (t - last_t_ > p_.max_gap || std::abs(I_) > kRebase)) {
    restart();
  }
  const double z = y - b_ * I_;
  const double dl = std::isfinite(last_delta_) ? last_delta_ : 0.0;
  if (std::isfinite(last_t_)) {
    // Dropped samples: filled on the straight line between their neighbours.
    const double gap = t - last_t_;
    const long steps = intervals(gap);
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
  return z_.count() >= L_ + 1 && z_.count() >= 3;
}

void JumpCheck::queue_for_learning(const Pending& s) {
  // Learning trails the decisions by the post window: a fault's first samples, seen before
  // it is detected, are dropped with the detection.
  const std::size_t P = pending_.size();
  if (pending_n_ == P) {
    learn(pending_[pending_head_]);
    pending_head_ = (pending_head_ + 1) % P;
    --pending_n_;
  }
  pending_[(pending_head_ + pending_n_) % P] = s;
  ++pending_n_;
}

bool JumpCheck::decide_noise(double t, JumpVerdict* v) {
  if (!noise_raised_ && N_ > noise_threshold_) {
    noise_raised_ = true;
    noise_raised_at_ = t;
    noise_below_since_ = kNaN;
    v->noise = JumpVerdict::Change::kRaise;
    pending_n_ = 0;
    char buf[160];
    std::snprintf(buf, sizeof buf, "noise: innovation mean square %.3g > %.3g (scale %.3g)", N_,
                  noise_threshold_, sigma2_);
    v->message = buf;
    if (raised_ && t - raised_at_ <= 2.0 * p_.noise_window) {
      raised_ = false;  // the jump raised just before was the first samples of this noise
      v->message += "; the jump before it was this";
    }
    return true;
  }
  if (noise_raised_ && !noise_reported_ && !armed_ && t - noise_raised_at_ >= p_.hold_max) {
    noise_raised_ = false;  // a rise watched before arming must not stop the learning forever
  }
  if (!noise_raised_) return false;
  if (d2_n_ < d2_.size()) return true;  // refilling after a restart: no verdict
  if (N_ < p_.exit_ratio * noise_threshold_) {
    if (std::isnan(noise_below_since_)) noise_below_since_ = t;
    if (t - noise_below_since_ >= p_.leave_time) {
      noise_raised_ = false;
      v->noise = JumpVerdict::Change::kClear;
      v->message = "noise back below " + std::to_string(p_.exit_ratio * noise_threshold_);
    }
  } else {
    noise_below_since_ = kNaN;
  }
  return true;
}

void JumpCheck::decide_step(double t, int m_best, double f_best, JumpVerdict* v) {
  if (m_best < 0 || !(T_ > threshold_) || !persists(m_best, f_best)) return;
  const int cap = static_cast<int>(ts_.size());
  const double onset = ts_[static_cast<std::size_t>((z_.newest() - m_best + cap) % cap)];
  pending_n_ = 0;
  char buf[200];
  if (!raised_ && std::isfinite(let_go_at_) && t - let_go_at_ <= p_.history &&
      f_best * let_go_offset_ < 0 && std::abs(f_best) >= 0.5 * std::abs(let_go_offset_)) {
    // The end of the offset let go at hold_max: the channel is back where it was before it.
    let_go_at_ = kNaN;
  } else if (!raised_) {
    let_go_at_ = kNaN;
    raised_ = true;
    offset_ = f_best;
    raised_at_ = t;
    v->step = JumpVerdict::Change::kRaise;
    v->onset = onset;
    v->size = f_best;
    std::snprintf(buf, sizeof buf, "jump of %+.4g at %.3f s: T %.3g > %.3g (scale %.3g)", f_best,
                  onset, T_, threshold_, sigma_);
    v->message = buf;
  } else if (f_best * offset_ > 0 || std::abs(f_best) < 0.5 * std::abs(offset_)) {
    offset_ += f_best;  // it grew, or came back part of the way
  } else {
    offset_ += f_best;
    raised_ = false;
    v->step = JumpVerdict::Change::kClear;
    v->onset = onset;
    v->size = f_best;
    std::snprintf(buf, sizeof buf, "jump back of %+.4g at %.3f s (offset left %+.3g)", f_best,
                  onset, offset_);
    v->message = buf;
  }
  // The step leaves every window: keep only the samples from its onset on.
  keep_newest(m_best + 1);
}

}  // namespace usvfdi
