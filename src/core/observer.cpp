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
  d.poles = Vec2(p1, p2);
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

void foh_discretise(const Mat2& A, const Vec2& B, double h, Mat2* Phi, Vec2* Ga, Vec2* Gb) {
  // z = [x; u; w], u' = w, w' = 0: exp(M h) gives Phi, Psi1 = int_0^h e^{A (h - s)} B ds and
  // Psi2 = int_0^h e^{A (h - s)} B s ds; with w = (u(h) - u(0)) / h,
  // x(h) = Phi x0 + (Psi1 - Psi2 / h) u(0) + (Psi2 / h) u(h).
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  M.topLeftCorner<2, 2>() = A * h;
  M.block<2, 1>(0, 2) = B * h;
  M(2, 3) = h;
  const Eigen::Matrix4d E = M.exp();
  *Phi = E.topLeftCorner<2, 2>();
  const Vec2 psi1 = E.block<2, 1>(0, 2);
  const Vec2 psi2_h = E.block<2, 1>(0, 3) / h;
  *Ga = psi1 - psi2_h;
  *Gb = psi2_h;
}

void DedicatedObserver::set_design(const ObserverDesign& d, const Vec2& B) {
  if (!d.ok) {
    ready_ = false;
    return;
  }
  k_ = d.k;
  A_ = d.F + d.k * Eigen::RowVector2d::Unit(channel_);
  poles_ = d.poles;
  B_ = B;
  dt_ = -1.0;  // force re-discretisation
  have_deriv_ = false;
  ready_ = true;
}

void DedicatedObserver::discrete_matrices(double h, Mat2* Phi, Vec2* Ga, Vec2* Gb, Vec2* Gy,
                                          bool* ok) const {
  foh_discretise(A_, B_, h, Phi, Ga, Gb);
  // Ackermann on (Phi, e_c^T): L = phi(Phi) O^-1 e2, phi(z) = (z - z1)(z - z2).
  const double z1 = std::exp(poles_(0) * h), z2 = std::exp(poles_(1) * h);
  Eigen::RowVector2d c = Eigen::RowVector2d::Unit(channel_);
  Mat2 O;
  O.row(0) = c;
  O.row(1) = c * *Phi;
  const Mat2 phi = *Phi * *Phi - (z1 + z2) * *Phi + z1 * z2 * Mat2::Identity();
  *Gy = phi * O.partialPivLu().solve(Vec2(0.0, 1.0));
  *ok = Gy->allFinite() && std::abs(O.determinant()) > 1e-12 * O.norm() * O.norm();
  if (!*ok) Gy->setZero();
}

void DedicatedObserver::discretise(double dt) {
  discrete_matrices(dt, &Phi_, &Ga_, &Gb_, &Gy_, &discrete_ok_);
  Ad_ = Phi_ - Gy_ * Eigen::RowVector2d::Unit(channel_);
  dt_ = dt;
  have_deriv_ = false;
  if (band_ > 0 && discrete_ok_) {
    // Central differences (relative step 1e-3: truncation ~1e-6, round-off ~1e-13).
    const double e = 1e-3 * dt;
    Mat2 P1, P2;
    Vec2 a1, a2, b1, b2, g1, g2;
    bool ok1 = false, ok2 = false;
    discrete_matrices(dt + e, &P1, &a1, &b1, &g1, &ok1);
    discrete_matrices(dt - e, &P2, &a2, &b2, &g2, &ok2);
    if (ok1 && ok2) {
      dPhi_ = (P1 - P2) / (2 * e);
      dGa_ = (a1 - a2) / (2 * e);
      dGb_ = (b1 - b2) / (2 * e);
      dGy_ = (g1 - g2) / (2 * e);
      have_deriv_ = true;
    }
  }
}

void DedicatedObserver::step(double dt, double delta_prev, double delta, double y_c,
                             bool use_measurement) {
  if (!ready_ || !(dt > 0)) return;
  if (std::abs(dt - dt_) > 1e-9 * dt) {
    const double e = dt - dt_;
    if (have_deriv_ && std::abs(e) <= band_ * dt_) {
      const Vec2 open =
          (Phi_ + e * dPhi_) * x_ + (Ga_ + e * dGa_) * delta_prev + (Gb_ + e * dGb_) * delta;
      x_ = use_measurement ? Vec2(open + (Gy_ + e * dGy_) * (y_c - x_(channel_))) : open;
      return;
    }
    discretise(dt);
  }
  const Vec2 open = Phi_ * x_ + Ga_ * delta_prev + Gb_ * delta;
  // A step length at which the sampled pair is unobservable runs open loop.
  x_ = use_measurement && discrete_ok_ ? Vec2(open + Gy_ * (y_c - x_(channel_))) : open;
}

}  // namespace usvfdi
