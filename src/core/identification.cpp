#include "usv_fdi/core/identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace usvfdi {
namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("identification.") + field + " = " +
                                std::to_string(value) + ": " + what);
  }
}

bool finite(const Sample& s) {
  return std::isfinite(s.t) && std::isfinite(s.v) && std::isfinite(s.r) && std::isfinite(s.delta);
}

}  // namespace

void IdentificationParams::validate() const {
  require(std::isfinite(eps1) && eps1 > 0, "eps1", eps1, "must be a positive number");
  if (method == IdentMethod::kPaper) {
    require(std::isfinite(eps2) && eps2 > 0, "eps2", eps2, "must be a positive number");
    require(eps2 != eps1, "eps2", eps2, "must differ from eps1 (R would be singular)");
  }
  require(std::isfinite(gamma) && gamma > 0, "gamma", gamma, "must be a positive number");
  if (normalised) require(std::isfinite(mu) && mu > 0, "mu", mu, "must be a positive number");
  require(std::isfinite(lambda) && lambda > 0, "lambda", lambda, "must be a positive number");
  require(std::isfinite(warmup_time), "warmup_time", warmup_time, "must be a number");
  require(std::isfinite(max_gap) && max_gap > 0, "max_gap", max_gap, "must be positive");
  require(std::isfinite(prefilter) && prefilter >= 0, "prefilter", prefilter,
          "must be 0 (none) or a positive bandwidth");
  require(a0.allFinite(), "a0", a0.norm(), "must be finite");
  require(min_excitation >= 0 && min_excitation <= 1, "min_excitation", min_excitation,
          "must lie in [0, 1]");
  require(settle_window > 0, "settle_window", settle_window, "must be positive");
  require(settle_tolerance > 0, "settle_tolerance", settle_tolerance, "must be positive");
  require(settle_windows >= 1, "settle_windows", settle_windows, "must be at least 1");
  require(settle_floor >= 0, "settle_floor", settle_floor, "must not be negative");
  require(max_std_error > 0, "max_std_error", max_std_error, "must be positive");
  require(guard_threshold > 0, "guard_threshold", guard_threshold, "must be positive");
  require(guard_min_shift >= 0, "guard_min_shift", guard_min_shift, "must not be negative");
  require(guard_recent_time > 0, "guard_recent_time", guard_recent_time, "must be positive");
  require(uncertain_ratio == 0 || uncertain_ratio >= 1, "uncertain_ratio", uncertain_ratio,
          "must be 0 (off) or at least 1");
  require(uncertain_time >= 0, "uncertain_time", uncertain_time, "must not be negative");
}

const char* to_string(IdentStatus s) {
  switch (s) {
    case IdentStatus::kConverged:
      return "converged";
    case IdentStatus::kWarmingUp:
      return "not converged: filters warming up";
    case IdentStatus::kFrozen:
      return "not converged: frozen (fault suspected)";
    case IdentStatus::kInconsistent:
      return "not converged: equation error inconsistent";
    case IdentStatus::kLowExcitation:
      return "not converged: excitation too low";
    case IdentStatus::kImprecise:
      return "not converged: standard errors too large";
    case IdentStatus::kSettling:
      return "not converged: estimate settling";
    case IdentStatus::kUncertain:
      return "not converged: uncertainty grew after convergence";
  }
  return "?";
}

Identifier::Identifier(const IdentificationParams& params, const Vec2& B, const SpeedParams& speed)
    : p_(params),
      B_(B),
      prefilter_(params.method == IdentMethod::kPaper ? 0.0 : params.prefilter),
      f1_(params.eps1),
      f2_(params.eps2),
      speed_(speed),
      guard_(ConsistencyGuard::Settings{
          params.guard && params.method == IdentMethod::kKreisselmeier, params.lambda, params.eps1,
          params.guard_threshold, params.guard_min_shift, params.guard_recent_time,
          params.settle_floor}),
      a_(params.a0),
      a_ref_(params.a0) {
  p_.validate();
  if (!B.allFinite()) throw std::invalid_argument("model.B must be finite");
  const double eps_min = p_.method == IdentMethod::kPaper ? std::min(p_.eps1, p_.eps2) : p_.eps1;
  warmup_ = p_.warmup_time >= 0 ? p_.warmup_time : 10.0 / eps_min;
  est_.A = from_params(a_);
  est_.time_constant = std::numeric_limits<double>::infinity();
  // Before any estimate: poles -eps1 +- i eps1, so x_aux has two independent components for
  // any B != 0 (B is never an eigenvector of a rotation).
  A_aux_ << -p_.eps1, p_.eps1, -p_.eps1, -p_.eps1;
}

void Identifier::step_instruments(double dt, double delta_prev, double s_prev, double s_now) {
  // At speed ratio s the auxiliary model is x' = s A_aux x + s^2 B delta: A_aux over the
  // vessel's own time s dt, driven by s delta (s in steps of speed.quantum, so that a
  // slowly changing speed does not re-discretise on every sample).
  if (std::abs(s_now - s_aux_) > speed_.params().quantum * s_aux_) {
    s_aux_ = s_now;
    h_aux_ = -1.0;
  }
  const double h = s_aux_ * dt;
  if (std::abs(h - h_aux_) > 1e-9 * h) {
    // Exact ZOH discretisation of x' = A_aux x + B delta over h.
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    M.topLeftCorner<2, 2>() = A_aux_ * h;
    M.topRightCorner<2, 1>() = B_ * h;
    const Eigen::Matrix3d E = M.exp();
    Ad_aux_ = E.topLeftCorner<2, 2>();
    Bd_aux_ = E.topRightCorner<2, 1>();
    h_aux_ = h;
  }
  const Vec2 x_prev = x_aux_;
  x_aux_ = Ad_aux_ * x_aux_ + Bd_aux_ * (speed_.input_factor(s_aux_) / s_aux_ * delta_prev);
  // F1[s x_aux] as the regressor F1[s y] (first-order hold; the instruments need no
  // particular accuracy).
  for (int i = 0; i < 2; ++i) z_(i) = f1_.step(s_prev * x_prev(i), s_now * x_aux_(i), z_(i));
}

void Identifier::refresh_aux_model(double t) {
  if (!std::isnan(t_aux_) && t - t_aux_ < p_.settle_window) return;
  t_aux_ = t;
  // The least-squares estimate of the same memory, when it is defined, with the data still
  // waiting for their verdict: the instruments need no verdict (any A_aux gives valid
  // ones), only to resemble q as early as possible, and a rejected segment leaves this sum
  // with the next refresh.
  Mat2 Phi_ls, Y_ls;
  guard_.least_squares_with_pending(&Phi_ls, &Y_ls);
  const double det = Phi_ls.determinant();
  if (!(det > 1e-6 * Phi_ls(0, 0) * Phi_ls(1, 1))) return;
  Mat2 A = (Phi_ls.partialPivLu().solve(Y_ls)).transpose();
  if (!A.allFinite()) return;
  // Slowest pole no slower than -lambda: shift the spectrum left where needed.
  const double half_tr = 0.5 * A.trace(), disc = half_tr * half_tr - A.determinant();
  const double re_max = disc >= 0 ? half_tr + std::sqrt(disc) : half_tr;
  const double shift = std::max(0.0, re_max + p_.lambda);
  A -= shift * Mat2::Identity();
  const double change = (A - A_aux_).norm() / A_aux_.norm();
  if (change <= 1e-3) return;
  A_aux_ = A;
  h_aux_ = -1.0;  // re-discretise on the next step
}

void Identifier::restart_filters(const Sample& s) {
  // A grown uncertainty must last uncertain_time of evaluated data: a freeze and the warm-up
  // after it change nothing in the memory, and do not count.
  t_uncertain_ = kNaN;
  // Zero initial conditions, as in the paper; the warm-up hides the e^{-eps t} transient.
  q_.setZero();
  m_.setZero();
  qb_.setZero();
  mb_.setZero();
  fd1_ = fd2_ = 0.0;
  qs_.setZero();
  fds_ = 0.0;
  s_prev_ = speed_.ratio();
  z_.setZero();  // x_aux_ carries on: it depends on the rudder only
  // A window must not straddle the restart (the sums after it use fresh filters), and the
  // data no window has judged yet is dropped with them.
  guard_.restart();
  prev_ = s;
  have_prev_ = true;
  have_prev2_ = false;
  have_dd_prev_ = false;
  restart_pending_ = false;
  t_start_ = s.t;
  est_.warming_up = true;
}

bool Identifier::update(const Sample& raw, bool freeze) {
  if (!finite(raw)) return false;
  // Time must increase over every accepted sample, frozen ones included.
  if (!std::isnan(t_last_) && !(raw.t > t_last_)) return false;
  // The prefilter runs on every accepted sample, frozen ones too, so that it is settled
  // when identification resumes; a gap restarts it with the other filters.
  if (std::isnan(t_last_) || raw.t - t_last_ > p_.max_gap) prefilter_.reset();
  Sample s = raw;
  if (prefilter_.enabled()) {
    const InputPrefilter::Vec3 y =
        prefilter_.step(raw.t - t_last_, InputPrefilter::Vec3(raw.v, raw.r, raw.delta));
    s.v = y(0);
    s.r = y(1);
    s.delta = y(2);
  }
  t_last_ = s.t;
  est_.t = s.t;
  const double sr = speed_.update(s);
  est_.speed_ratio = sr;
  est_.reference_speed = speed_.reference_speed();
  if (freeze) {
    est_.frozen = true;
    restart_pending_ = true;
    if (!est_.converged) est_.status = IdentStatus::kFrozen;
    return true;
  }
  est_.frozen = false;
  if (restart_pending_ || !have_prev_ || s.t - prev_.t > p_.max_gap) {
    restart_filters(s);
    return true;
  }
  const double dt = s.t - prev_.t;
  const bool rudder_iv =
      p_.method == IdentMethod::kKreisselmeier && p_.instruments == Instruments::kRudder;
  filter_sample(s, dt, sr, rudder_iv);
  prev2_ = prev_;
  have_prev2_ = true;
  prev_ = s;
  s_prev_ = sr;
  est_.warming_up = s.t - t_start_ < warmup_;
  if (est_.warming_up) {
    if (!est_.converged) est_.status = IdentStatus::kWarmingUp;
    return true;
  }
  if (p_.method == IdentMethod::kPaper) {
    mix_paper();
  } else {
    step_memories(s.t, dt, rudder_iv);
    if (rudder_iv) refresh_aux_model(s.t);
  }
  advance_scalar_laws(dt);
  update_convergence(s.t);
  return true;
}

Identifier::InputCorrections Identifier::input_corrections(const Sample& s, double dt) {
  // Curvature of each input over the step (zero until three samples are known), and its
  // change, the cubic term (zero until four are known).
  InputCorrections c;
  c.hp = dt;
  if (!p_.curvature_correction || !have_prev2_) return c;
  c.hp = prev_.t - prev2_.t;
  c.dd(0) = FohLowPass::curvature(prev2_.v, prev_.v, s.v, c.hp, dt);
  c.dd(1) = FohLowPass::curvature(prev2_.r, prev_.r, s.r, c.hp, dt);
  c.dd(2) = FohLowPass::curvature(prev2_.delta, prev_.delta, s.delta, c.hp, dt);
  if (p_.cubic_correction && have_dd_prev_) {
    for (int i = 0; i < 3; ++i) {
      c.c3(i) = FohLowPass::third_difference(c.dd(i), dd_prev_(i), s.t - t_dd_prev_);
    }
  }
  dd_prev_ = c.dd;
  t_dd_prev_ = prev2_.t;
  have_dd_prev_ = true;
  return c;
}

void Identifier::filter_sample(const Sample& s, double dt, double sr, bool rudder_iv) {
  const Vec2 y(s.v, s.r), y_prev(prev_.v, prev_.r);
  const InputCorrections c = input_corrections(s, dt);
  const Vec3& dd = c.dd;
  const Vec3& c3 = c.c3;
  f1_.set_step(dt, c.hp);
  for (int i = 0; i < 2; ++i) q_(i) = f1_.step_cubic(y_prev(i), y(i), dd(i), c3(i), q_(i));
  fd1_ = f1_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd1_);
  // The paper's method is kept as written: it knows no speed.
  if (speed_.measured() && p_.method != IdentMethod::kPaper) {
    // The curvature and cubic terms of s y are taken as s times those of y (s changes
    // slowly); the end points are exact.
    const double sp = s_prev_;
    for (int i = 0; i < 2; ++i) {
      qs_(i) = f1_.step_cubic(sp * y_prev(i), sr * y(i), sr * dd(i), sr * c3(i), qs_(i));
    }
    const double kp = speed_.input_factor(sp), kn = speed_.input_factor(sr);
    fds_ = f1_.step_cubic(kp * prev_.delta, kn * s.delta, kn * dd(2), kn * c3(2), fds_);
  } else {
    qs_ = q_;
    fds_ = fd1_;
  }
  m_ = p_.eps1 * (y - q_) - B_ * fds_;
  if (rudder_iv) {
    step_instruments(dt, prev_.delta, s_prev_, sr);
  } else {
    z_ = qs_;
  }
  if (p_.method == IdentMethod::kPaper) {
    f2_.set_step(dt, c.hp);
    for (int i = 0; i < 2; ++i) qb_(i) = f2_.step_cubic(y_prev(i), y(i), dd(i), c3(i), qb_(i));
    fd2_ = f2_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd2_);
    mb_ = p_.eps2 * (y - qb_) - B_ * fd2_;
  }
}

void Identifier::mix_paper() {
  // R = [[q1 q2], [qb1 qb2]]; adj(R) = [[qb2 -q2], [-qb1 q1]].
  Mat2 R;
  R << q_(0), q_(1), qb_(0), qb_(1);
  psi_ = R.determinant();
  Mat2 adj;
  adj << R(1, 1), -R(0, 1), -R(1, 0), R(0, 0);
  const Vec2 h12 = adj * Vec2(m_(0), mb_(0));
  const Vec2 h34 = adj * Vec2(m_(1), mb_(1));
  h_ << h12, h34;
  scale_ = R.col(0).norm() * R.col(1).norm();
  est_.excitation = scale_ > 0 ? std::abs(psi_) / scale_ : 0.0;
}

void Identifier::step_memories(double t, double dt, bool rudder_iv) {
  const ConsistencyGuard::Change c = guard_.add(t, dt, qs_, m_, z_, est_.converged, supervised_);
  const GuardReport& g = guard_.report();
  est_.consistent = g.consistent;
  est_.consistency = g.consistency;
  est_.inconsistent_time = g.inconsistent_time;
  est_.rejected_windows = g.rejected_windows;
  est_.rejected_time = g.rejected_time;
  est_.removed_windows = g.removed_windows;
  est_.resets = g.resets;
  est_.memory_mismatch = g.memory_mismatch;
  if (c.unsettled) settled_count_ = 0;
  if (c.reset) {
    t_ref_ = kNaN;
    est_.std_error = Vec4::Constant(kNaN);
  }
  if (c.memory) {
    commit_mixing(rudder_iv);
    update_std_error();
  }
}

void Identifier::commit_mixing(bool rudder_iv) {
  const KreisselmeierMemory& mem = guard_.memory();
  Mat2 Phi = mem.Phi_ls, Y = mem.Y_ls;
  if (rudder_iv) {
    // Rescale the instruments' rows to the RMS of q's components (the identity only needs
    // an invertible row scaling).
    Vec2 sc;
    for (int i = 0; i < 2; ++i) {
      sc(i) = mem.Szz(i) > 0 ? std::sqrt(std::max(0.0, mem.Phi_ls(i, i)) / mem.Szz(i)) : 0.0;
    }
    Phi = sc.asDiagonal() * mem.Phi;
    Y = sc.asDiagonal() * mem.Y;
  }
  psi_ = Phi.determinant();
  Mat2 adj;
  adj << Phi(1, 1), -Phi(0, 1), -Phi(1, 0), Phi(0, 0);
  const Mat2 Z = adj * Y;  // = psi A^T
  h_ << Z(0, 0), Z(1, 0), Z(0, 1), Z(1, 1);
  // |det(int z q^T)| <= sqrt(Szz0 Szz1 Phi_ls00 Phi_ls11) (Hadamard, Cauchy-Schwarz), so
  // this lies in [0, 1]; for z = q it is psi / (Phi00 Phi11) = 1 - (correlation of q1, q2)^2.
  scale_ = mem.Phi_ls(0, 0) * mem.Phi_ls(1, 1);
  est_.excitation = scale_ > 0 ? std::clamp(std::abs(psi_) / scale_, 0.0, 1.0) : 0.0;
}

void Identifier::update_std_error() {
  // Row i of A^ is off by Phi^-1 sum w z e_i: Cov_i = Phi^-1 V_i Phi^-T, with V_i = (the
  // recent rate of Var(b_i)) x (the memory's sum of squared weights), from the last
  // kStdBatches accepted windows (tapered batch sums b = Y - Phi A^T, see
  // Estimate::std_error).
  const KreisselmeierMemory& mem = guard_.memory();
  Mat2 At;
  if (!mem.estimate(&At)) return;
  std::array<Mat2, 2> R{Mat2::Zero(), Mat2::Zero()};
  double T = 0.0;
  int n = 0;
  const auto& windows = guard_.windows();
  for (auto it = windows.rbegin(); it != windows.rend() && n < kStdBatches; ++it) {
    if (!it->accepted) continue;
    const Mat2 b = it->Y - it->Phi * At;  // column i: tapered sum of z e_i over the batch
    for (int i = 0; i < 2; ++i) R[i] += b.col(i) * b.col(i).transpose();
    T += it->H2;  // Var(b_j) = (long-run variance rate) x int h^4 dt
    ++n;
  }
  if (n < ConsistencyGuard::kMinBatches) return;
  // The b_j sum to ~0 over the memory (A^ solves its normal equations), so n batches carry
  // n - 2 degrees of freedom per row: scale by n / (n - 2).
  const double dof = n / std::max(1.0, n - 2.0);
  std_error_dof_ = n - 2.0;
  const auto lu = mem.Phi.partialPivLu();
  for (int i = 0; i < 2; ++i) {
    const Mat2 G = lu.solve(R[i] * (dof * mem.W2 / T));  // Phi^-1 V_i
    const Mat2 C = lu.solve(G.transpose());              // Phi^-1 V_i Phi^-T (V_i symmetric)
    for (int j = 0; j < 2; ++j) est_.std_error(2 * i + j) = std::sqrt(std::max(0.0, C(j, j)));
    row_cov_[i] = C;
  }
}

void Identifier::advance_scalar_laws(double dt) {
  const double psi2 = psi_ * psi_;
  const double rate =
      p_.normalised ? p_.gamma * psi2 / (p_.mu * scale_ * scale_ + psi2) : p_.gamma * psi2;
  est_.psi = psi_;
  est_.time_constant = rate > 0 ? 1.0 / rate : std::numeric_limits<double>::infinity();
  if (!(psi2 > 0) || !std::isfinite(rate)) return;
  // Exact solution of a' = -rate (a - h/psi) over dt with psi, h held.
  const double w = -std::expm1(-rate * dt);
  for (int n = 0; n < 4; ++n) {
    const double target = h_(n) / psi_;
    a_(n) += w * (target - a_(n));
  }
  est_.A = from_params(a_);
  ++est_.updates;
}

double Identifier::relative_std_error(const Vec4& a) const {
  // The standard errors come from few batches at first, so their own uncertainty counts:
  // the upper 90 % confidence bound, se sqrt(k / chi2_k(0.1)), k the noise level's degrees
  // of freedom (Wilson-Hilferty for the quantile). NaN (too few batches) gives infinity.
  const double k = std::max(1.0, std_error_dof_);
  const double c = 2.0 / (9.0 * k);
  const double q = k * std::pow(std::max(1e-3, 1.0 - c - 1.2816 * std::sqrt(c)), 3.0);
  const double upper2 = k / q;
  double worst = 0.0;
  if (p_.precision == Precision::kCoefficients) {
    for (int n = 0; n < 4; ++n) {
      const double r =
          std::sqrt(upper2) * est_.std_error(n) / std::max(std::abs(a(n)), p_.settle_floor);
      worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
    }
    return worst;
  }
  for (int i = 0; i < 2; ++i) {
    // E[(da_i^T q)^2] = tr(Cov_i Q) over the memory (Q: its sum of q q^T).
    const double err = std::sqrt(upper2 * (row_cov_[i] * guard_.memory().Phi_ls).trace());
    const double r = err / prediction_scale(a, i);
    worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
  }
  return worst;
}

double Identifier::prediction_scale(const Vec4& a, int i) const {
  // The RMS of each term a_ij q_j, added: the terms of a_i^T q may cancel (in a steady turn
  // A x = -B delta), and a relative error must not grow with that cancellation.
  const Mat2& Q = guard_.memory().Phi_ls;
  const double floor = p_.settle_floor * std::sqrt(Q.trace());
  const double s = std::abs(a(2 * i)) * std::sqrt(std::max(0.0, Q(0, 0))) +
                   std::abs(a(2 * i + 1)) * std::sqrt(std::max(0.0, Q(1, 1)));
  return std::max(s, floor);
}

double Identifier::relative_prediction_change(const Vec4& d, const Vec4& a) const {
  double worst = 0.0;
  if (p_.precision == Precision::kCoefficients) {
    for (int n = 0; n < 4; ++n) {
      worst = std::max(worst, std::abs(d(n)) / (std::abs(a(n)) + p_.settle_floor));
    }
    return worst;
  }
  for (int i = 0; i < 2; ++i) {
    const Vec2 di(d(2 * i), d(2 * i + 1));
    const double r =
        std::sqrt(std::max(0.0, di.dot(guard_.memory().Phi_ls * di))) / prediction_scale(a, i);
    worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
  }
  return worst;
}

void Identifier::update_convergence(double t) {
  if (std::isnan(t_ref_)) {
    t_ref_ = t;
    a_ref_ = a_;
    return;
  }
  if (t - t_ref_ < p_.settle_window) return;
  // How much the last window's change of A moved the model's prediction (relative).
  const double d = relative_prediction_change(a_ - a_ref_, a_);
  est_.settling = d;
  bool precise = true;
  if (p_.method == IdentMethod::kKreisselmeier) {
    // The standard errors come from few batches at first, so their own uncertainty counts:
    // the test uses their upper 90 % confidence bound, se sqrt(k / chi2_k(0.1)), k = batches
    // - 2 degrees of freedom (Wilson-Hilferty for the quantile). NaN (too few batches) fails.
    est_.uncertainty = relative_std_error(a_);
    precise = est_.uncertainty <=
              (p_.precision == Precision::kPrediction ? p_.max_prediction_error : p_.max_std_error);
  }
  // Nothing converges on data the guard keeps out, nor while it keeps data out, nor before
  // it can judge (with the guard on).
  const bool consistent = guard_.consistent();
  const bool excited = est_.excitation >= p_.min_excitation &&
                       est_.time_constant <= p_.settle_window * p_.settle_windows;
  settled_count_ =
      (d < p_.settle_tolerance && precise && excited && consistent) ? settled_count_ + 1 : 0;
  if (settled_count_ >= p_.settle_windows && !est_.converged) {
    est_.converged = true;
    t_uncertain_ = kNaN;
  }
  if (est_.converged && p_.method == IdentMethod::kKreisselmeier && p_.uncertain_ratio > 0) {
    // A converged estimate the data no longer support (its uncertainty grew, the memory
    // having forgotten what defined it) is not kept as converged: it may wander far.
    const double limit =
        p_.precision == Precision::kPrediction ? p_.max_prediction_error : p_.max_std_error;
    if (!(est_.uncertainty <= p_.uncertain_ratio * limit)) {
      if (std::isnan(t_uncertain_)) t_uncertain_ = t;
      if (t - t_uncertain_ >= p_.uncertain_time) {
        est_.converged = false;
        settled_count_ = 0;
        ++est_.unconvergences;
      }
    } else {
      t_uncertain_ = kNaN;
    }
  }
  if (est_.converged) {
    est_.status = IdentStatus::kConverged;
  } else {
    // Imprecise after a loss of convergence reads uncertain (only a loss ends convergence, so
    // an estimate not converged that has lost it before has not found it again).
    est_.status =
        !consistent ? IdentStatus::kInconsistent
        : !excited  ? IdentStatus::kLowExcitation
        : !precise  ? (est_.unconvergences > 0 ? IdentStatus::kUncertain : IdentStatus::kImprecise)
                    : IdentStatus::kSettling;
  }
  t_ref_ = t;
  a_ref_ = a_;
}

}  // namespace usvfdi
