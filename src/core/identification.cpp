#include "usv_fdi/core/identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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
}

Identifier::Identifier(const IdentificationParams& params, const Vec2& B)
    : p_(params), B_(B), f1_(params.eps1), f2_(params.eps2), a_(params.a0), a_ref_(params.a0) {
  p_.validate();
  if (!B.allFinite()) throw std::invalid_argument("model.B must be finite");
  const double eps_min = p_.method == IdentMethod::kPaper ? std::min(p_.eps1, p_.eps2) : p_.eps1;
  warmup_ = p_.warmup_time >= 0 ? p_.warmup_time : 10.0 / eps_min;
  est_.A = from_params(a_);
  est_.time_constant = std::numeric_limits<double>::infinity();
}

void Identifier::restart_filters(const Sample& s) {
  // Zero initial conditions, as in the paper; the warm-up hides the e^{-eps t} transient.
  q_.setZero();
  m_.setZero();
  qb_.setZero();
  mb_.setZero();
  fd1_ = fd2_ = 0.0;
  prev_ = s;
  have_prev_ = true;
  have_prev2_ = false;
  restart_pending_ = false;
  t_start_ = s.t;
  est_.warming_up = true;
}

bool Identifier::update(const Sample& s, bool freeze) {
  if (!finite(s)) return false;
  if (have_prev_ && !(s.t > prev_.t)) return false;
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
  // Curvature of each input over the step (zero until three samples are known).
  Vec2 ydd = Vec2::Zero();
  double ddd = 0.0;
  if (p_.curvature_correction && have_prev2_) {
    const double hp = prev_.t - prev2_.t;
    ydd(0) = FohLowPass::curvature(prev2_.v, prev_.v, s.v, hp, dt);
    ydd(1) = FohLowPass::curvature(prev2_.r, prev_.r, s.r, hp, dt);
    ddd = FohLowPass::curvature(prev2_.delta, prev_.delta, s.delta, hp, dt);
  }
  f1_.set_step(dt);
  for (int i = 0; i < 2; ++i) q_(i) = f1_.step_curved(y_prev(i), y(i), ydd(i), q_(i));
  fd1_ = f1_.step_curved(prev_.delta, s.delta, ddd, fd1_);
  m_ = p_.eps1 * (y - q_) - B_ * fd1_;
  if (p_.method == IdentMethod::kPaper) {
    f2_.set_step(dt);
    for (int i = 0; i < 2; ++i) qb_(i) = f2_.step_curved(y_prev(i), y(i), ydd(i), qb_(i));
    fd2_ = f2_.step_curved(prev_.delta, s.delta, ddd, fd2_);
    mb_ = p_.eps2 * (y - qb_) - B_ * fd2_;
  }
  prev2_ = prev_;
  have_prev2_ = true;
  prev_ = s;
  est_.warming_up = s.t - t_start_ < warmup_;
  if (est_.warming_up) return true;

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
    const double scale = R.col(0).norm() * R.col(1).norm();
    est_.excitation = scale > 0 ? std::abs(psi_) / scale : 0.0;
  } else {
    const double E = std::exp(-p_.lambda * dt);
    Phi_ = E * Phi_ + dt * (q_ * q_.transpose());
    Y_ = E * Y_ + dt * (q_ * m_.transpose());
    psi_ = Phi_.determinant();
    Mat2 adj;
    adj << Phi_(1, 1), -Phi_(0, 1), -Phi_(1, 0), Phi_(0, 0);
    const Mat2 Z = adj * Y_;  // = psi A^T
    h_ << Z(0, 0), Z(1, 0), Z(0, 1), Z(1, 1);
    const double scale = Phi_(0, 0) * Phi_(1, 1);
    est_.excitation = scale > 0 ? std::clamp(psi_ / scale, 0.0, 1.0) : 0.0;
  }
  advance_scalar_laws(dt);
  update_convergence(s.t);
  return true;
}

void Identifier::advance_scalar_laws(double dt) {
  const double psi2 = psi_ * psi_;
  const double rate = p_.normalised ? p_.gamma * psi2 / (p_.mu + psi2) : p_.gamma * psi2;
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
  const bool excited = est_.excitation >= p_.min_excitation &&
                       est_.time_constant <= p_.settle_window * p_.settle_windows;
  settled_count_ = (d < p_.settle_tolerance && excited) ? settled_count_ + 1 : 0;
  if (settled_count_ >= p_.settle_windows) est_.converged = true;
  t_ref_ = t;
  a_ref_ = a_;
}

}  // namespace usvfdi
