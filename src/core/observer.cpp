#include "usv_fdi/core/observer.hpp"

#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

namespace usvfdi {

ObserverDesign place_poles(const Mat2& A, int channel, double p1, double p2, double sigma_v,
                           double sigma_r, double min_observability) {
  ObserverDesign d;
  if (!(p1 < 0 && p2 < 0) || !std::isfinite(p1) || !std::isfinite(p2)) {
    d.reason = "observer poles must be strictly negative";
    return d;
  }
  if (!A.allFinite()) {
    d.reason = "estimate of A is not finite";
    return d;
  }
  const double scale = std::sqrt(p1 * p2);
  // Coupling through which the other state is seen, in whitened coordinates.
  const double coupling = channel == kV ? A(0, 1) * sigma_r / sigma_v : A(1, 0) * sigma_v / sigma_r;
  d.observability = std::abs(coupling) / scale;
  if (!(d.observability >= min_observability)) {
    d.reason = std::string(channel == kV ? "observer V: (A, [1 0]) near-unobservable, a2"
                                         : "observer G: (A, [0 1]) near-unobservable, a3") +
               " = " + std::to_string(channel == kV ? A(0, 1) : A(1, 0)) + ", index " +
               std::to_string(d.observability);
    return d;
  }
  // Ackermann: k = phi(A) O^{-1} e2, O = [c^T; c^T A], phi(s) = (s - p1)(s - p2).
  Eigen::RowVector2d c = Eigen::RowVector2d::Zero();
  c(channel) = 1.0;
  Mat2 O;
  O.row(0) = c;
  O.row(1) = c * A;
  const Mat2 phi = A * A - (p1 + p2) * A + p1 * p2 * Mat2::Identity();
  const Vec2 w = O.partialPivLu().solve(Vec2(0.0, 1.0));
  d.k = phi * w;
  d.F = A - d.k * c;
  if (!d.k.allFinite()) {
    d.reason = "pole placement produced a non-finite gain";
    return d;
  }
  d.ok = true;
  return d;
}

void zoh_discretise(const Mat2& M, const Eigen::Matrix<double, 2, 2>& N, double h, Mat2* Md,
                    Eigen::Matrix<double, 2, 2>* Nd) {
  Eigen::Matrix4d aug = Eigen::Matrix4d::Zero();
  aug.topLeftCorner<2, 2>() = M * h;
  aug.topRightCorner<2, 2>() = N * h;
  const Eigen::Matrix4d e = aug.exp();
  *Md = e.topLeftCorner<2, 2>();
  *Nd = e.topRightCorner<2, 2>();
}

bool discrete_lyapunov(const Mat2& Ad, const Vec2& g, Mat2* P) {
  // Schur stability of a 2x2 matrix: |det| < 1 and |tr| < 1 + det.
  const double tr = Ad.trace(), det = Ad.determinant();
  if (!(std::abs(det) < 1.0 && std::abs(tr) < 1.0 + det)) return false;
  // Doubling: P = sum_j Ad^j g g^T Ad^jT.
  Mat2 S = g * g.transpose();
  Mat2 Ak = Ad;
  for (int i = 0; i < 64; ++i) {
    S = S + Ak * S * Ak.transpose();
    Ak = Ak * Ak;
    if (Ak.cwiseAbs().maxCoeff() < 1e-18) break;
  }
  *P = S;
  return P->allFinite();
}

void DedicatedObserver::set_design(const ObserverDesign& d, const Vec2& B) {
  if (!d.ok) {
    ready_ = false;
    return;
  }
  F_ = d.F;
  k_ = d.k;
  A_ = d.F + d.k * Eigen::RowVector2d::Unit(channel_);
  B_ = B;
  dt_ = -1.0;  // force re-discretisation
  ready_ = true;
}

void DedicatedObserver::discretise(double dt) {
  Eigen::Matrix<double, 2, 2> N, Nd;
  N.col(0) = B_;
  N.col(1) = k_;
  zoh_discretise(F_, N, dt, &Ad_, &Nd);
  Gd_ = Nd.col(0);
  Gy_ = Nd.col(1);
  N.col(1).setZero();
  zoh_discretise(A_, N, dt, &Ad_open_, &Nd);
  Gd_open_ = Nd.col(0);
  dt_ = dt;
}

void DedicatedObserver::step(double dt, double delta, double y_c, bool use_measurement) {
  if (!ready_ || !(dt > 0)) return;
  if (std::abs(dt - dt_) > 1e-9 * dt) discretise(dt);
  if (use_measurement) {
    x_ = Ad_ * x_ + Gd_ * delta + Gy_ * y_c;
  } else {
    x_ = Ad_open_ * x_ + Gd_open_ * delta;
  }
}

}  // namespace usvfdi
