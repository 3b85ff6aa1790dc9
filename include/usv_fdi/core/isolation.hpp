// Detection and isolation (the isolation thread's engine), docs/design.md sections 3 and 4.
//
// Two dedicated observers on the current estimate of A give the structured residual
//   s = [ (y1 - x1^V) / sigma_sa , (y2 - x2^G) / sigma_sg ]
// whose first entry is blind to gyro faults and second to accelerometer faults, so a fault
// of sensor i keeps s on l_i (l_a = [1 0]^T, l_g = [0 1]^T). Isolation confidence
//   C_i = |l_i^T e| / (||l_i|| ||e||)
// on the windowed excess-energy vector e of s. The cross residuals
//   d = [ (y1 - x1^G) / sigma_da , (y2 - x2^V) / sigma_dg ]
// see a fault of sensor i without absorption (observer G never sees y1), so they hold a
// raised fault while it persists. Sensor-level checks (after PX4's data validator) catch
// stale, stuck, invalid and spiky channels.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "usv_fdi/core/detection.hpp"
#include "usv_fdi/core/healthy_maxima.hpp"
#include "usv_fdi/core/identification.hpp"
#include "usv_fdi/core/jump_check.hpp"
#include "usv_fdi/core/observer.hpp"
#include "usv_fdi/core/sensor_checks.hpp"
#include "usv_fdi/core/speed.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi {

/// IsolationParams::on_lost_convergence.
enum class LostConvergence : std::uint8_t {
  /// Un-arm: the residual checks stop (their raised conditions clear, saying why), the banks
  /// and the healthy maxima are dropped, and they arm again, with a new design and its
  /// learning, when the estimate has converged anew.
  kUnarm = 0,
  /// Keep the design in force and redesign nothing until the estimate converges again
  /// (IsolatorStatus::design_held).
  kHold,
  /// Redesigns follow the estimate, converged or not (the engine before 2026-12-07).
  kFollow,
};

struct IsolationParams {
  Vec2 poles_v = Vec2(-0.5, -0.7);    ///< poles of observer V [1/s]
  Vec2 poles_g = Vec2(-0.5, -0.7);    ///< poles of observer G [1/s]
  double min_observability = 1e-3;    ///< refuse an observer design below this index
  double redesign_tolerance = 0.005;  ///< relative change of A that triggers a redesign
  /// Sensor noise. The residual scales are always learned on healthy data after arming
  /// (they include model mismatch); configured sensor noise sets their floors.
  double sigma_v = 0.0;         ///< accelerometer-channel noise [m/s]; 0: floors only
  double sigma_r = 0.0;         ///< gyro noise [rad/s]; 0: floors only
  double sigma_floor_v = 1e-4;  ///< floor of every v-channel scale [m/s]
  double sigma_floor_r = 1e-5;  ///< floor of every r-channel scale [rad/s]
  /// Observer settling after arming [s]; <0: 3 / min|pole|. After an input gap longer than
  /// stale_timeout the observers restart from the measurements and detection pauses for at
  /// least this, longer while the restart's transient (3-sigma noise in the state a channel
  /// does not measure) is above half a sigma of the residual.
  double settle_time = -1;
  double learn_time = 60.0;       ///< healthy data used to learn scales and threshold [s]
  double window = 0.5;            ///< evaluation window J_N [s]
  int min_window_samples = 10;    ///< the window holds at least this many samples
  double clip = 4.0;              ///< whitened residuals are clipped to +-clip inside J_N
  double threshold = 6.0;         ///< minimum enter threshold on J_N, D_N (whitened mean square)
  double threshold_margin = 1.5;  ///< learned threshold: at least margin * 99.9 % quantile
  double threshold_k = 8.0;       ///< learned threshold: median + k robust std of healthy J_N
  /// After learning, the thresholds on J_N and D_N are at least history_margin x the largest
  /// value each took on healthy data over the last `history` seconds (near the clip, at least
  /// the knee and 1.05 x it: history_bar): they follow the hull,
  /// the sea and the manoeuvres met since (a J_N the model's mismatch reaches in a zigzag is
  /// no evidence of a sensor fault) [-]
  double history_margin = 1.5;
  double history = 600.0;   ///< [s]
  double exit_ratio = 0.5;  ///< leave threshold = exit_ratio * enter threshold
  /// J_N above threshold this long raises (at least 1 sample), the other channel staying
  /// quiet: model mismatch lights the other channel within seconds, a single sensor's fault
  /// never (and the jump check raises a sudden offset at once) [s]
  double enter_time = 2.5;
  /// ... times this while the healthy maxima cover less than `history` (after learning, and
  /// after a restart of the maxima): their bars then follow the largest of a few minutes
  /// only, extrapolated, and a manoeuvre the hull has not yet made lifts J_N over them for
  /// a few seconds. A sensor another check has raised (a jump) is confirmed in enter_time.
  /// 1.5 with the history bar that never falls (history_bar): docs/benchmark.md, "The
  /// history bar" [-]
  double young_enter_ratio = 1.5;
  /// A channel whose J_N is above its bar from the moment detection goes live raises nothing
  /// until it has been at or below it (no onset: what the model does not hold in what the
  /// vessel was doing when it armed), unless its J_N was at or below the bar just learned
  /// within this long before going live and quiet before that (above the bar on at most 1 %
  /// of the learning samples): a fault that began in the last seconds of learning (the
  /// paper's gyro bias, 0.9 s before) keeps its onset [s]
  double onset_lookback = 5.0;
  /// A channel whose bar learned on J_N had to be capped at 0.75 clip^2 to stay within the
  /// statistic's reach is closed instead (its bar above clip^2: IsolatorStatus::
  /// bar_unreachable) until a new design learns again: its healthy J_N already went where a
  /// fault would take it (docs/benchmark.md, "A bar that had to be capped closes the
  /// channel"). The new design's bar is still at least the history bar, which the closed
  /// channel's healthy maxima may hold out of reach for up to `history`. Not applied when
  /// `threshold` itself is at or above the cap. false: the capped bar stands.
  bool close_capped_bars = true;
  /// A redesign still learning when a fault is raised starts its learning again (what it
  /// learned just before the raise may hold the fault's onset). false: it keeps it.
  bool relearn_after_raise = true;
  /// What the isolation thread does when A's estimate loses convergence after arming
  /// (IdentificationParams::uncertain_ratio: its uncertainty grew; it may wander far).
  LostConvergence on_lost_convergence = LostConvergence::kUnarm;
  double leave_time = 1.0;  ///< below the leave threshold this long clears [s]
  /// While one sensor's fault is raised, the other raises after J_N stayed above its
  /// threshold this long. Its structured entry is blind to the first fault, but the design
  /// in force cannot be renewed without healthy data, so its model mismatch (largest in
  /// turns, for about a second) grows as the estimate it was made from ages [s].
  double second_fault_time = 2.0;
  /// Model mismatch, not a sensor fault: residuals on both channels at once (C_i singles
  /// out neither), or the other channel's structured residual rising within this long of a
  /// raise (it is blind to the raised sensor's fault: the raise is withdrawn), or a channel
  /// beginning to rise again within this long of being seen again after a raise of its own
  /// that nothing held (cleared within min_active_time + leave_time of the raise: neither
  /// its cross residual nor its monitor kept it, as when a hull slows down and its rudder
  /// does less than B says; the clear restarts its observer, which settles for settle_time)
  /// or of the end of such a verdict, its cross residual below its leave threshold. Reported
  /// in IsolatorStatus (model_mismatch, mismatch_reason, mismatches), never latched;
  /// identification goes on learning, and detection resumes once every statistic stayed
  /// below its leave threshold for leave_time [s]
  double mismatch_window = 10.0;
  double min_active_time = 3.0;  ///< a residual fault stays raised at least this long [s]
  double c_min = 0.8;            ///< isolation needs C_i >= c_min ...
  double c_margin = 0.3;         ///< ... and C_i - C_other >= c_margin; else sensor unknown
  double resume_time = 2.0;      ///< quiet time before identification resumes [s]
  /// ... and after a fault condition cleared: a fault that comes and goes with the signal
  /// (a scale error is invisible while the vessel holds its course) must not reach the
  /// estimate of A in its quiet spells [s].
  double resume_after_fault = 10.0;
  // Sensor-level checks.
  double stale_timeout = 0.5;  ///< no valid value for this long: stale [s]
  double stuck_time = 0.5;     ///< value unchanged for this long: stuck [s]
  int stuck_min_samples = 5;   ///< ... and for at least this many samples
  /// A quantised or coarsely printed channel (a yaw rate as NMEA ROT, v to 3 significant
  /// digits) repeats its value while it moves. The fraction f of samples that repeat the
  /// previous one is learned per decade of |x| (exponential average over stuck_learn_time, a
  /// run's repeats once it has ended, not while stuck: SensorChecks), and a channel is stuck
  /// only when its run of repeats is also longer than n samples with f^n <= stuck_probability:
  /// improbable for the channel as it has been at that value [-]
  double stuck_probability = 1e-9;
  double stuck_learn_time = 60.0;  ///< averaging time of the repeat fraction [s]
  double stuck_time_max = 5.0;     ///< ... but unchanged this long is always stuck [s]
  double max_abs_v = 20.0;         ///< |v| above this is invalid [m/s]
  double max_abs_r = 3.0;          ///< |r| above this is invalid [rad/s]
  double max_abs_delta = 1.6;      ///< |delta| above this is invalid [rad]
  double spike_gate = 8.0;         ///< |s_i| above this on 1-2 samples is a spike
  double spike_window = 3.0;       ///< spikes are counted over this window [s]
  int spike_count = 3;             ///< this many spikes in the window raise a spikes fault
  int invalid_count = 3;           ///< this many invalid values in spike_window raise invalid
  double classify_window = 8.0;    ///< history used to name the kind of a fault [s]
  /// The drift test (issue 11, item 6). A slow fault of sensor i is absorbed by its own
  /// structured residual s_i, which keeps a part of it (det(A) / (p1 p2) of a constant one),
  /// too little for J_N's window but steady; s_j, blind to sensor i, keeps none. Per channel
  /// a two-sided CUSUM of the whitened structured residual w, integrated over time,
  ///   S+ = max(0, S+ + (w - drift_k) dt),  S- = max(0, S- + (-w - drift_k) dt),
  /// raises a drift of sensor i when max(S+, S-) of channel i passes its threshold while
  /// channel j's stays below exit_ratio x its own and J_N of channel j below its leave
  /// threshold; C_i is the paper's on [sqrt(S_a / thr_a), sqrt(S_g / thr_g)]. Each threshold
  /// is max(drift_threshold, history_margin x the largest value the CUSUM took on healthy
  /// data over `history`), learned from values once they are drift_lag old (a drift grows
  /// for tens of seconds before it is raised). Off by default: with the default poles a
  /// ship's structured residual keeps 0.3 % of a slow fault, nothing to see, while the
  /// CUSUM integrates every slow disturbance (docs/benchmark.md); on for observers whose
  /// poles are slow relative to the hull's (the shipped vessel configurations).
  bool drift_check = false;
  double drift_k = 0.5;              ///< the CUSUM's reference offset [whitened units]
  double drift_threshold = 5.0;      ///< floor of its threshold [whitened units x s]
  double drift_lag = 40.0;           ///< its healthy maximum learns from values this old [s]
  double drift_min_history = 120.0;  ///< healthy time seen before it may raise [s]
  /// The model-free jump check of each channel (core/jump_check.hpp): sudden offsets and
  /// noise rises, armed after its learn_time whether or not A is known.
  JumpParams jump;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// Reason flags for the inputs (FdiStatus).
struct InputHealth {
  bool v_ok = true, r_ok = true, delta_ok = true;
  std::uint64_t rejected_time = 0;   ///< samples whose time did not increase
  std::uint64_t invalid_values = 0;  ///< NaN/Inf/absurd values seen
  std::uint64_t gaps = 0;            ///< gaps longer than stale_timeout
};

struct IsolatorStatus {
  bool armed = false;
  bool learning = false;
  bool settling = false;
  bool relearning = false;    ///< a redesign is learning its statistics beside the design in force
  std::uint64_t designs = 0;  ///< observer designs put in force (the first at arming)
  std::string observer_problem;  ///< why an observer design was refused (empty when fine)
  /// A's estimate lost convergence after arming: the design in force is kept, no redesign
  /// until it converges again (LostConvergence::kHold).
  bool design_held = false;
  /// Times the residual checks were un-armed because A's estimate lost convergence
  /// (LostConvergence::kUnarm).
  std::uint64_t unarms = 0;
  Mat2 A_design = Mat2::Zero();
  Vec2 k_v = Vec2::Zero(), k_g = Vec2::Zero();
  Vec2 sigma_s = Vec2::Zero();  ///< scales of the structured residual [m/s, rad/s]
  Vec2 sigma_d = Vec2::Zero();  ///< scales of the cross residual
  double threshold = 0.0;       ///< largest enter threshold on J_N in force (of thresholds)
  double threshold_d = 0.0;     ///< largest threshold on the cross statistic D_N
  /// Per channel [accelerometer, gyro]: each residual channel's healthy statistics differ
  /// (the gyro's carries most of the model mismatch), so each has its own thresholds.
  Vec2 thresholds = Vec2::Zero();    ///< enter thresholds on J_N
  Vec2 thresholds_d = Vec2::Zero();  ///< thresholds on D_N (hold: exit_ratio x)
  Vec2 J = Vec2::Zero();             ///< windowed statistic per channel (structured)
  Vec2 D = Vec2::Zero();             ///< windowed statistic per channel (cross)
  /// Monitor statistic per raised channel: the signed offset of its monitor residual in
  /// the fault's direction as a mean square (1 + m^2), or its energy for noise and spikes.
  Vec2 M = Vec2::Zero();
  Vec2 s = Vec2::Zero();  ///< latest structured residual [m/s, rad/s] (NaN where unusable)
  Vec2 d = Vec2::Zero();  ///< latest cross residual, the fault estimate [m/s, rad/s]
  double c_a = 0.0, c_g = 0.0;
  double speed_ratio = 1.0;  ///< s = u / U0 of the last sample (1 without a speed input)
  /// The residuals contradict the model on both channels (IsolationParams::mismatch_window):
  /// no sensor fault is raised from the residuals while this holds.
  bool model_mismatch = false;
  std::string mismatch_reason;   ///< why (empty when there is none)
  std::uint64_t mismatches = 0;  ///< verdicts of model mismatch so far
  /// Per channel [accelerometer, gyro]: detection is live but the channel's J_N has been above
  /// its bar ever since, so its residual raises nothing until it falls once (no onset yet).
  std::array<bool, 2> awaiting_onset{};
  /// Per channel: its bar on J_N is at or above clip^2, which the statistic (a mean of squares
  /// clipped at +-clip) can never pass: its residual raises nothing while this holds (the
  /// healthy maximum reached the clip: waves, or a model that does not hold; or the bar
  /// learned at the design's learning had to be capped: IsolationParams::close_capped_bars).
  std::array<bool, 2> bar_unreachable{};
  InputHealth input;
  std::uint64_t samples = 0;
  /// The jump check per channel [accelerometer, gyro] (core/jump_check.hpp).
  bool jump_armed = false;
  Vec2 jump_T = Vec2::Zero(), jump_threshold = Vec2::Zero();    ///< step statistic
  Vec2 noise_N = Vec2::Zero(), noise_threshold = Vec2::Zero();  ///< noise statistic
  /// The drift test (IsolationParams::drift_k) per channel [accelerometer, gyro]: the CUSUM
  /// of the whitened structured residual [whitened units x s] and its threshold (0 while it
  /// cannot raise).
  Vec2 drift_S = Vec2::Zero(), drift_threshold = Vec2::Zero();
};

/// The bar the healthy past sets on a windowed mean of squares clipped at +-clip whose
/// healthy maximum is healthy_max: margin x healthy_max up to a knee at 0.8 clip^2, then the
/// larger of the knee and 1.05 x healthy_max. Non-decreasing in healthy_max, and below
/// clip^2 (a fault that pegs the statistic is still raised) while 1.05 x healthy_max < clip^2.
double history_bar(double healthy_max, double margin, double clip);

/// Whether the J_N a bank learned (J, in time order) shows an onset just before going live:
/// at or below threshold within its last `back` samples, and above it on at most 1 % of the
/// samples before them (Isolator::await_onsets; IsolationParams::onset_lookback).
bool onset_before_live(const std::vector<double>& J, std::size_t back, double threshold);

class Isolator {
 public:
  /// Throws std::invalid_argument on bad parameters. With a speed input (Sample::u) the
  /// observers run on A0 in the vessel's own time (core/speed.hpp), B is B0.
  Isolator(const IsolationParams& params, const Vec2& B, const SpeedParams& speed = {});

  /// Installs the latest identification snapshot. Arms (designs the observers) the first
  /// time the estimate has converged; afterwards, when A moved by more than
  /// redesign_tolerance, designs new observers that settle and learn their scales and
  /// thresholds on healthy data beside the ones in force, and replace them once learned.
  void set_estimate(const Estimate& est);

  /// Processes one sample; appends every change of a sensor's fault condition to out.
  /// Returns false when the sample was rejected (time did not increase).
  bool update(const Sample& s, std::vector<Detection>* out);
  /// A sample whose stamp does not fit the time base (repeated, backward, or far ahead):
  /// counted, and against the unknown sensor's invalid condition. Returns false.
  bool reject_timestamp(std::vector<Detection>* out);

  /// True while identification must not learn from the data (fault suspected or active,
  /// inputs unusable, or within resume_time of that).
  bool freeze_requested() const { return freeze_; }
  const IsolatorStatus& status() const { return st_; }
  const IsolationParams& params() const { return p_; }
  const SpeedRatio& speed() const { return speed_; }

 private:
  /// The last n values and their running sum, in a ring (no allocation once it has grown).
  class Window {
   public:
    void push(double x, std::size_t n);
    std::size_t size() const { return count_; }
    bool empty() const { return count_ == 0; }
    double mean() const { return count_ == 0 ? 0.0 : sum_ / static_cast<double>(count_); }
    /// The i-th value held, oldest first.
    double at(std::size_t i) const {
      const std::size_t k = head_ + i;
      return buf_[k < buf_.size() ? k : k - buf_.size()];
    }

   private:
    std::vector<double> buf_;
    std::size_t head_ = 0, count_ = 0;
    double sum_ = 0.0;
  };
  struct Condition {
    bool active = false;
    unsigned sources = 0;  ///< bitmask of Source
    FaultKind kind = FaultKind::kUnknown;
  };
  enum Source : unsigned {
    kResidual = 1u,
    kStale = 2u,
    kStuck = 4u,
    kSpikes = 8u,
    kInvalid = 16u,
    kJump = 32u,       ///< the jump check: a sudden offset
    kNoiseRise = 64u,  ///< the jump check: a rise of the noise
  };

  /// What the residual evaluation keeps of one INS channel (0: v, the accelerometer's; 1: r,
  /// the gyro's) beside the banks.
  struct ChannelState {
    bool resync = false;           ///< restart the channel's own observer (cleared)
    double resettle_until = kNaN;  ///< the restarted observer settles
    /// Its J_N seen at or below its enter threshold since arming: a sensor fault has an onset.
    bool onset_seen = false;
    std::deque<std::pair<double, double>> hist_s;  ///< (t, whitened structured residual)
    std::deque<std::pair<double, double>> hist_d;  ///< (t, raw cross residual)
    std::deque<std::pair<double, double>> hist_x;  ///< (t, other-observer state)
    double jump_at = kNaN;                         ///< time of the channel's last jump raise
    bool jump_handed = false;  ///< the raised jump was handed to the observers (both hold it)
    // Holding a raised residual fault (see hold_or_clear).
    DedicatedObserver mon;    ///< monitor: the observer, not reconfigured
    bool mon_on = false;      ///< monitor running (channel raised)
    bool mon_ok = false;      ///< its post-fault transient opposes the fault
    double mon_sign = 1.0;    ///< the fault's sign at the raise
    Window win_m;             ///< clipped squared whitened monitor residual
    Window win_ms;            ///< signed whitened monitor residual
    double refine_at = kNaN;  ///< when to refine a raised fault's kind
    // Spikes of the whitened structured residual (check_spikes).
    std::deque<double> spikes;  ///< times of spikes
    int outlier_run = 0;
    bool last_ordinary = true;  ///< the previous residual was well inside the gate
    bool run_isolated = false;  ///< the current outlier run began after an ordinary sample
    double outlier_start = kNaN;
  };
  /// The decision's state of one sensor (accelerometer, gyro, unknown).
  struct SensorState {
    Condition cond;
    double above_since = kNaN;  ///< its statistic above the enter threshold since
    double below_since = kNaN;  ///< ... below the leave threshold since
    double raised_at = kNaN;    ///< time of the residual raise
    /// When the channel was seen again (its restarted observer settled) after a residual
    /// raise of this sensor cleared within min_active_time + leave_time of the raise, nothing
    /// (cross residual, monitor) holding it longer, or when a verdict of its repeated rise
    /// ended: the model's mismatch, not a fault, if it comes back
    double unheld_at = kNaN;
  };

  /// One pair of dedicated observers on one design of A, with the residual statistics
  /// learned for that design. The healthy residual of a design carries the model mismatch
  /// of the estimate it was made from, so its scales and thresholds hold for it alone: a
  /// redesign builds a new bank that settles and learns on healthy data beside the one in
  /// force (which keeps detecting), and replaces it once it has learned.
  struct Bank {
    DedicatedObserver v, g;
    Mat2 A = Mat2::Zero();
    Vec2 k_v = Vec2::Zero(), k_g = Vec2::Zero();
    bool theory_scales_pending = false;
    Vec2 floor_s = Vec2::Zero(), floor_d = Vec2::Zero();  ///< floors of the learned scales
    Vec2 sigma_s = Vec2::Zero(), sigma_d = Vec2::Zero();
    Vec2 threshold = Vec2::Zero(), threshold_d = Vec2::Zero();  ///< per channel
    double settle_until = kNaN;
    double learned_time = 0.0;  ///< healthy data used by the current learning phase [s]
    bool scales_learned = false;
    bool learned = false;
    // Learning samples (robust statistics: a fault during learning cannot inflate the
    // scales unless it covers half of the learning time).
    std::array<std::vector<double>, 4> learn_raw;         ///< s_a, s_g, d_a, d_g raw residuals
    std::array<std::vector<double>, 2> learn_J, learn_D;  ///< per channel
    /// Per channel: an onset just before going live (onset_before_live on learn_J).
    std::array<bool, 2> onset_in_learning{};
    std::array<Window, 2> win_s;   ///< clipped squared structured residuals
    std::array<Window, 2> win_sl;  ///< signed structured residuals (classification)
    std::array<Window, 2> win_d;   ///< clipped squared cross residuals
    Vec2 J = Vec2::Zero(), D = Vec2::Zero();
    /// Empties channel c's evaluation windows.
    void clear_windows(int c) {
      for (Window* w : {&win_s[c], &win_sl[c], &win_d[c]}) *w = Window{};
    }
  };

  bool design(const Mat2& A, Bank* b);
  /// rudder: the rudder at t_{k-1} and t_k that drives the observers over the step.
  void propagate(Bank* b, const Sample& s, double dt, bool v_ok, bool r_ok, const Vec2& rudder);
  /// Learning and evaluation windows of one bank for one sample. Fills raw (structured and
  /// cross residuals) and sw (whitened structured, NaN where unusable). Returns false while
  /// the bank settles (nothing evaluated).
  bool evaluate(Bank* b, const Sample& s, double dt, bool learn_ok, bool v_ok, bool r_ok,
                double raw[4], Vec2* sw);
  void publish_bank();
  void set_condition(Sensor sensor, Source src, bool on, FaultKind kind, double t,
                     const std::string& message, std::vector<Detection>* out);
  Detection make_detection(Sensor sensor, bool active, FaultKind kind, double t) const;
  void sensor_checks(const Sample& s, std::vector<Detection>* out);
  /// The jump check of both channels (model-free: runs armed or not).
  void jump_checks(const Sample& s, std::vector<Detection>* out);
  /// Each channel's check on one sample; their statistics into the status.
  void update_jump_checks(const Sample& s, JumpVerdict verdict[2]);
  /// A channel's verdict turned into conditions; e: both channels' excess evidence.
  void apply_jump_verdict(int c, const JumpVerdict& v, const Vec2& e, double t,
                          std::vector<Detection>* out);
  /// The jump raised just before a noise rise was its first samples: one noise condition.
  void jump_was_noise(int c, const std::string& message, double t, std::vector<Detection>* out);
  /// The observers, live, take over a jump's condition.
  void hand_jump_to_observers(int c, const char* name, double t, std::vector<Detection>* out);
  /// The observers are designed, settled and have learned their statistics.
  bool model_live() const;
  /// The observers' residuals, one sample: a short sequence of the steps below.
  void residual_checks(const Sample& s, double dt, std::vector<Detection>* out);
  /// A sample's raw statistics: structured s (0, 1) and cross d (2, 3) residuals, and the
  /// whitened structured residual sw.
  struct Statistics {
    double raw[4] = {0.0, 0.0, 0.0, 0.0};
    Vec2 sw = Vec2::Constant(kNaN);
  };
  /// The statistics against their thresholds.
  struct Levels {
    Vec2 thr = Vec2::Zero();         ///< enter thresholds on J_N
    Vec2 ratio = Vec2::Zero();       ///< J_N / thr (0 while a window refills or resettles)
    bool live[2] = {true, true};     ///< ratio(c) is from a full window, settled
    Vec2 thr_exit_d = Vec2::Zero();  ///< leave thresholds on D_N
    std::size_t n_full = 0;          ///< samples in a full window
  };
  /// Candidate raise: 0 accelerometer, 1 gyro, 2 model mismatch (not a sensor), -1 none.
  struct Candidate {
    int k = -1;
    int reclassify = -1;  ///< a raised sensor whose evidence turned out to be the model's
    int repeated = -1;    ///< a sensor whose last raise nothing held, rising again
  };
  void propagate_observers(const Sample& s, double dt, bool v_ok, bool r_ok);
  void resync_observers(const Sample& s, bool v_ok, bool r_ok);
  /// Healthy for the maxima the bars follow: both channels usable, no fault raised now or
  /// within resume_after_fault, the data consistent with identification. A model-mismatch
  /// verdict does not stop it (its residual is the model's, and the bar must know it); the
  /// scales and the other statistics learn only without one.
  bool healthy_for_maxima(double t, bool v_ok, bool r_ok) const;
  /// Evaluates the redesign (which takes over once it has learned) and the active bank;
  /// false when nothing more is to be done on this sample (settling, no rudder, scales not
  /// learned yet).
  bool evaluate_banks(const Sample& s, double dt, bool learn_ok, bool v_ok, bool r_ok,
                      Statistics* x);
  void record_statistics(double t, const Statistics& x, bool maxima_ok);
  void update_monitors(const Sample& s, double dt, bool v_ok, bool r_ok);
  void update_confidences();
  void check_spikes(double t, const Vec2& sw, std::vector<Detection>* out);
  Levels levels(double t, double dt) const;
  /// Keeps a channel that has not been at or below its bar since arming out of the levels.
  void await_onsets(Levels* lv);
  Candidate choose_candidate(double t, const Levels& lv);
  void confirm_candidate(double t, const Levels& lv, const Candidate& c,
                         std::vector<Detection>* out);
  void refine_kinds(double t, std::vector<Detection>* out);
  void hold_or_clear(double t, const Levels& lv, int candidate, std::vector<Detection>* out);
  /// The drift test of both channels on one sample (IsolationParams::drift_k).
  void drift_checks(double t, double dt, const Statistics& x, bool learn_ok, const Levels& lv,
                    std::vector<Detection>* out);
  void reset_drift(double t);
  /// The fault kind of a channel from its histories (core/fault_kind.hpp).
  FaultKind classify(int ch) const;
  std::size_t window_samples(double dt) const;
  double learned_threshold(std::vector<double>* healthy) const;
  /// Un-arms the residual checks (LostConvergence::kUnarm): their conditions clear, the banks
  /// and the channels' residual state are dropped; set_estimate arms again.
  void unarm(double t, std::vector<Detection>* out);
  /// Drops the redesign learning beside the design in force, if any.
  void drop_shadow();
  bool unarm_pending_ = false;
  /// Forget a bank's learning: it learns its scales and bars again from the next healthy data.
  void restart_learning(Bank* b);
  /// The highest threshold a windowed statistic of clipped squares reaches with margin.
  double reachable_threshold() const;
  /// A closed bar, in clip^2 (close_capped_bars): above clip^2, which a windowed mean of
  /// squares clipped at +-clip never passes.
  static constexpr double kClosedBar = 1.05;
  /// The bar the healthy past sets for a statistic whose healthy maximum is healthy_max.
  double history_threshold(double healthy_max) const;

  IsolationParams p_;
  Vec2 B_;
  SpeedRatio speed_;
  double in_obs_ = 1.0;  ///< the observers' input factor s^(k-1) (core/speed.hpp)
  IsolatorStatus st_;
  Bank act_;     ///< the bank in force
  Bank shadow_;  ///< a redesign learning beside it
  bool has_shadow_ = false;
  bool have_prev_ = false;
  Sample prev_{};
  double t_armed_ = kNaN;
  double mismatch_since_ = kNaN;  ///< the current model-mismatch verdict began
  double below_mm_since_ = kNaN;  ///< ... and its statistics have been quiet since
  int mismatch_repeated_ = -1;    ///< the verdict was a channel's repeated rise (Candidate)
  int repeat_rise_ = -1;          ///< the candidate of the last sample was that repeated rise
  double settle_time_ = 0.0;
  double t_last_suspect_ = -1e300;
  double t_last_fault_ = -1e300;
  bool was_faulty_ = false;  ///< a fault condition was active at the last sample
  bool freeze_ = false;
  bool data_inconsistent_ = false;  ///< identification's guard keeps the latest data out
  bool scales_configured_ = false;
  SensorChecks checks_;            ///< stale, stuck, invalid and timing
  std::array<JumpCheck, 2> jump_;  ///< v, r
  /// Healthy maxima of J_N and D_N of the bank in force [J_a, J_g, D_a, D_g], learned from
  /// samples once they are older than a raise could be late (history_lag()).
  HealthyMaxima<4> healthy_;
  struct PendingStat {
    double t;
    double x[4];
    bool ok;
  };
  std::deque<PendingStat> pending_stats_;
  // The drift test: its CUSUMs per channel (high and low side, and when each side last was
  // 0), and their healthy maxima, learned from values drift_lag old.
  std::array<double, 2> drift_hi_{}, drift_lo_{};
  std::array<double, 2> drift_from_hi_{}, drift_from_lo_{};
  double drift_last_t_ = kNaN;  ///< the last sample the test saw
  HealthyMaxima<2> drift_healthy_;
  struct PendingDrift {
    double t;
    double x[2];
    bool ok;
  };
  std::deque<PendingDrift> pending_drift_;
  double history_lag() const;
  /// How long J_N must stay above its bar to raise a sensor (enter_time, times young_enter_ratio
  /// while the bars are young).
  double sensor_enter_time() const;
  double last_delta_ = kNaN;
  std::array<ChannelState, 2> chan_;  ///< v, r
  std::array<SensorState, 3> sens_;   ///< accelerometer, gyro, unknown
  void start_monitor(int ch);
};

}  // namespace usvfdi
