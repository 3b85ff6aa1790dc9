// Random streams, Gauss-Markov processes and the environment (waves, wind, current).
#include <cmath>
#include <stdexcept>
#include <string>

#include "voyage_internal.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Lower Cholesky factor of a symmetric positive semi-definite 2x2 matrix (0 where singular).
Mat2 chol2(const Mat2& p) {
  Mat2 l = Mat2::Zero();
  l(0, 0) = std::sqrt(std::max(p(0, 0), 0.0));
  if (l(0, 0) > 0) l(1, 0) = p(1, 0) / l(0, 0);
  l(1, 1) = std::sqrt(std::max(p(1, 1) - l(1, 0) * l(1, 0), 0.0));
  return l;
}
}  // namespace

SeaState sea_state(int code) {
  // Hs: the middle of the WMO sea state code's range; Tp: the most probable modal period
  // of the open North Atlantic for that code, as commonly tabulated (NATO STANAG 4194).
  switch (code) {
    case 0:
      return {0, 0.0, 0.0};
    case 3:
      return {3, 0.875, 7.5};
    case 4:
      return {4, 1.875, 8.8};
    case 5:
      return {5, 3.25, 9.7};
    case 6:
      return {6, 5.0, 12.4};
    default:
      break;
  }
  throw std::invalid_argument("sea state " + std::to_string(code) +
                              ": expected 0 (calm), 3, 4, 5 or 6");
}

namespace detail {

Stream::Stream(std::uint64_t seed, std::uint64_t id)
    : rng_(splitmix64(splitmix64(seed) ^ (0xA5A5A5A5ull * (id + 1)))) {}

GaussMarkov1::GaussMarkov1(double sigma, double tau, double dt) : sigma_(sigma) {
  phi_ = tau > 0 ? std::exp(-dt / tau) : 0.0;
  q_ = sigma * std::sqrt(std::max(0.0, 1.0 - phi_ * phi_));
}

double GaussMarkov1::step(Stream* s) {
  if (sigma_ > 0) x_ = phi_ * x_ + q_ * s->normal();
  return x_;
}

void GaussMarkov1::start(Stream* s) { x_ = sigma_ > 0 ? sigma_ * s->normal() : 0.0; }

WaveProcess::WaveProcess(double sigma, double w0, double lambda, double dt) {
  if (!(sigma > 0) || !(w0 > 0) || !(lambda > 0) || !(lambda < 1)) return;
  // Stationary covariance of x' = F x + [0 K]^T w: P = diag(K^2/(4 l w0^3), K^2/(4 l w0)).
  const double p22 = sigma * sigma, p11 = p22 / (w0 * w0);
  Mat2 p;
  p << p11, 0.0, 0.0, p22;
  const double a = lambda * w0, wd = w0 * std::sqrt(1.0 - lambda * lambda);
  const double e = std::exp(-a * dt), c = std::cos(wd * dt), s = std::sin(wd * dt);
  phi_ << e * (c + a / wd * s), e * s / wd, -e * w0 * w0 * s / wd, e * (c - a / wd * s);
  const Mat2 q = p - phi_ * p * phi_.transpose();
  lq_ = chol2(0.5 * (q + q.transpose()));
  lp_ = chol2(p);
}

void WaveProcess::step(Stream* s) {
  const Vec2 n(s->normal(), s->normal());
  x_ = phi_ * x_ + lq_ * n;
}

void WaveProcess::start(Stream* s) {
  const Vec2 n(s->normal(), s->normal());
  x_ = lp_ * n;
}

void wave_sigmas(const SeaState& sea, double length, double* yaw_rate, double* sway) {
  *yaw_rate = 0.0;
  *sway = 0.0;
  if (!(sea.hs > 0) || !(sea.tp > 0)) return;
  // A hull follows the wave slope and orbital motion of waves much longer than itself and
  // averages them out over waves shorter than itself: attenuation lw / (lw + L).
  const double w0 = 2.0 * kPi / sea.tp, lw = kG * sea.tp * sea.tp / (2.0 * kPi);
  const double att = lw / (lw + length);
  const double slope = kPi * sea.hs / lw;  // steepness of the significant wave [rad]
  *yaw_rate = 0.3 * slope * att * w0;      // yaw angle std 0.3 slope
  *sway = 0.1 * w0 * 0.5 * sea.hs * att;   // 10 % of the orbital velocity
}

Environment::Environment(const EnvironmentConfig& c, const Linearisation& lin, double length,
                         double dt, std::uint64_t seed)
    : c_(c), lin_(lin), s_wave_(seed, 1), s_wind_(seed, 2), s_current_(seed, 3), dt_(dt) {
  double sy = 0, sv = 0;
  wave_sigmas(c.sea, length, &sy, &sv);
  if (c.wave_yaw_sigma >= 0) sy = c.wave_yaw_sigma;
  if (c.wave_sway_sigma >= 0) sv = c.wave_sway_sigma;
  waves_ = c.sea.tp > 0 && (sy > 0 || sv > 0);
  if (waves_) {
    const double w0 = 2.0 * kPi / c.sea.tp;
    yaw_ = WaveProcess(sy, w0, c.wave_damping, dt);
    sway_ = WaveProcess(sv, w0, c.wave_damping, dt);
    yaw_.start(&s_wave_);
    sway_.start(&s_wave_);
  }
  gust_ = GaussMarkov1(c.wind_sigma, c.wind_tau, dt);
  gust_.start(&s_wind_);
  current_ = GaussMarkov1(c.current_sigma, c.current_tau, dt);
  current_.start(&s_current_);
  set_ = c.current_direction;
  update_disturbance(0.0);
}

void Environment::step(double psi) {
  if (waves_) {
    yaw_.step(&s_wave_);
    sway_.step(&s_wave_);
  }
  gust_.step(&s_wind_);
  current_.step(&s_current_);
  if (c_.current_direction_rw > 0)
    set_ += c_.current_direction_rw * std::sqrt(dt_) * s_current_.normal();
  update_disturbance(psi);
}

void Environment::update_disturbance(double psi) {
  // Wind: a yaw moment and sway force as the rudder would make them (the rudder column of B).
  const double wind = c_.wind + gust_.value();
  const Vec2 d = lin_.B * wind;
  d_.du = 0.0;
  d_.dv = d(0);
  d_.dr = d(1);
  // Current over ground, seen in the body frame (y axis to starboard).
  vc_ = (c_.current + current_.value()) * std::sin(set_ - psi);
}

}  // namespace detail
}  // namespace usvfdi::sim
