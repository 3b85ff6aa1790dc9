// Identification of the unknown sway-yaw matrix A by DREM (dynamic regressor extension
// and mixing), Bazylev & Margun section 3, with the better-conditioned variant of
// docs/design.md section 2 (normalised update, Kreisselmeier regressor extension).
//
//   q = F1[y],  m = p F1[y] - B F1[delta] = eps1 (y - q) - B F1[delta]   =>  m = A q
//   paper:        R = [[q1 q2], [qb1 qb2]] (second filter eps2), G1 = [m1 mb1]^T, G2 = [m2 mb2]^T,
//                 psi = det R, [h1 h2]^T = adj(R) G1, [h3 h4]^T = adj(R) G2  =>  h_n = psi a_n
//   kreisselmeier: Phi' = -lambda Phi + z q^T, Y' = -lambda Y + z m^T  =>  Y = Phi A^T,
//                 psi = det Phi, adj(Phi) Y = psi A^T, for ANY instrument z:
//                 z = q (least squares, "regressor") or z = F1[x_aux] ("rudder",
//                 instrumental variables from an auxiliary model driven by the rudder)
//   scalar laws:  a_n' = gamma psi (h_n - psi a_n)                       (paper)
//                 a_n' = gamma psi (h_n - psi a_n) / (mu S^2 + psi^2)     (normalised)
//                 S = the regressor's scale (Phi00 Phi11, or the column-norm product of the
//                 paper's R), so psi / S is the excitation in [0, 1] and mu is dimensionless:
//                 the law does not slow down on a vessel whose signals are merely small.
// Each scalar law is advanced by its exact solution over one step, which is stable for any
// gain and step: a <- h/psi + (a - h/psi) exp(-gamma psi^2 dt / (mu S^2 + psi^2)).
//
// Why instruments. The regressor q = F1[y] is built from the MEASURED y = x + n, so it
// carries the sensor noise low-pass filtered, n_q = F1[n], of covariance N ~ D eps1 dt / 2
// (D = diag(sigma_v^2, sigma_r^2)) for white noise sampled every dt: the sampled noise has
// the spectral density D dt, so its filtered part grows with the sample interval. With
// z = q the memories are Phi = Phi_x + int N, and the estimate is A Phi_x (Phi_x + N)^-1:
// every entry is shrunk towards zero (errors in variables, attenuation), amplified by
// 1/excitation when v and r move together (a turning vessel: excitation ~0.04 on the
// Otter). With the Otter's INS noise that is 4-6 % at 10 Hz and ~1 % at 50 Hz. The current
// sample's noise also enters both q (weight 5/12 eps1 dt with the curvature term) and m
// (weight eps1): a cross term E[n_q n_m^T] = -D eps1^2 dt / 12 in Y, eps1/6 of N and of the
// opposite sign (O(dt^2) without the curvature term). It is not the main mechanism: most
// of N comes from the earlier samples in F1's memory, so no discretisation of q removes it.
//
// Instruments uncorrelated with the INS noise remove both terms at any rate and noise
// level: E[z n_q^T] = E[z n_m^T] = 0, so Y = Phi A^T holds in expectation, and exactly on
// noise-free data. The instruments are those of the refined instrumental-variable method
// for continuous-time models (Young; Garnier): the state of an auxiliary model driven by
// the rudder alone, x_aux' = A_aux x_aux + B delta, filtered like the regressor, z =
// F1[x_aux]. With A_aux close to A, z resembles the noise-free q, so the extended regressor
// is as well conditioned as the least-squares one. A_aux is the least-squares estimate of
// the same memory (biased by a few % at 10 Hz, which costs the instruments nothing),
// refreshed once per settle_window, shifted left if needed so that its slowest pole is no
// slower than -lambda (a course-unstable estimate would make x_aux diverge); before any
// estimate exists it is -eps1 [[1, -1], [1, 1]] (poles -eps1 +- i eps1, excited by any
// B != 0). The rows of z are rescaled to the RMS of q's components (any invertible row
// scaling leaves adj(Phi) Y / det Phi unchanged), so psi and the excitation keep their
// least-squares meaning. The rudder must not be driven by the INS noise: an autopilot that
// steers on the measured yaw rate feeds a filtered trace of the gyro noise back into
// delta, and with it a (much smaller, second-order) correlation into the instruments.
//
// Consistency guard: core/consistency_guard.hpp (the memory is built from segments that
// agree with it; docs/design.md section 8.1).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "usv_fdi/core/consistency_guard.hpp"
#include "usv_fdi/core/filters.hpp"
#include "usv_fdi/core/speed.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi {

enum class IdentMethod : std::uint8_t {
  kPaper = 0,      ///< two filters eps1, eps2, as written in the paper
  kKreisselmeier,  ///< one filter eps1 + Kreisselmeier extension (default, best on benchmark)
};

/// Instruments of the Kreisselmeier extension (Phi' = -lambda Phi + z q^T).
enum class Instruments : std::uint8_t {
  kRegressor = 0,  ///< z = q: least squares (biased by sensor noise, see header comment)
  kRudder,         ///< z = F1[x_aux], auxiliary model driven by the rudder (default)
};

/// What the convergence criterion's precision and settling tests measure.
enum class Precision : std::uint8_t {
  /// Each a_n: its standard error and its change per window relative to max(|a_n|,
  /// settle_floor) (the tiny a_n of a slow ship rarely pass).
  kCoefficients = 0,
  /// The model's prediction a_i^T q over the memory's regressors: the error the standard
  /// errors allow and the change per window, relative to RMS(a_i1 q1) + RMS(a_i2 q2), what
  /// the uncertainty does to the residuals (Identifier::relative_std_error).
  kPrediction,
};

struct IdentificationParams {
  IdentMethod method = IdentMethod::kKreisselmeier;
  Instruments instruments = Instruments::kRudder;  ///< kreisselmeier method only
  double eps1 = 1.0;                               ///< filter F1 bandwidth [1/s]
  double eps2 = 2.0;        ///< filter F2 bandwidth [1/s] (paper method only)
  double gamma = 1.0;       ///< adaptation gain: [1/s] normalised, [1/(psi^2 s)] paper law
  bool normalised = true;   ///< false: the paper's law a' = gamma psi (h - psi a)
  double mu = 1e-8;         ///< normaliser of the normalised law, in excitation^2 (> 0)
  double lambda = 0.005;    ///< Kreisselmeier forgetting rate [1/s] (200 s memory)
  double warmup_time = -1;  ///< filter warm-up before regressions are used [s]; <0: 10/min(eps)
  double max_gap = 1.0;     ///< a time gap longer than this restarts the filters [s]
  /// Bandwidth of the input prefilter (core/filters.hpp, InputPrefilter) on v, r and delta
  /// before every other filter [rad/s]; 0: none. Kreisselmeier only (the paper's method is
  /// kept as written). Off by default: at 0.3 the proving ground arms at the onset of 1598
  /// of 2300 faults instead of 1089, but detects the same 1805 and raises 459 false alarms
  /// instead of 395 (the Otters), 3 on the HSVA recordings (docs/benchmark.md).
  double prefilter = 0.0;
  bool curvature_correction = true;  ///< filter the inputs' curvature too (O(h^3) error)
  bool cubic_correction = true;      ///< and their cubic term (O(h^4); needs the curvature)
  Vec4 a0 = Vec4::Zero();            ///< initial estimate [a1 a2 a3 a4]
  // Convergence criterion (reported, and what arms the isolation thread).
  double min_excitation = 0.01;    ///< normalised excitation in [0,1] needed to converge
  double settle_window = 1.0;      ///< length of one settling window [s]
  double settle_tolerance = 0.01;  ///< max relative change (see precision) over one window
  int settle_windows = 3;          ///< consecutive settled windows needed
  double settle_floor = 1e-4;      ///< absolute floor of the relative change's denominator
  /// Kreisselmeier only: every a_n's standard error (its upper 90 % confidence bound, as it
  /// is estimated from few batches at first), relative to max(|a_n|, settle_floor), must be
  /// below this too (a growing memory moves slowly, so settling alone can pass on an
  /// estimate that is still several % off). Precision::kCoefficients.
  double max_std_error = 0.05;
  /// Precision::kPrediction: the relative RMS error of the model's prediction that the
  /// standard errors allow (upper 90 % bound; Estimate::uncertainty) must be below this.
  double max_prediction_error = 0.02;
  /// What max_std_error and settle_tolerance are relative to. Prediction (the default since
  /// 2026-12-03): what the remaining uncertainty does to the residuals, so the tiny a_n of a
  /// slow ship need not be precise; on the proving ground it arms 899 of 1166 calm voyages
  /// against coefficients' 512, sooner, and the engine then meets the model mismatch of
  /// manoeuvres and waves: 0.53 false alarms per healthy hour against 0.44 (docs/benchmark.md).
  Precision precision = Precision::kPrediction;
  /// A converged estimate whose uncertainty (Estimate::uncertainty) stays above this multiple
  /// of its limit (max_prediction_error or max_std_error) for uncertain_time is no longer
  /// converged (IdentStatus::kUncertain, Estimate::unconvergences): the data no longer support
  /// it (the memory forgot the manoeuvres that defined it), and the estimate may wander far
  /// while the status would say converged. It converges again by the ordinary criterion.
  /// 0: converged stays converged (the engine before 2026-12-07). Kreisselmeier only.
  double uncertain_ratio = 5.0;
  /// [s], see uncertain_ratio; of evaluated data (a freeze and the warm-up after it restart it)
  double uncertain_time = 10.0;
  // Consistency guard (Kreisselmeier only; see the header comment).
  bool guard = true;  ///< judge every window of data before it enters the memory
  /// A window is inconsistent when its equation-error statistic (chi-square with 4 degrees
  /// of freedom on healthy data) exceeds this ...
  double guard_threshold = 40.0;
  /// ... and it would move some a_n by more than this, relative to max(|a_n|, settle_floor)
  /// (rounding-level inconsistencies of noise-free data move nothing) [-].
  double guard_min_shift = 1e-3;
  /// The recent data compared with the memory as a whole (before convergence): when they
  /// agree among themselves and the memory fits them worse by more than guard_threshold,
  /// the memory (a fault in it from the start, or from before the guard could judge) is
  /// rebuilt from them. After convergence, data rejected for this long are let in again
  /// (a lasting change of the vessel, learned by forgetting; sensor faults are the
  /// isolation thread's to freeze) [s].
  double guard_recent_time = 60.0;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// Why the estimate has not (yet) converged; kConverged once it has.
enum class IdentStatus : std::uint8_t {
  kConverged = 0,
  kWarmingUp,      ///< filters settling after a (re)start
  kFrozen,         ///< the isolation thread froze identification (a fault suspected)
  kInconsistent,   ///< the data contradict the memory (equation error inconsistent)
  kLowExcitation,  ///< the rudder has not excited v and r independently enough yet
  kImprecise,      ///< standard errors still above max_std_error
  kSettling,       ///< the estimate still moves
  /// It had converged, and its uncertainty grew past uncertain_ratio x its limit: the data
  /// no longer support it.
  kUncertain,
};
/// "not converged: equation error inconsistent", ... ("converged" for kConverged).
const char* to_string(IdentStatus s);

/// One snapshot of the identification state (published by the identification thread).
struct Estimate {
  double t = kNaN;        ///< time of the last sample used [s]
  Mat2 A = Mat2::Zero();  ///< current estimate of A (with a speed input: A0, at U0)
  /// With a speed input: s = u / U0 of the last sample, and U0 [m/s] (1 and NaN without).
  double speed_ratio = 1.0;
  double reference_speed = kNaN;
  /// The criterion held, and the uncertainty has not since grown past uncertain_ratio x its
  /// limit (IdentificationParams::uncertain_ratio).
  bool converged = false;
  /// How often a converged estimate lost convergence because its uncertainty grew.
  std::uint64_t unconvergences = 0;
  double excitation = 0.0;   ///< normalised excitation of the extended regressor, [0,1]
  double psi = 0.0;          ///< mixed regressor psi
  double time_constant = 0;  ///< current time constant of the scalar laws [s] (inf: none)
  /// How much A changed over the last settle_window: the largest relative change of an a_n,
  /// or of the model's prediction (IdentificationParams::precision).
  double settling = 1.0;
  /// The largest relative standard error (upper 90 % bound; Identifier::relative_std_error)
  /// of the a_n or of the model's prediction (IdentificationParams::precision); must be
  /// below max_std_error or max_prediction_error to converge (inf: not known yet).
  double uncertainty = std::numeric_limits<double>::infinity();
  /// Standard error of each a_n [a_n's unit] (Kreisselmeier; NaN for the paper's method,
  /// and until three batches are in): row i of A^ is off by Phi^-1 sum w z e_i, e = m - A^ q
  /// the equation error, so Cov = Phi^-1 V_i Phi^-T with V_i = Var(sum w z e_i) estimated
  /// by tapered batch means: sums b_j of h^2 z e_i over batches of 5 / eps1 s (longer than
  /// e's correlation time), h a Hann window, two batches overlapping by half, recomputed
  /// with the current estimate from the batches' own sums (b_j = Y_j - Phi_j A^T), give the
  /// rate at which the variance grows (sum b_j b_j^T / sum int h^4 dt over the last 20
  /// batches, times n / (n - 2): A^ was fitted to them), times the memory's sum of squared
  /// weights. The taper matters: e's largest part, eps1 (n - F1[n]) in m = q' - B F1[delta],
  /// is the derivative of F1's noise; it averages out against the slow instruments, but a
  /// hard-edged batch sum of it is an end-point difference that would swamp a small error
  /// (the Mariner's yaw row). No assumption on the noise's spectrum is needed. Updated once
  /// per batch.
  Vec4 std_error = Vec4::Constant(kNaN);
  bool frozen = false;        ///< last sample was not used because of a freeze request
  bool warming_up = true;     ///< filters are settling; regressions not used yet
  std::uint64_t updates = 0;  ///< samples that updated the estimate
  IdentStatus status = IdentStatus::kWarmingUp;  ///< what the convergence waits for
  // Consistency guard (Kreisselmeier).
  bool consistent = true;    ///< the last judged window agreed with the memory
  double consistency = 0.0;  ///< its equation-error statistic (chi-square, 4 dof when healthy)
  double inconsistent_time = 0.0;      ///< length of the current run of rejected data [s]
  std::uint64_t rejected_windows = 0;  ///< windows kept out of the memory
  double rejected_time = 0.0;          ///< data kept out of the memory [s]
  std::uint64_t removed_windows = 0;   ///< windows taken out of the memory later
  std::uint64_t resets = 0;            ///< memory rebuilt from the recent data
  /// Wald statistic of the memory's estimate against the recent data's own (chi-square, 4
  /// degrees of freedom when both describe one vessel; before convergence only).
  double memory_mismatch = 0.0;
  /// A detector downstream checks the data (Identifier::set_supervised).
  bool supervised = false;
};

class Identifier {
 public:
  /// Throws std::invalid_argument on bad parameters. With a speed input (Sample::u) the
  /// estimate is A0, A at the reference speed (core/speed.hpp), and B is B0.
  Identifier(const IdentificationParams& params, const Vec2& B, const SpeedParams& speed = {});

  /// Feeds one sample. With freeze = true nothing in the estimator's memory changes (the
  /// filters restart, with a warm-up, on the first sample after the freeze).
  /// Returns false (and changes nothing) when the sample is unusable: a value is not
  /// finite, or t does not increase.
  bool update(const Sample& s, bool freeze);

  /// Whether a detector downstream checks the data (the isolation thread is armed and has
  /// learned): only then is a lasting inconsistency that it does not flag taken for a
  /// change of the vessel (guard_recent_time); otherwise the guard holds.
  void set_supervised(bool supervised) { supervised_ = est_.supervised = supervised; }

  const Estimate& estimate() const { return est_; }
  const IdentificationParams& params() const { return p_; }

  /// Latest mixed quantities, for tests of the DREM identity h_n = psi a_n.
  double psi() const { return psi_; }
  const Vec4& h() const { return h_; }
  /// Latest regression pair (m = A q holds for noise-free data; with a speed input q is
  /// F1[s y] and A is A0).
  const Vec2& q() const { return qs_; }
  const Vec2& m() const { return m_; }
  /// Latest instrument vector (z = q for the regressor instruments).
  const Vec2& z() const { return z_; }
  /// The auxiliary model's matrix A_aux that generates the rudder instruments.
  const Mat2& aux_model() const { return A_aux_; }
  /// The speed ratio s = u / U0 (1 without a speed input).
  const SpeedRatio& speed() const { return speed_; }

 private:
  void restart_filters(const Sample& s);
  void step_instruments(double dt, double delta_prev, double s_prev, double s_now);
  void refresh_aux_model(double t);
  void advance_scalar_laws(double dt);
  void update_convergence(double t);
  using Vec3 = Eigen::Matrix<double, 3, 1>;
  /// The inputs' curvature over the step and its change (zero until known), and the
  /// previous step hp [s].
  struct InputCorrections {
    Vec3 dd = Vec3::Zero(), c3 = Vec3::Zero();
    double hp = 0.0;
  };
  InputCorrections input_corrections(const Sample& s, double dt);
  /// One step of every filter: q, F1[delta], the speed-scaled regressor, m, the instruments
  /// and (the paper's method) the second filter.
  void filter_sample(const Sample& s, double dt, double sr, bool rudder_iv);
  /// The paper's mixing: Psi = det R and h = adj(R) [m; mb].
  void mix_paper();

  IdentificationParams p_;
  Vec2 B_;
  InputPrefilter prefilter_;
  double warmup_;
  FohLowPass f1_, f2_;
  bool have_prev_ = false;
  bool restart_pending_ = true;
  double t_last_ = kNaN;  ///< time of the last accepted sample (frozen or not)
  Sample prev_{};
  Sample prev2_{};  ///< the sample before prev_ (for the curvature)
  bool have_prev2_ = false;
  Vec3 dd_prev_ = Vec3::Zero();  ///< curvatures of v, r, delta over the previous stencil
  double t_dd_prev_ = kNaN;      ///< first node of that stencil
  bool have_dd_prev_ = false;
  double t_start_ = kNaN;  ///< time the filters (re)started
  // filter states: F1[y], F1[delta], F2[y], F2[delta]
  Vec2 q_ = Vec2::Zero(), m_ = Vec2::Zero();
  Vec2 qb_ = Vec2::Zero(), mb_ = Vec2::Zero();
  double fd1_ = 0.0, fd2_ = 0.0;
  // Speed (core/speed.hpp): x' = s A0 x + s^2 B0 delta, so m = F1[x'] - B0 F1[s^2 delta] =
  // A0 F1[s x]: the regressor qs_ = F1[s y] and fds_ = F1[s^2 delta] (q_ and fd1_ when s = 1).
  SpeedRatio speed_;
  double s_prev_ = 1.0;     ///< s of prev_
  double s_aux_ = 1.0;      ///< s of the instruments' discretisation (steps of speed.quantum)
  Vec2 qs_ = Vec2::Zero();  ///< F1[s y], the regressor
  double fds_ = 0.0;        ///< F1[s^2 delta]
  // Rudder instruments: auxiliary model x_aux' = A_aux x_aux + B delta, z = F1[x_aux].
  Mat2 A_aux_;
  Mat2 Ad_aux_ = Mat2::Identity();
  Vec2 Bd_aux_ = Vec2::Zero();
  double h_aux_ = -1.0;        ///< step Ad_aux_, Bd_aux_ were computed for (<0: stale)
  double t_aux_ = kNaN;        ///< time A_aux_ was last refreshed
  Vec2 x_aux_ = Vec2::Zero();  ///< kept across filter restarts (it depends on delta only)
  Vec2 z_ = Vec2::Zero();
  // The Kreisselmeier memory, built from judged segments (core/consistency_guard.hpp).
  ConsistencyGuard guard_;
  static constexpr int kStdBatches = 20;  ///< standard errors from the latest windows
  bool supervised_ = false;               ///< see set_supervised
  void step_memories(double t, double dt, bool rudder_iv);
  void commit_mixing(bool rudder_iv);
  void update_std_error();
  /// The largest upper-bound relative standard error (inf while there are none):
  /// Precision::kCoefficients, of each a_n relative to max(|a_n|, settle_floor);
  /// Precision::kPrediction, what the uncertainty of A does to the model's prediction (the
  /// tiny a_n of a slow ship never pass a relative test and barely matter): per row i, the
  /// RMS over the memory's regressors q of the error of a_i^T q, relative to
  /// prediction_scale.
  double relative_std_error(const Vec4& a) const;
  /// Row i's prediction scale over the memory: RMS(a_i1 q_1) + RMS(a_i2 q_2).
  double prediction_scale(const Vec4& a, int i) const;
  /// Per row, the RMS of d_i^T q over the memory relative to prediction_scale (d: a change
  /// of the parameters, a: the estimate), the larger row: how much a change of A moves
  /// the model's prediction.
  double relative_prediction_change(const Vec4& d, const Vec4& a) const;
  /// Row i's covariance of (a_{i,1}, a_{i,2}) (update_std_error).
  std::array<Mat2, 2> row_cov_{Mat2::Constant(kNaN), Mat2::Constant(kNaN)};
  double std_error_dof_ = 0.0;  ///< effective degrees of freedom of the noise level
  double psi_ = 0.0;
  double scale_ = 0.0;  ///< S: psi / S is the excitation
  Vec4 h_ = Vec4::Zero();
  Vec4 a_;
  // convergence bookkeeping
  Vec4 a_ref_;
  double t_ref_ = kNaN;
  int settled_count_ = 0;
  double t_uncertain_ = kNaN;  ///< since when a converged estimate's uncertainty is too high
  Estimate est_;
};

}  // namespace usvfdi
