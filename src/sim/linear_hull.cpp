// Linear sway-yaw hulls with a first-order surge: x' = (u/U0) A0 x + (u/U0)^2 B0 delta.
// A linear-derivative model written in the prime system has exactly this dependence on
// speed (A ~ U/L, B ~ U^2/L); the surge answers the throttle with a time constant T_u.
#include <memory>
#include <stdexcept>

#include "hull_base.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {
using detail::kDeg;
using detail::kRho;

class LinearHull final : public detail::HullWithFacts {
 public:
  LinearHull(detail::HullFacts f, const LinearHullData& data)
      : HullWithFacts(std::move(f)), d_(data) {}
  HullRates rates(const HullState& x, const HullInput& in, const Disturbance& d) const override {
    const double s = x.u / d_.U0;
    const Vec2 xd = s * (d_.A0 * Vec2(x.v, x.r)) + s * s * d_.B0 * in.delta;
    const double du = (in.throttle * d_.U0 - x.u) / d_.T_u;
    return detail::add({du, xd(0), xd(1)}, d);
  }

 private:
  LinearHullData d_;
};

/// x' = A x + B delta from M' nu' + N' nu' = b' delta in the prime system (nu' = [v/U, rL/U],
/// time t U/L): A = -(U/L) S M'^-1 N' S^-1, B = (U^2/L) S M'^-1 b', S = diag(1, 1/L).
void from_prime(const Mat2& Mp, const Mat2& Np, const Vec2& bp, double L, double U, Mat2* A,
                Vec2* B) {
  const Mat2 S = Vec2(1.0, 1.0 / L).asDiagonal();
  const Mat2 Sinv = Vec2(1.0, L).asDiagonal();
  *A = -(U / L) * S * Mp.partialPivLu().solve(Np) * Sinv;
  *B = (U * U / L) * S * Mp.partialPivLu().solve(bp);
}
}  // namespace

std::shared_ptr<const Hull> make_linear_hull(const LinearHullData& data) {
  if (!(data.U0 > 0.0) || !(data.T_u > 0.0)) {
    throw std::invalid_argument("linear hull '" + data.name + "': U0 and T_u must be > 0");
  }
  detail::HullFacts f{data.name, data.source, false, data.U0, data.limits};
  return std::make_shared<LinearHull>(f, data);
}

LinearHullData lcontainer_data() {
  // Son & Nomoto (1982) linear model of the container ship in the prime system, as the
  // matrices of Fossen's MSS Lcontainer.m (order v, r; roll row and column dropped).
  Mat2 Mp, Np;
  Mp << 0.01497, 0.0003525, 0.0003525, 0.000875;
  Np << 0.012035, 0.00522, 0.0038436, 0.00243;
  const Vec2 bp(-0.002578, 0.00126);
  LinearHullData d;
  d.name = "lcontainer";
  d.source =
      "Son & Nomoto 1982 (Naval Arch. Ocean Eng. 20:73-83), linear sway-yaw(-roll) model of the "
      "175 m container ship, prime-system matrices as in Fossen's MSS Lcontainer.m; roll "
      "frozen";
  d.U0 = 7.0;
  from_prime(Mp, Np, bp, 175.0, d.U0, &d.A0, &d.B0);
  d.T_u = 175.0;  // surge time constant ~ L [s] (Fossen 2021, shipClarke83 approximation)
  d.limits = {35.0 * kDeg, 5.0 * kDeg, 1.0, 175.0};
  return d;
}

LinearHullData clarke83_data(const std::string& name, double L, double B, double T, double Cb,
                             double U0) {
  // Clarke, Gedling & Hine (1983), Trans. RINA 125:45-68: regression of the linear
  // derivatives (prime system, scale pi (T/L)^2).
  const double S = M_PI * (T / L) * (T / L);
  const double Yvdot = -S * (1 + 0.16 * Cb * B / T - 5.1 * (B / L) * (B / L));
  const double Yrdot = -S * (0.67 * B / L - 0.0033 * (B / T) * (B / T));
  const double Nvdot = -S * (1.1 * B / L - 0.041 * (B / T));
  const double Nrdot = -S * (1.0 / 12 + 0.017 * Cb * (B / T) - 0.33 * (B / L));
  const double Yv = -S * (1 + 0.4 * Cb * (B / T));
  const double Yr = -S * (-0.5 + 2.2 * (B / L) - 0.08 * (B / T));
  const double Nv = -S * (0.5 + 2.4 * (T / L));
  const double Nr = -S * (0.25 + 0.039 * (B / T) - 0.56 * (B / L));
  // Rigid body in the prime system (m' = m / (rho/2 L^3)), CG at the origin, R66 = 0.25 L.
  const double mp = Cb * L * B * T / (0.5 * L * L * L);
  const double Izp = mp * 0.25 * 0.25;
  Mat2 Mp, Np;
  Mp << mp - Yvdot, -Yrdot, -Nvdot, Izp - Nrdot;
  Np << -Yv, mp - Yr, -Nv, -Nr;  // the Coriolis term m' u' r' joins Yr
  // Rudder (Fossen 2021, section 9.5.1): height 0.7 T, aspect ratio 0.7, normal force
  // coefficient C_N = 6.13 Lambda/(Lambda + 2.25) (Fujii), hull interaction a_H = 0.4 at
  // x_H = -L, rudder at x_R = -0.45 L; forces 0.25 rho U^2 A_R C_N sin(2 delta) linearised.
  const double Lambda = 0.7, hR = 0.7 * T, AR = hR * hR / Lambda;
  const double CN = 6.13 * Lambda / (Lambda + 2.25);
  const double aH = 0.4, xR = -0.45 * L, xH = -1.0 * L;
  const double Yd = 0.5 * (1 + aH) * kRho * AR * CN;        // per U^2, per rad (x 2 delta)
  const double Nd = 0.5 * (xR + aH * xH) * kRho * AR * CN;  // [N m / (m/s)^2 / rad]
  const double q = 0.5 * kRho * L * L;
  const Vec2 bp(Yd / q, Nd / (q * L));
  LinearHullData d;
  d.name = name;
  d.source =
      "Clarke, Gedling & Hine 1983, The application of manoeuvring criteria in hull design "
      "using linear theory, Trans. RINA 125:45-68 (regression); rudder as Fossen 2021, 9.5.1";
  d.U0 = U0;
  from_prime(Mp, Np, bp, L, U0, &d.A0, &d.B0);
  d.T_u = L;
  d.limits = {35.0 * kDeg, 5.0 * kDeg, 1.0, L};
  return d;
}

}  // namespace usvfdi::sim
