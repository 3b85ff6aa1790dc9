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
  require(a0.allFinite(), "a0", a0.norm(), "must be finite");
  require(min_excitation >= 0 && min_excitation <= 1, "min_excitation", min_excitation,
          "must lie in [0, 1]");
  require(settle_window > 0, "settle_window", settle_window, "must be positive");
  require(settle_tolerance > 0, "settle_tolerance", settle_tolerance, "must be positive");
  require(settle_windows >= 1, "settle_windows", settle_windows, "must be at least 1");
  require(settle_floor >= 0, "settle_floor", settle_floor, "must not be negative");
  require(max_std_error > 0, "max_std_error", max_std_error, "must be positive");
}

Identifier::Identifier(const IdentificationParams& params, const Vec2& B)
    : p_(params), B_(B), f1_(params.eps1), f2_(params.eps2), a_(params.a0), a_ref_(params.a0) {
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

void Identifier::step_instruments(double dt, double delta_prev) {
  if (std::abs(dt - h_aux_) > 1e-9 * dt) {
    // Exact ZOH discretisation of x' = A_aux x + B delta over dt.
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    M.topLeftCorner<2, 2>() = A_aux_ * dt;
    M.topRightCorner<2, 1>() = B_ * dt;
    const Eigen::Matrix3d E = M.exp();
    Ad_aux_ = E.topLeftCorner<2, 2>();
    Bd_aux_ = E.topRightCorner<2, 1>();
    h_aux_ = dt;
  }
  const Vec2 x_prev = x_aux_;
  x_aux_ = Ad_aux_ * x_aux_ + Bd_aux_ * delta_prev;
  // F1 as for q (first-order hold; the instruments need no particular accuracy).
  for (int i = 0; i < 2; ++i) z_(i) = f1_.step(x_prev(i), x_aux_(i), z_(i));
}

void Identifier::refresh_aux_model(double t) {
  if (!std::isnan(t_aux_) && t - t_aux_ < p_.settle_window) return;
  t_aux_ = t;
  // The least-squares estimate of the same memory, when it is defined.
  const double det = Pqq_.determinant();
  if (!(det > 1e-6 * Pqq_(0, 0) * Pqq_(1, 1))) return;
  Mat2 A = (Pqq_.partialPivLu().solve(Yqm_)).transpose();
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
  // Zero initial conditions, as in the paper; the warm-up hides the e^{-eps t} transient.
  q_.setZero();
  m_.setZero();
  qb_.setZero();
  mb_.setZero();
  fd1_ = fd2_ = 0.0;
  z_.setZero();  // x_aux_ carries on: it depends on the rudder only
  // A batch must not straddle the restart (the sums after it use fresh filters).
  open_[0] = Batch{};
  open_[1] = Batch{};
  open_[1].T = -0.5 * kBatchLength / p_.eps1;  // half a batch later
  prev_ = s;
  have_prev_ = true;
  have_prev2_ = false;
  have_dd_prev_ = false;
  restart_pending_ = false;
  t_start_ = s.t;
  est_.warming_up = true;
}

bool Identifier::update(const Sample& s, bool freeze) {
  if (!finite(s)) return false;
  // Time must increase over every accepted sample, frozen ones included.
  if (!std::isnan(t_last_) && !(s.t > t_last_)) return false;
  t_last_ = s.t;
  est_.t = s.t;
  if (freeze) {
    est_.frozen = true;
    restart_pending_ = true;
    return true;
  }
  est_.frozen = false;
  if (restart_pending_ || !have_prev_ || s.t - prev_.t > p_.max_gap) {
    restart_filters(s);
    return true;
  }
  const double dt = s.t - prev_.t;
  const Vec2 y(s.v, s.r), y_prev(prev_.v, prev_.r);
  // Curvature of each input over the step (zero until three samples are known), and its
  // change, the cubic term (zero until four are known).
  Vec3 dd = Vec3::Zero(), c3 = Vec3::Zero();
  double hp = dt;
  if (p_.curvature_correction && have_prev2_) {
    hp = prev_.t - prev2_.t;
    dd(0) = FohLowPass::curvature(prev2_.v, prev_.v, s.v, hp, dt);
    dd(1) = FohLowPass::curvature(prev2_.r, prev_.r, s.r, hp, dt);
    dd(2) = FohLowPass::curvature(prev2_.delta, prev_.delta, s.delta, hp, dt);
    if (p_.cubic_correction && have_dd_prev_) {
      for (int i = 0; i < 3; ++i) {
        c3(i) = FohLowPass::third_difference(dd(i), dd_prev_(i), s.t - t_dd_prev_);
      }
    }
    dd_prev_ = dd;
    t_dd_prev_ = prev2_.t;
    have_dd_prev_ = true;
  }
  f1_.set_step(dt, hp);
  for (int i = 0; i < 2; ++i) q_(i) = f1_.step_cubic(y_prev(i), y(i), dd(i), c3(i), q_(i));
  fd1_ = f1_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd1_);
  m_ = p_.eps1 * (y - q_) - B_ * fd1_;
  const bool rudder_iv =
      p_.method == IdentMethod::kKreisselmeier && p_.instruments == Instruments::kRudder;
  if (rudder_iv) {
    step_instruments(dt, prev_.delta);
  } else {
    z_ = q_;
  }
  if (p_.method == IdentMethod::kPaper) {
    f2_.set_step(dt, hp);
    for (int i = 0; i < 2; ++i) qb_(i) = f2_.step_cubic(y_prev(i), y(i), dd(i), c3(i), qb_(i));
    fd2_ = f2_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd2_);
    mb_ = p_.eps2 * (y - qb_) - B_ * fd2_;
  }
  prev2_ = prev_;
  have_prev2_ = true;
  prev_ = s;
  est_.warming_up = s.t - t_start_ < warmup_;
  if (est_.warming_up) return true;

  bool batch_done = false;
  if (p_.method == IdentMethod::kPaper) {
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
  } else {
    const double E = std::exp(-p_.lambda * dt);
    Pqq_ = E * Pqq_ + dt * (q_ * q_.transpose());
    Yqm_ = E * Yqm_ + dt * (q_ * m_.transpose());
    // Batch sums for the standard errors.
    // Tapered batch sums of z q^T and z m^T (two Hann windows, half a batch apart).
    const double T_b = kBatchLength / p_.eps1;
    for (Batch& b : open_) {
      b.T += dt;
      if (b.T <= 0.0) continue;  // the second window has not begun yet
      const double sn = std::sin(M_PI * std::min(1.0, b.T / T_b));
      const double w = sn * sn;  // Hann window
      b.P += w * dt * (z_ * q_.transpose());
      b.G += w * dt * (z_ * m_.transpose());
      b.H2 += w * w * dt;
      if (b.T >= T_b) {
        batches_[head_] = b;
        head_ = (head_ + 1) % kBatches;
        n_batches_ = std::min(n_batches_ + 1, kBatches);
        b = Batch{};
        batch_done = true;
      }
    }
    W2_ = std::exp(-2.0 * p_.lambda * dt) * W2_ + dt;
    Mat2 P = Pqq_, Yv = Yqm_;
    if (rudder_iv) {
      Pzq_ = E * Pzq_ + dt * (z_ * q_.transpose());
      Yzm_ = E * Yzm_ + dt * (z_ * m_.transpose());
      Szz_ = E * Szz_ + dt * z_.cwiseProduct(z_);
      // Rescale the instruments' rows to the RMS of q's components (the identity only
      // needs an invertible row scaling).
      Vec2 sc;
      for (int i = 0; i < 2; ++i) sc(i) = Szz_(i) > 0 ? std::sqrt(Pqq_(i, i) / Szz_(i)) : 0.0;
      P = sc.asDiagonal() * Pzq_;
      Yv = sc.asDiagonal() * Yzm_;
      refresh_aux_model(s.t);
    }
    psi_ = P.determinant();
    Mat2 adj;
    adj << P(1, 1), -P(0, 1), -P(1, 0), P(0, 0);
    const Mat2 Z = adj * Yv;  // = psi A^T
    h_ << Z(0, 0), Z(1, 0), Z(0, 1), Z(1, 1);
    // |det(int z q^T)| <= sqrt(Szz0 Szz1 Pqq00 Pqq11) (Hadamard, Cauchy-Schwarz), so this
    // lies in [0, 1]; for z = q it is psi / (Phi00 Phi11) = 1 - (correlation of q1, q2)^2.
    scale_ = Pqq_(0, 0) * Pqq_(1, 1);
    est_.excitation = scale_ > 0 ? std::clamp(std::abs(psi_) / scale_, 0.0, 1.0) : 0.0;
  }
  advance_scalar_laws(dt);
  if (batch_done) update_std_error();
  update_convergence(s.t);
  return true;
}

void Identifier::update_std_error() {
  // Row i of A^ is off by Pzq^-1 sum w z e_i: Cov_i = Pzq^-1 V_i Pzq^-T, with V_i = (the
  // recent rate of Var(b_i)) x (the memory's sum of squared weights).
  const Mat2 P = p_.instruments == Instruments::kRudder ? Pzq_ : Pqq_;
  if (n_batches_ < kMinBatches || !(std::abs(P.determinant()) > 0)) return;

  const Mat2 At = (psi_ != 0.0 ? from_params(h_ / psi_) : from_params(a_)).transpose();
  std::array<Mat2, 2> R{Mat2::Zero(), Mat2::Zero()};
  double T = 0.0;
  for (int k = 0; k < n_batches_; ++k) {
    const Batch& bt = batches_[k];
    const Mat2 b = bt.G - bt.P * At;  // column i: tapered sum of z e_i over the batch
    for (int i = 0; i < 2; ++i) R[i] += b.col(i) * b.col(i).transpose();
    T += bt.H2;  // Var(b_j) = (long-run variance rate) x int h^4 dt
  }
  const Mat2 Pinv = P.inverse();
  // The b_j sum to ~0 over the memory (A^ solves its normal equations), so n batches carry
  // n - 2 degrees of freedom per row: scale by n / (n - 2).
  const double dof = n_batches_ / std::max(1.0, n_batches_ - 2.0);
  for (int i = 0; i < 2; ++i) {
    const Mat2 C = Pinv * (R[i] * (dof * W2_ / T)) * Pinv.transpose();
    for (int j = 0; j < 2; ++j) {
      est_.std_error(2 * i + j) = std::sqrt(std::max(0.0, C(j, j)));
    }
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

void Identifier::update_convergence(double t) {
  if (std::isnan(t_ref_)) {
    t_ref_ = t;
    a_ref_ = a_;
    return;
  }
  if (t - t_ref_ < p_.settle_window) return;
  double d = 0.0;
  for (int n = 0; n < 4; ++n) {
    d = std::max(d, std::abs(a_(n) - a_ref_(n)) / (std::abs(a_(n)) + p_.settle_floor));
  }
  est_.settling = d;
  bool precise = true;
  if (p_.method == IdentMethod::kKreisselmeier) {
    // The standard errors come from few batches at first, so their own uncertainty counts:
    // the test uses their upper 90 % confidence bound, se sqrt(k / chi2_k(0.1)), k = batches
    // - 2 degrees of freedom (Wilson-Hilferty for the quantile). NaN (too few batches) fails.
    const double k = std::max(1, n_batches_ - 2);
    const double c = 2.0 / (9.0 * k);
    const double q = k * std::pow(std::max(1e-3, 1.0 - c - 1.2816 * std::sqrt(c)), 3.0);
    const double upper = std::sqrt(k / q);
    for (int n = 0; n < 4; ++n) {
      precise = precise && upper * est_.std_error(n) <=
                               p_.max_std_error * std::max(std::abs(a_(n)), p_.settle_floor);
    }
  }
  const bool excited = precise && est_.excitation >= p_.min_excitation &&
                       est_.time_constant <= p_.settle_window * p_.settle_windows;
  settled_count_ = (d < p_.settle_tolerance && excited) ? settled_count_ + 1 : 0;
  if (settled_count_ >= p_.settle_windows) est_.converged = true;
  t_ref_ = t;
  a_ref_ = a_;
}

}  // namespace usvfdi
