// Building blocks of the voyage simulator (private to src/sim): random streams, first- and
// second-order Gauss-Markov processes, the environment, a sensor channel and the faults.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/types.hpp"
#include "usv_fdi/sim/hull.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::sim::detail {

/// Independent random stream `id` of a voyage seed (splitmix64 of seed and id).
class Stream {
 public:
  Stream(std::uint64_t seed, std::uint64_t id);
  double normal() { return n01_(rng_); }
  double uniform() { return u01_(rng_); }

 private:
  std::mt19937_64 rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  std::uniform_real_distribution<double> u01_{0.0, 1.0};
};

/// First-order Gauss-Markov process x' = -x / tau + w, stationary std sigma; exact
/// discretisation over steps of dt (x_k+1 = phi x_k + sigma sqrt(1 - phi^2) n).
class GaussMarkov1 {
 public:
  GaussMarkov1() = default;
  GaussMarkov1(double sigma, double tau, double dt);
  double step(Stream* s);
  double value() const { return x_; }
  void start(Stream* s);  ///< draws x from the stationary distribution

 private:
  double phi_ = 0.0, q_ = 0.0, sigma_ = 0.0, x_ = 0.0;
};

/// Second-order wave shaping filter (Fossen's linear approximation of a wave spectrum):
/// x1' = x2, x2' = -w0^2 x1 - 2 lambda w0 x2 + K w, so that x2 = K s / (s^2 + 2 lambda w0 s
/// + w0^2) w has its spectral peak at w0. Scaled so that std(x2) = sigma; exact
/// discretisation (transition matrix and Q = P - Phi P Phi^T of the stationary P).
class WaveProcess {
 public:
  WaveProcess() = default;
  WaveProcess(double sigma, double w0, double lambda, double dt);
  void step(Stream* s);
  void start(Stream* s);
  double position() const { return x_(0); }  ///< x1 (e.g. wave yaw angle)
  double rate() const { return x_(1); }      ///< x2 = x1' (e.g. wave yaw rate)

 private:
  Mat2 phi_ = Mat2::Zero();
  Mat2 lq_ = Mat2::Zero();  ///< Cholesky factor of the process noise per step
  Mat2 lp_ = Mat2::Zero();  ///< Cholesky factor of the stationary covariance
  Vec2 x_ = Vec2::Zero();
};

/// Wave-induced motion std of a sea state for a hull of length L [m]: yaw rate [rad/s] and
/// sway velocity [m/s] (see environment.cpp for the rule).
void wave_sigmas(const SeaState& sea, double length, double* yaw_rate, double* sway);

/// Waves, wind and current of a voyage, advanced once per sample. The wind acts on the hull
/// (a sway force and yaw moment as the rudder would make them); a current does not push
/// the hull (its hydrodynamics act on the velocity through the water) but moves it over
/// ground: the INS reads its cross component in the sway velocity.
class Environment {
 public:
  Environment(const EnvironmentConfig& c, const Linearisation& lin, double length, double dt,
              std::uint64_t seed);
  /// Advances over one sample at the (true, low-frequency) heading psi.
  void step(double psi);
  double v_wave() const { return sway_.rate(); }
  double r_wave() const { return yaw_.rate(); }
  double psi_wave() const { return yaw_.position(); }
  Disturbance disturbance() const { return d_; }
  /// The current's component along the body y axis [m/s] at the heading of the last step.
  double v_current() const { return vc_; }

 private:
  void update_disturbance(double psi);
  EnvironmentConfig c_;
  Linearisation lin_;
  bool waves_ = false;
  Stream s_wave_, s_wind_, s_current_;
  WaveProcess yaw_, sway_;
  GaussMarkov1 gust_, current_;
  double set_ = 0.0, dt_ = 0.0, vc_ = 0.0;
  Disturbance d_;
};

/// One sensor channel without faults: lag, offset, bias instability, white and GM noise.
class Channel {
 public:
  Channel(const ChannelNoise& c, double dt, std::uint64_t seed, std::uint64_t id);
  /// The channel's reading of `truth` at this sample (before faults and quantisation).
  double measure(double truth);
  double bias() const { return c_.bias + walk_; }

 private:
  ChannelNoise c_;
  double dt_;
  Stream s_;
  GaussMarkov1 gm_;
  double walk_ = 0.0, lagged_ = 0.0;
  bool first_ = true;
};

/// Scripted INS faults (core FaultInjection semantics) on the two channels.
class Faults {
 public:
  Faults(const std::vector<FaultInjection>& faults, double dt, std::uint64_t seed);
  /// Applies the faults active at t to `y` (the channel's reading; `truth` for scale) and
  /// returns the kind of the last active one (kUnknown: none).
  double apply(Sensor sensor, double t, double truth, double y, FaultKind* active);

 private:
  double apply_one(std::size_t i, double t, double truth, double y);
  std::vector<FaultInjection> f_;
  std::vector<double> held_;
  double dt_;
  Stream s_;
};

}  // namespace usvfdi::sim::detail
