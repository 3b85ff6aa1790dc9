// Esso 190 000 dwt tanker (L = 304.8 m, draft 18.46 m, design speed 8.23 m/s at 80 rpm):
// nonlinear manoeuvring model with propeller, in deep water.
//
// Source of the coefficients: W. B. van Berlekom and T. A. Goddard (1972), "Maneuvering of
// large tankers", Trans. SNAME 80:264-298 (Appendix A); the table as given in Fossen's
// handbook (2011) and the MSS toolbox (tanker.m). Deep water: the shallow-water terms
// (z = T/(h - T)) vanish. This is the 190 000 dwt tanker of that paper, not the 278 000 dwt
// Esso Osaka of the later ITTC trials.
// Throttle: shaft speed n = throttle * n0, n0 the one that holds 8.23 m/s straight ahead.
// Rudder sign (as published): delta > 0 turns the ship to port (r < 0).
#include <memory>
#include <stdexcept>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;

constexpr double L = 304.8, t = 0.22, cun = 0.605, cnn = 38.2;
constexpr double Tuu = -0.00695, Tun = -0.00063, Tnn = 0.0000354;
constexpr double m11 = 1.050, m22 = 2.020, m33 = 0.1232;   // 1 - Xudot, 1 - Yvdot, kz^2 - Nrdot
constexpr double d11 = 2.020, d22 = -0.752, d33 = -0.231;  // 1 + Xvr, Yur - 1, Nur - xG
constexpr double YT = 0.04, NT = -0.02;
constexpr double Xuu = -0.0377, Xvv = 0.3, Xccdd = -0.093, Xccbd = 0.152;
constexpr double Yvv = -2.400, Yuv = -1.205, Yccd = 0.208, Yccbbd = -2.16;
constexpr double Nvr = -0.300, Nuv = -0.451, Nccd = -0.098, Nccbbd = 0.688;
constexpr double kU0 = 8.23;

/// Accelerations [m/s^2, m/s^2, rad/s^2] at shaft speed n [rps].
HullRates tanker_rates(double u, double v, double r, double delta, double n) {
  const double beta = std::atan(v / u);
  const double gT = Tuu * u * u / L + Tun * u * n + L * Tnn * std::abs(n) * n;
  const double c = std::sqrt(std::max(cun * u * n + cnn * n * n, 0.0));
  const double cc = c * c;  // |c| c, c >= 0
  const double bb = std::abs(beta) * beta * std::abs(delta);
  const double gX = (Xuu * u * u + L * d11 * v * r + Xvv * v * v + Xccdd * cc * delta * delta +
                     Xccbd * cc * beta * delta + L * gT * (1 - t)) /
                    L;
  const double gY = (Yuv * u * v + Yvv * std::abs(v) * v + Yccd * cc * delta + L * d22 * u * r +
                     Yccbbd * cc * bb + YT * gT * L) /
                    L;
  const double gN = Nuv * u * v + L * Nvr * std::abs(v) * r + Nccd * cc * delta + L * d33 * u * r +
                    Nccbbd * cc * bb + L * NT * gT;
  return {gX / m11, gY / m22, gN / (L * L * m33)};
}

class EssoTanker final : public detail::HullWithFacts {
 public:
  EssoTanker(detail::HullFacts f, double n0_rps) : HullWithFacts(std::move(f)), n0_(n0_rps) {}
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override {
    const double u = std::max(x.u, 1e-3);
    return detail::add(tanker_rates(u, x.v, x.r, in.delta, in.throttle * n0_), d);
  }

 private:
  double n0_;  ///< shaft speed at throttle 1 [rps]
};

/// Shaft speed [rps] whose thrust balances the resistance at U (bisection on du(n) = 0).
double shaft_speed_for(double U) {
  return detail::balancing_shaft_speed("tanker", 0.01, 5.0,
                                       [U](double n) { return tanker_rates(U, 0, 0, 0, n).du; });
}
}  // namespace

std::shared_ptr<const Hull> make_esso_tanker() {
  detail::HullFacts f;
  f.name = "esso-tanker";
  f.source =
      "van Berlekom & Goddard 1972, Maneuvering of large tankers, Trans. SNAME 80:264-298, "
      "Appendix A (Esso 190 000 dwt tanker, deep water); table as in Fossen's handbook 2011";
  f.nonlinear = true;
  f.nominal_speed = kU0;
  f.limits = {35.0 * kDeg, 2.33 * kDeg, 1.0, L};
  return std::make_shared<EssoTanker>(f, shaft_speed_for(kU0));
}

}  // namespace usvfdi::sim
