// Dedicated Luenberger observers of docs/design.md section 3.
//
// Observer V is driven by the accelerometer channel alone (K = [k_V 0], needs a2 != 0),
// observer G by the gyro alone (K = [0 k_G], needs a3 != 0). Gains by pole placement on
// the current estimate of A.
//
// The observer runs in discrete time on the exact sampled model of the vessel, with the
// rudder linear between samples (first-order hold, as a servo moves it):
//   x^_k = Phi x^_{k-1} + Ga delta_{k-1} + Gb delta_k + L (y_c,{k-1} - x^_c,{k-1}),
//   Phi = exp(A h), Ga, Gb the first-order-hold input matrices, L placing the poles of
//   Phi - L e_c^T at exp(p_i h) (the continuous poles p_i sampled).
// A noise-free, fault-free vessel is then tracked exactly (to the rudder's deviation from
// a straight line over a step), at any sample rate. The continuous observer discretised
// with the rudder and y_c held over the step (ZOH) lags a turning vessel by about half a
// step: with the true A at 10 Hz on the Otter its gyro residual carried 1.5 sigma_r RMS
// and 4 sigma_r peaks of pure model error at every course change (0.27 / 0.8 at 50 Hz).
#pragma once

#include <string>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

/// Result of a pole-placement design for the pair (A, e_c^T).
struct ObserverDesign {
  bool ok = false;
  Vec2 k = Vec2::Zero();       ///< continuous gain: x' = (A - k e_c^T) x + B delta + k y_c
  Vec2 poles = Vec2::Zero();   ///< the continuous poles p1, p2 placed
  Mat2 F = Mat2::Zero();       ///< A - k e_c^T
  double observability = 0.0;  ///< scale-free observability index (see place_poles)
  std::string reason;          ///< why the design was refused (empty when ok)
};

/// Places the poles p1, p2 (real, negative) of A - k e_c^T, c = channel (kV or kR).
/// The observability index is |a2| sigma_r/sigma_v (c = kV) or |a3| sigma_v/sigma_r (c = kR),
/// i.e. the coupling in whitened coordinates, divided by sqrt(p1 p2). The design is refused
/// when the index is below min_observability or a pole is not strictly negative.
ObserverDesign place_poles(const Mat2& A, int channel, double p1, double p2, double sigma_v,
                           double sigma_r, double min_observability);

/// A single-output observer advanced exactly over each step.
class DedicatedObserver {
 public:
  DedicatedObserver() = default;
  /// Installs a design; the state is kept (bumpless).
  void set_design(const ObserverDesign& d, const Vec2& B);
  bool ready() const { return ready_; }
  int channel() const { return channel_; }
  void set_channel(int c) { channel_ = c; }

  /// Predicted state x^(k|k-1).
  const Vec2& x() const { return x_; }
  void reset(const Vec2& x0) { x_ = x0; }

  /// Discrete matrices for the last step length (valid after the first step): the error
  /// transition Phi - L e_c^T, the measurement gain L, and the open-loop Phi, Ga, Gb.
  const Mat2& Ad() const { return Ad_; }
  /// The step length Ad, Gy, Phi, Ga and Gb are for (<= 0 before the first step).
  double dt() const { return dt_; }
  const Vec2& Gy() const { return Gy_; }
  const Mat2& Phi() const { return Phi_; }
  const Vec2& Ga() const { return Ga_; }
  const Vec2& Gb() const { return Gb_; }
  const Vec2& k() const { return k_; }

  /// Advances from t_{k-1} to t_k = t_{k-1} + dt: the rudder moves linearly from
  /// delta_prev to delta, y_c is the driving measurement at t_{k-1}. Pass use_measurement
  /// = false to run open loop for this step (invalid measurement).
  void step(double dt, double delta_prev, double delta, double y_c, bool use_measurement);

  /// A step length within band (relative) of the one discretised for is taken with the
  /// matrices corrected to first order in the difference (their derivatives in the step
  /// length, computed with each discretisation), not re-discretised: for a step that moves
  /// a little on every sample (the vessel's own time at a changing speed, core/speed.hpp).
  /// 0 (the default): every other step length is discretised exactly.
  void set_step_band(double band) { band_ = band; }

 private:
  void discretise(double dt);
  /// Phi, Ga, Gb, Gy (and Ad) for step length h into the given outputs.
  void discrete_matrices(double h, Mat2* Phi, Vec2* Ga, Vec2* Gb, Vec2* Gy, bool* ok) const;
  int channel_ = kV;
  bool ready_ = false;
  Mat2 A_ = Mat2::Zero();
  Vec2 k_ = Vec2::Zero(), B_ = Vec2::Zero(), poles_ = Vec2::Zero();
  double dt_ = -1.0;
  bool discrete_ok_ = false;
  Mat2 Phi_ = Mat2::Identity(), Ad_ = Mat2::Identity();
  Vec2 Ga_ = Vec2::Zero(), Gb_ = Vec2::Zero(), Gy_ = Vec2::Zero();
  double band_ = 0.0;
  bool have_deriv_ = false;  ///< the derivatives below belong to dt_
  Mat2 dPhi_ = Mat2::Zero();
  Vec2 dGa_ = Vec2::Zero(), dGb_ = Vec2::Zero(), dGy_ = Vec2::Zero();
  Vec2 x_ = Vec2::Zero();
};

/// Exact sampled model of x' = A x + B u with u linear over the step (first-order hold):
/// x(h) = Phi x(0) + Ga u(0) + Gb u(h).
void foh_discretise(const Mat2& A, const Vec2& B, double h, Mat2* Phi, Vec2* Ga, Vec2* Gb);

/// Exact ZOH discretisation of x' = M x + N u (2 states, up to 2 inputs): returns
/// (exp(M h), integral_0^h exp(M s) ds N).
void zoh_discretise(const Mat2& M, const Eigen::Matrix<double, 2, 2>& N, double h, Mat2* Md,
                    Eigen::Matrix<double, 2, 2>* Nd);

/// Stationary covariance of e+ = Ad e + g w, w ~ (0, 1): solves P = Ad P Ad^T + g g^T.
/// Returns false when Ad is not Schur stable.
bool discrete_lyapunov(const Mat2& Ad, const Vec2& g, Mat2* P);

}  // namespace usvfdi
