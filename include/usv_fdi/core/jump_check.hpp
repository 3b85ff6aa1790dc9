// The jump check: a model-free test of one INS channel for the faults that break the
// smoothness of a vessel's motion, a sudden offset (bias) and a rise of the noise, armed
// after a minute of data whether or not A has been identified. docs/design.md section 8.6.
//
// A hull's sway velocity and yaw rate are integrals of forces, so they are continuous; the
// rudder's part of their slope is known from B: z = y - b * int(delta dt) removes it. A
// sensor offset of size f at sample k0 shows as a level step in z. A B that is off, or a
// lagging rudder sensor, leave part of the rudder's effect in z: the step test discounts
// |b| (b_uncertainty |f_m(int delta)| + rudder_lag |f_m(delta)|), what they could make of
// the same window. At every sample k and
// for every onset k0 = k - m (m = persist - 1 .. M - 1) a straight line is fitted to the L
// samples before k0 and extrapolated over the post window [k0, k]:
//   f_m = mean(z over [k0, k]) - mean(line over [k0, k]),   T_m = f_m^2 / (sigma^2 c_m),
// c_m = 1/(m+1) + 1/L + (m/2 - jbar)^2 / S_jj the variance factor of f_m for white noise
// of scale sigma (jbar, S_jj the mean and the sum of squares of the pre window's indices
// about it), sigma learned as the scale of the one-step innovation e = f_0 / sqrt(c_0).
// T = max_m T_m is tested against max(threshold, margin x the largest T of the healthy
// past), so waves, manoeuvres and coloured noise raise the bar the check has to clear on
// this hull in this sea, and a jump that is only one or two samples long (an outlier) is
// refused: the post samples must deviate in the step's direction by half of it, at least
// persist of them, with a spread about the new level below half of it. The noise test is
// the mean square of the second differences of z over noise_window without their three
// largest (a step moves two of them, an outlier three), relative to its healthy mean,
// against max(noise_threshold, margin x its healthy maximum).
//
// A raised jump holds until a jump back (of the opposite sign and at least half the offset
// so far; a jump of the same sign, or a smaller one back, adds to the offset), or hold_max; a
// jump back to the level before an offset let go at hold_max (within `history`) is its end, not
// a new jump. Samples
// are taken as equally spaced at the learned interval: one or a few dropped samples are filled by
// linear interpolation, a gap longer than max_gap restarts the windows.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "usv_fdi/core/healthy_maxima.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi {

struct JumpParams {
  bool enabled = true;           ///< false: the check never raises
  double pre_window = 1.0;       ///< line fitted before a candidate onset [s]
  double post_window = 0.5;      ///< longest time after the onset that is tested [s]
  int min_samples = 5;           ///< each window holds at least this many samples
  int persist_samples = 3;       ///< a jump must last this many samples (else an outlier)
  double persist_time = 0.3;     ///< ... and this long (a burst of noise is not a jump) [s]
  double threshold = 30.0;       ///< floor of the step statistic's threshold [-]
  double noise_threshold = 4.0;  ///< floor of the noise statistic's threshold [-]
  double margin = 2.0;           ///< thresholds >= margin x the healthy maximum [-]
  double noise_window = 1.0;     ///< mean square of the innovations over this [s]
  /// ... and over at least this many samples: at 10 Hz a window of 10 second differences
  /// (7 after the three largest are dropped) passes 4 on 7 in 10^6 samples of white noise,
  /// over 20 never in 2 x 10^7 (docs/benchmark.md, "The noise statistic's window")
  int noise_min_samples = 20;
  double learn_time = 15.0;  ///< healthy data before the check reports (watched from half) [s]
  double history = 600.0;    ///< the healthy maximum is that of this long [s]
  double scale_time = 30.0;  ///< averaging time of the innovation scale [s]
  double leave_time = 1.0;   ///< a noise rise clears after this long below [s]
  double exit_ratio = 0.5;   ///< ... below exit_ratio x its threshold [-]
  double hold_max = 30.0;    ///< a jump with no jump back is held this long [s]
  double max_gap = 0.5;      ///< a longer gap between samples restarts the windows [s]
  /// The rudder's part of z is known only so well: B may be off by this much (relative) and
  /// the rudder sensor may lag by rudder_lag; a step is only what these cannot explain [-]
  double b_uncertainty = 0.5;
  double rudder_lag = 0.3;  ///< [s]
  /// The hull's own dynamics bend z (z'' = a_row . x': the Otter's yaw rate answers a rudder
  /// step within a second), which a line fitted before the onset and extrapolated misses; at
  /// 10 Hz a zigzag's bend looked like a step. The step test also discounts
  /// min(bend_margin |z''|, bend_rate |b| max|delta|) |f_m(t^2 / 2)|: z'' is the change of
  /// z's slope between the two pre windows before the onset (the bend seen may grow
  /// bend_margin times), and the rudder bounds the bend it can drive (a hull's rate 1/T up to
  /// bend_rate), so that waves, which bend z with the rudder near midships, are no excuse.
  /// A rudder that swings further within the windows than it did in the healthy past the bar
  /// learned from (a first zigzag execute after course keeping) starts a bend the pre window
  /// has not seen yet: bend_rate |b| times that extra swing is added to |z''| (within the
  /// same bound). Either 0: no such discount [-], [1/s].
  double bend_margin = 2.0;
  double bend_rate = 2.0;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// What the check found on one sample.
struct JumpVerdict {
  enum class Change : std::uint8_t { kNone = 0, kRaise, kClear };
  Change step = Change::kNone;   ///< a jump raised, or cleared by a jump back / hold_max
  Change noise = Change::kNone;  ///< a noise rise raised or cleared
  double onset = kNaN;           ///< the raised jump's first sample [s]
  double size = kNaN;            ///< its size [channel unit]
  std::string message;
};

/// The jump check of one channel (y = v or r, b = B's entry of that channel).
class JumpCheck {
 public:
  /// sigma_floor: the smallest scale of the innovations [channel unit].
  JumpCheck(const JumpParams& p, double b, double sigma_floor);

  /// One sample (y and delta NaN when unusable). learn_ok: the channel is healthy as far
  /// as the caller knows (its statistics and thresholds may learn from this sample).
  JumpVerdict update(double t, double y, double delta, bool learn_ok);

  /// Forgets a raised jump (another detector holds the fault from now on): the next jump
  /// of either sign is a new one.
  void release() {
    raised_ = false;
    offset_ = 0.0;
    let_go_at_ = kNaN;
  }

  bool armed() const { return armed_; }
  bool jump_raised() const { return raised_; }
  bool noise_raised() const { return noise_raised_; }
  double statistic() const { return T_; }  ///< max_m T_m of the last sample
  /// The range of the rudder angle over the samples held (the pre and post windows) [rad].
  double swing() const { return swing_; }
  double threshold() const { return threshold_; }  ///< in force (0 before arming)
  double noise_statistic() const { return N_; }
  double noise_threshold() const { return noise_threshold_; }
  double scale() const { return sigma_; }  ///< innovation scale [channel unit]
  double interval() const { return dt_; }  ///< learned sample interval [s]

 private:
  /// The lowest and highest of the newest w values pushed, in O(1) amortised per value (two
  /// monotonic queues of the values that may still become the extreme, in rings).
  class SlidingRange {
   public:
    void reset(int w);
    void clear();
    void push(double x);
    double lo() const { return lo_.front(); }  ///< (after at least one push)
    double hi() const { return hi_.front(); }

   private:
    struct Queue {
      std::vector<std::pair<long long, double>> ring;  ///< (sequence number, value)
      int head = 0, size = 0;
      const std::pair<long long, double>& at(int k) const {
        return ring[static_cast<std::size_t>((head + k) % static_cast<int>(ring.size()))];
      }
      double front() const { return at(0).second; }
    };
    /// Appends x to q after dropping the values it makes irrelevant (keep(back, x) false).
    template <typename Keep>
    void add(Queue* q, double x, Keep keep);
    int w_ = 1;
    long long n_ = 0;  ///< values pushed since clear()
    Queue lo_, hi_;
  };
  /// Equally spaced samples of one series in a ring, with the line fitted to the L samples
  /// ending at each of the last M + 1 samples (sliding sums: O(1) per sample).
  class Series {
   public:
    void reset(int L, int M);
    void clear();
    void push(double x);
    int count() const { return count_; }    ///< samples since clear() (capped at 2^30)
    int newest() const { return newest_; }  ///< the newest sample's place in the ring
    /// The value `back` samples before the newest (0: the newest).
    double at(int back) const {
      const int k = newest_ - back;  // back < cap_
      return x_[static_cast<std::size_t>(k < 0 ? k + cap_ : k)];
    }
    /// f_m for m in [0, m_hi] (needs count() >= L + m_hi + 1): the mean of the last m + 1
    /// samples minus that of the line fitted to the L samples before them.
    void steps(int m_hi, double* f) const;
    /// The line fitted before the last m + 1 samples, at `back` samples before the newest.
    double line(int m, int back) const;
    /// That line's slope [per sample].
    double slope_before(int m) const {
      const int k = newest_ - (m + 1);
      return slope_[static_cast<std::size_t>(k < 0 ? k + cap_ : k)];
    }

   private:
    int L_ = 0, M_ = 0, cap_ = 1;
    std::vector<double> x_;
    std::vector<double> mean_, slope_;  ///< fits of the L samples ending at each sample
    int newest_ = -1, count_ = 0;
    double S0_ = 0.0, S1_ = 0.0;  ///< sums of x and j x over the newest L (j = 0 oldest)
    int since_exact_ = 0;
  };
  struct Pending {
    double t, T, N, e2, d2sq, swing;
    bool ok;
  };

  JumpVerdict decide(double t, double y, double delta, bool learn_ok);
  /// Adds the interval since the last sample to the rudder integral I_.
  void integrate_rudder(double t, double delta);
  /// Learns the sample interval from the first samples; true once it is known.
  bool learn_interval(double t);
  /// How many learned intervals a gap between two stamps spans (at least one); the interval
  /// must be known.
  long intervals(double gap) const;
  /// Puts z = y - b I (and the dropped samples before it) in the windows; true once they
  /// hold enough for the statistics.
  bool take_sample(double t, double y);
  /// Queues a sample for learning, learning from the oldest queued one once the queue is full.
  void queue_for_learning(const Pending& s);
  /// The noise rise's raise and clear; true when it decided the sample (no step verdict).
  bool decide_noise(double t, JumpVerdict* v);
  /// The step's raise, growth and jump back.
  void decide_step(double t, int m_best, double f_best, JumpVerdict* v);
  void resize_windows();
  void restart();
  /// Keeps only the newest `keep` samples (a jump leaves every window).
  void keep_newest(int keep);
  void push(double t, double z, double I, double delta);
  /// The step statistics of the samples held: T_ and the best onset (*m_best, *f_best).
  void step_statistics(int* m_best, double* f_best);
  bool persists(int m, double f) const;
  /// A new level, not a new slope, explains the n post samples (their squares about the
  /// level, sum, sum of squares, sum of j x each for j = 1 .. n, and the first); true below
  /// 3 samples.
  static bool level_not_bend(int n, double spread, double sum, double sum2, double sum_j,
                             double first);
  void noise_statistic(double d2sq);
  /// Learns from a sample once it is M samples old and no jump or noise rise was found
  /// since (the first samples of a fault come before its detection).
  void learn(const Pending& s);

  JumpParams p_;
  double b_;
  double floor_;
  Series z_, i_, d_;                 ///< z = y - b int(delta), int(delta) [rad s], delta [rad]
  std::vector<double> ts_;           ///< times of the samples held (a ring like the series')
  std::vector<double> c_, inv_c_;    ///< variance factor c_m of f_m, and 1 / c_m
  std::vector<double> bend_;         ///< |f_m| of t^2 / 2 [s^2]: a constant z'' = 1
  std::vector<double> f_, fi_, fd_;  ///< scratch: f_m of z, int(delta), delta
  int L_ = 0, M_ = 0;                ///< pre window, longest post window [samples]
  int persist_ = 1;                  ///< samples a jump must last
  double dt_ = 0.0;                  ///< learned interval [s]
  int dt_seen_ = 0;
  std::vector<double> first_t_;  ///< the first samples' times (for dt)
  double last_t_ = kNaN, last_z_ = kNaN, last_I_ = kNaN, last_d_ = kNaN;
  double I_ = 0.0;       ///< int delta dt since the restart [rad s]
  double int_t_ = kNaN;  ///< the time the integral has reached [s]
  double last_delta_ = kNaN;
  // Learning.
  double sigma_ = 0.0, sigma2_ = 0.0;  ///< scales of the innovation and the 2nd difference
  double sigma_seen_ = 0.0;
  double learned_ = 0.0;  ///< healthy time seen [s]
  bool armed_ = false;
  HealthyMaxima<3> healthy_;      ///< of the step and the noise statistic, and the rudder's swing
  std::vector<Pending> pending_;  ///< samples not yet learned from (a ring, oldest first)
  std::size_t pending_head_ = 0, pending_n_ = 0;
  std::vector<double> d2_;  ///< ring of the last squared second differences (noise window)
  std::size_t d2_next_ = 0, d2_n_ = 0;
  double d2_sum_ = 0.0;
  int d2_since_exact_ = 0;
  // Verdicts.
  double T_ = 0.0, N_ = 0.0;
  double T_learn_ = 0.0;  ///< T without the bend's discount: what the healthy maximum learns
  double swing_ = 0.0;    ///< the rudder's range over the samples held [rad]
  SlidingRange d_range_;  ///< the rudder's range over the newest L + M samples
  double threshold_ = 0.0, noise_threshold_ = 0.0;
  bool raised_ = false;
  bool step_reported_ = false, noise_reported_ = false;  ///< their raise was reported
  double offset_ = 0.0;  ///< the offset since the raise (the jumps added up)
  double raised_at_ = kNaN;
  /// The offset let go at hold_max without a jump back, and when: for `history` seconds a jump
  /// back to the level before it is that offset's end, not a new jump.
  double let_go_offset_ = 0.0;
  double let_go_at_ = kNaN;
  bool noise_raised_ = false;
  double noise_raised_at_ = kNaN;
  double noise_below_since_ = kNaN;
};

}  // namespace usvfdi
