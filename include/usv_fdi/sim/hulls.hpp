// The vessel zoo: hull models from published sources (see docs/vessels.md for the table of
// sources, speeds and sign conventions), their linearisation and the registry.
// Depends on Eigen and the core types alone.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "usv_fdi/sim/hull.hpp"

namespace usvfdi::sim {

// --- Nonlinear 3-DOF manoeuvring models -------------------------------------------------

/// Mariner class vessel, 160.93 m (Chislett & Strom-Tejsen 1965), about approach speed U0.
std::shared_ptr<const Hull> make_mariner();
/// High-speed container ship, 175 m, propeller and rudder (Son & Nomoto 1981/1982); roll
/// frozen (phi = p = 0) to make a 3-DOF model.
std::shared_ptr<const Hull> make_container();
/// Esso 190 000 dwt tanker, 304.8 m, deep water (van Berlekom & Goddard 1972).
std::shared_ptr<const Hull> make_esso_tanker();
/// KVLCC2 MMG standard model (Yasukawa & Yoshimura 2015) at the scale of length lpp [m]
/// (7 m: the free-running model; 320 m: the ship) and approach speed u0 [m/s]; named
/// "kvlcc2" below 50 m and "kvlcc2-full" above.
std::shared_ptr<const Hull> make_kvlcc2(double lpp, double u0);
/// Otter 2 m USV in surge, sway and yaw (Fossen 2021; PythonVehicleSimulator otter.py
/// parameters), the differential-thrust yaw moment as an equivalent rudder angle.
std::shared_ptr<const Hull> make_otter3dof();

// --- Linear sway-yaw models with a first-order surge ------------------------------------

/// A linear hull: x' = (u/U0) A0 x + (u/U0)^2 B0 delta, x = [v r]; u' = (throttle U0 - u)/T_u.
struct LinearHullData {
  std::string name;
  std::string source;
  double U0 = 0.0;         ///< speed of A0, B0 [m/s]
  Mat2 A0 = Mat2::Zero();  ///< [1/s, m/s per rad/s; rad/s^2 per m/s, 1/s]
  Vec2 B0 = Vec2::Zero();  ///< [m/s^2/rad, 1/s^2]
  double T_u = 0.0;        ///< surge time constant [s]
  HullLimits limits;
};
std::shared_ptr<const Hull> make_linear_hull(const LinearHullData& data);
/// The linear Son & Nomoto container ship (Fossen, MSS Lcontainer.m matrices), roll frozen.
LinearHullData lcontainer_data();
/// Clarke, Gedling & Hine (1983) regression of the linear derivatives for main dimensions
/// L, B, T, Cb at speed U0, with a rudder of height 0.7 T and aspect ratio 0.7 whose normal
/// force follows Fujii's C_N = 6.13 Lambda / (Lambda + 2.25) (Fossen 2021, section 9.5).
LinearHullData clarke83_data(const std::string& name, double L, double B, double T, double Cb,
                             double U0);

// --- Linearisation ----------------------------------------------------------------------

/// Throttle that holds straight running at surge speed u0 (1-D root of du = 0).
/// Throws std::runtime_error when the hull cannot reach u0 in [0.05, 4].
double equilibrium_throttle(const Hull& hull, double u0);
/// A, B about straight running at u0 (v = r = delta = 0, throttle from
/// equilibrium_throttle) by central differences of Hull::rates with relative step h.
Linearisation linearise(const Hull& hull, double u0, double h = 1e-5);

// --- Registry ---------------------------------------------------------------------------

struct ZooEntry {
  std::string name;
  std::shared_ptr<const Hull> hull;
  std::vector<double> speeds;  ///< speeds it is meant to run at [m/s]; speeds[0] nominal
};
/// Every hull of the zoo, in a fixed order.
const std::vector<ZooEntry>& zoo();
/// The entry called name, or nullptr.
const ZooEntry* find_hull(const std::string& name);

}  // namespace usvfdi::sim
