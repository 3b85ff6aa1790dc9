// The vessel zoo against its sources: registry coverage, linearisation (finite differences at
// other steps, analytic A and B of the linear hulls, the published linear models), standard
// manoeuvres (IMO MSC.137(76) criteria, the recorded HSVA KVLCC2 zigzags), speed loss in
// turns, determinism.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/manoeuvre.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kDeg = M_PI / 180.0;

const Hull& hull(const std::string& name) {
  const ZooEntry* e = find_hull(name);
  if (e == nullptr) throw std::runtime_error("no hull " + name);
  return *e->hull;
}

bool stable(const Mat2& A) {
  const Eigen::Vector2cd ev = Eigen::EigenSolver<Mat2>(A).eigenvalues();
  return ev(0).real() < 0 && ev(1).real() < 0;
}

/// |x - y| <= tol * max(|x|, |y|), per element.
void expect_rel(const Mat2& x, const Mat2& y, double tol, const std::string& what) {
  for (int i = 0; i < 4; ++i) {
    const double a = x(i), b = y(i);
    EXPECT_LE(std::abs(a - b), tol * std::max(std::abs(a), std::abs(b)))
        << what << " [" << i << "]: " << a << " vs " << b;
  }
}
void expect_rel(const Vec2& x, const Vec2& y, double tol, const std::string& what) {
  for (int i = 0; i < 2; ++i) {
    EXPECT_LE(std::abs(x(i) - y(i)), tol * std::max(std::abs(x(i)), std::abs(y(i))))
        << what << " [" << i << "]: " << x(i) << " vs " << y(i);
  }
}

// --- Registry and coverage ------------------------------------------------------------

TEST(Zoo, HasAtLeastEightHullsThreeNonlinearEachAtTwoSpeeds) {
  int nonlinear = 0;
  std::map<std::string, int> names;
  for (const ZooEntry& e : zoo()) {
    ++names[e.name];
    EXPECT_EQ(e.name, e.hull->name());
    EXPECT_GE(e.speeds.size(), 2u) << e.name;
    EXPECT_DOUBLE_EQ(e.speeds.front(), e.hull->nominal_speed()) << e.name;
    EXPECT_FALSE(e.hull->source().empty()) << e.name;
    EXPECT_GT(e.hull->limits().length, 0.0) << e.name;
    EXPECT_GT(e.hull->limits().max_rudder, 0.0) << e.name;
    EXPECT_GT(e.hull->limits().max_rudder_rate, 0.0) << e.name;
    nonlinear += e.hull->nonlinear() ? 1 : 0;
  }
  EXPECT_GE(zoo().size(), 8u);
  EXPECT_GE(nonlinear, 3);
  for (const auto& [name, n] : names) EXPECT_EQ(n, 1) << name;
  EXPECT_EQ(find_hull("no-such-hull"), nullptr);
  ASSERT_NE(find_hull("kvlcc2"), nullptr);
  EXPECT_EQ(find_hull("kvlcc2")->hull->name(), "kvlcc2");
}

TEST(Zoo, CoversSlowShipsCourseUnstableShipsAndUnstableUsvs) {
  int slow_ships = 0, unstable_ships = 0;
  for (const ZooEntry& e : zoo()) {
    if (e.hull->limits().length < 100.0) continue;
    bool slow = false;
    for (double U : e.speeds) {
      const double det = linearise(*e.hull, U).A.determinant();
      slow = slow || (det >= 1e-4 && det <= 1e-3);
    }
    slow_ships += slow ? 1 : 0;
    unstable_ships += stable(linearise(*e.hull, e.speeds.front()).A) ? 0 : 1;
  }
  EXPECT_GE(slow_ships, 3);
  EXPECT_GE(unstable_ships, 1);
  // The Otter: stable at 1 m/s, open-loop unstable at its 2 m/s cruise and at 3 m/s.
  EXPECT_TRUE(stable(linearise(hull("otter3dof"), 1.0).A));
  EXPECT_FALSE(stable(linearise(hull("otter3dof"), 2.0).A));
  EXPECT_FALSE(stable(linearise(hull("otter3dof"), 3.0).A));
}

TEST(Zoo, TheEssoTankerIsCourseUnstableLoadedInDeepWaterAsItsTrialsFound) {
  // Full-scale trials of the 193 000 dwt Esso Bernicia (Clarke, Patterson & Wooderson 1973,
  // Trans. RINA, pp. 89-109): course-unstable in all conditions except deep-water ballast.
  // The van Berlekom & Goddard model of that tanker size, loaded, in deep water:
  for (double U : {8.23, 5.0}) {
    const Linearisation l = linearise(hull("esso-tanker"), U);
    EXPECT_LT(l.A.determinant(), 0.0) << U;  // one positive real eigenvalue
  }
}

// --- Linearisation --------------------------------------------------------------------

TEST(Linearise, AgreesWithFiniteDifferencesAtOtherStepSizes) {
  for (const ZooEntry& e : zoo()) {
    for (double U : e.speeds) {
      const Linearisation ref = linearise(*e.hull, U, 1e-5);
      // |x|x damping terms (zero slope at zero) put an O(h) term in a central difference:
      // steps up to 1e-4 keep it below the tolerance.
      for (double h : {3e-5, 1e-4, 1e-6}) {
        const Linearisation l = linearise(*e.hull, U, h);
        const std::string what = e.name + " U=" + std::to_string(U) + " h=" + std::to_string(h);
        EXPECT_LE((l.A - ref.A).norm(), 2e-3 * ref.A.norm()) << what;
        EXPECT_LE((l.B - ref.B).norm(), 2e-3 * ref.B.norm()) << what;
      }
    }
  }
}

TEST(Linearise, StraightRunningIsASurgeEquilibrium) {
  for (const ZooEntry& e : zoo()) {
    for (double U : e.speeds) {
      HullInput in;
      in.throttle = equilibrium_throttle(*e.hull, U);
      const HullRates f = e.hull->rates({U, 0.0, 0.0}, in, {});
      EXPECT_LE(std::abs(f.du), 1e-9 * U) << e.name << " U=" << U;
    }
    EXPECT_NEAR(equilibrium_throttle(*e.hull, e.hull->nominal_speed()), 1.0, 1e-9) << e.name;
  }
}

TEST(Linearise, LinearHullsGiveTheirAnalyticAAndB) {
  const std::vector<LinearHullData> data = {lcontainer_data(),
                                            clarke83_data("coaster", 50.0, 7.0, 5.0, 0.7, 5.0)};
  for (const LinearHullData& d : data) {
    const auto h = make_linear_hull(d);
    for (double U : {0.6 * d.U0, d.U0, 1.3 * d.U0}) {
      const Linearisation l = linearise(*h, U);
      const double s = U / d.U0;
      expect_rel(l.A, s * d.A0, 1e-7, d.name + " A");
      expect_rel(l.B, s * s * d.B0, 1e-7, d.name + " B");
    }
  }
  // The zoo's linear Mariner is the core's shipped model.
  const Linearisation l = linearise(hull("mariner-linear"), mariner().u0);
  expect_rel(l.A, mariner().A, 1e-7, "mariner-linear A");
  expect_rel(l.B, mariner().B, 1e-7, "mariner-linear B");
}

TEST(Linearise, NonlinearMarinerGivesThePublishedLinearisation) {
  // The core's mariner() is mariner.m (Chislett & Strom-Tejsen coefficients) linearised at
  // 15 knots, printed to 6 digits.
  const Linearisation l = linearise(hull("mariner"), mariner().u0);
  expect_rel(l.A, mariner().A, 2e-5, "A");
  expect_rel(l.B, mariner().B, 2e-5, "B");
}

TEST(Linearise, Otter3dofAtOneMetrePerSecondIsTheCoresLinearOtter) {
  // The core's otter() is otter.py linearised at 1 m/s, to 6 digits; its B rests on the
  // equivalent-rudder moment 63.9 N m printed to 3 digits (2e-4 relative).
  const Linearisation l = linearise(hull("otter3dof"), otter().u0);
  expect_rel(l.A, otter().A, 1e-4, "A");
  expect_rel(l.B, otter().B, 5e-4, "B");
}

TEST(Linearise, NonlinearContainerAgreesWithSonAndNomotosLinearModel) {
  // Son & Nomoto published both; their linear model (Lcontainer) is the linearisation of the
  // nonlinear one with the propeller race simplified: A within 5 %, B within 20 % (the
  // rudder inflow of the nonlinear model depends on the propeller loading).
  const Linearisation nl = linearise(hull("container"), 7.0);
  const Linearisation li = linearise(hull("lcontainer"), 7.0);
  expect_rel(nl.A, li.A, 0.05, "A");
  expect_rel(nl.B, li.B, 0.20, "B");
}

TEST(Linearise, Kvlcc2ModelScaleAgreesWithTheRealDataReadme) {
  // ../shared/realdata/kvlcc2-hsva/README.md: the same published MMG model linearised at
  // 1.179 m/s, A = [[-0.103, -0.412], [-0.090, -0.394]], B = [0.0345, -0.0375] with delta
  // positive to port (HSVA); this hull keeps the MMG sign (delta > 0 to starboard).
  Mat2 A;
  A << -0.103, -0.412, -0.090, -0.394;
  const Linearisation l = linearise(hull("kvlcc2"), 1.179);
  expect_rel(l.A, A, 0.05, "A");
  expect_rel(l.B, -Vec2(0.0345, -0.0375), 0.15, "B");
}

TEST(Linearise, ShipHydrodynamicsScaleWithSpeed) {
  // Prime-system models: A ~ U and B ~ U^2 where the propeller loading stays the same.
  for (const std::string name : {"mariner", "container", "esso-tanker", "kvlcc2-full"}) {
    const ZooEntry& e = *find_hull(name);
    const double U0 = e.speeds[0], U1 = e.speeds[1];
    const Linearisation l0 = linearise(*e.hull, U0), l1 = linearise(*e.hull, U1);
    expect_rel(l1.A, (U1 / U0) * l0.A, 0.05, name + " A");
    expect_rel(l1.B, (U1 / U0) * (U1 / U0) * l0.B, 0.30, name + " B");
  }
}

// --- Manoeuvres -----------------------------------------------------------------------

/// IMO MSC.137(76) limit on the first (second) overshoot of a 10/10 zigzag [deg].
double imo_first_overshoot(double L_over_U) {
  return L_over_U < 10 ? 10 : L_over_U >= 30 ? 20 : 5 + 0.5 * L_over_U;
}
double imo_second_overshoot(double L_over_U) {
  return L_over_U < 10 ? 25 : L_over_U >= 30 ? 40 : 17.5 + 0.75 * L_over_U;
}

TEST(Manoeuvre, ShipsMeetTheImoManoeuvringCriteria) {
  // MSC.137(76): advance < 4.5 L, tactical diameter < 5 L (35 deg turn); 10/10 and 20/20
  // overshoots. These are the standards the sources' ships were designed to; the Mariner
  // (a 1950s design) turns wider than 5 L in this model: its tactical diameter is only
  // printed.
  for (const std::string name : {"mariner", "container", "esso-tanker", "kvlcc2", "kvlcc2-full"}) {
    const Hull& h = hull(name);
    const double L = h.limits().length, U = h.nominal_speed();
    const TurningCircle tc = turning_circle(h, U, 35 * kDeg);
    const Zigzag z10 = zigzag(h, U, 10 * kDeg, 10 * kDeg);
    const Zigzag z20 = zigzag(h, U, 20 * kDeg, 20 * kDeg);
    std::printf("%-12s AD/L %.2f TD/L %.2f U_turn/U0 %.2f 10/10 %.1f %.1f deg 20/20 %.1f deg\n",
                name.c_str(), tc.advance / L, tc.tactical_diameter / L, tc.steady_speed / U,
                z10.first_overshoot / kDeg, z10.second_overshoot / kDeg,
                z20.first_overshoot / kDeg);
    EXPECT_LT(tc.advance, 4.5 * L) << name;
    if (name != "mariner") {
      EXPECT_LT(tc.tactical_diameter, 5.0 * L) << name;
    }
    EXPECT_GT(tc.tactical_diameter, 1.5 * L) << name;
    EXPECT_LT(z10.first_overshoot / kDeg, imo_first_overshoot(L / U)) << name;
    EXPECT_LT(z10.second_overshoot / kDeg, imo_second_overshoot(L / U)) << name;
    EXPECT_LT(z20.first_overshoot / kDeg, 25.0) << name;
    EXPECT_GT(z10.first_overshoot, 0.0) << name;
  }
}

TEST(Manoeuvre, Kvlcc2TurnsLikeThePublishedMmgStandardModel) {
  // Yasukawa & Yoshimura 2015 (J. Mar. Sci. Technol. 20:37-52), Table 4: the MMG standard
  // model of the KVLCC2 L7 model (7 m) turning with 35 deg of rudder, calculated: advance
  // 3.31 L, tactical diameter 3.36 L (their free-running tests: 3.25 L and 3.34 L). The
  // paper's simulations moved the rudder at 1.76 deg/s full scale, this hull at the SIMMAN
  // test rate of 2.32 deg/s (docs/vessels.md), which turns a little tighter; 10 %, about
  // twice the paper's own calculation-to-experiment differences, is allowed.
  const Hull& h = hull("kvlcc2");
  const double L = h.limits().length;
  const TurningCircle tc = turning_circle(h, h.nominal_speed(), 35 * kDeg);
  std::printf("kvlcc2 35 deg turn: advance %.2f L, tactical diameter %.2f L\n", tc.advance / L,
              tc.tactical_diameter / L);
  EXPECT_NEAR(tc.advance / L, 3.31, 0.10 * 3.31);
  EXPECT_NEAR(tc.tactical_diameter / L, 3.36, 0.10 * 3.36);
}

TEST(Manoeuvre, Kvlcc2TurnsToPortLikeThePublishedMmgStandardModel) {
  // Yasukawa & Yoshimura 2015, Table 4, the 7 m model turning with 35 deg of rudder to PORT,
  // calculated with the MMG standard model: advance 3.26 L, tactical diameter 3.26 L (their
  // free-running tests: 3.11 L and 3.08 L). The port figures were not read from the paper
  // here but from a secondary source that transcribes Table 4 (JuliaComputing/DyadShip,
  // scripts/validate_kvlcc2.jl; its starboard figures are the 3.31 / 3.36 L above);
  // docs/vessels.md says so. Tolerance as to starboard: 10 % of the calculated figure, about
  // twice the paper's own calculation-to-test differences (up to 5.8 %, the port tactical
  // diameter). Against the free-running test the same 10 % is asserted.
  const Hull& h = hull("kvlcc2");
  const double L = h.limits().length;
  const TurningCircle tc = turning_circle(h, h.nominal_speed(), 35 * kDeg, Side::kPort);
  std::printf("kvlcc2 35 deg turn to port: advance %.2f L, tactical diameter %.2f L\n",
              tc.advance / L, tc.tactical_diameter / L);
  EXPECT_NEAR(tc.advance / L, 3.26, 0.10 * 3.26);
  EXPECT_NEAR(tc.tactical_diameter / L, 3.26, 0.10 * 3.26);
  EXPECT_NEAR(tc.advance / L, 3.11, 0.10 * 3.11);
  EXPECT_NEAR(tc.tactical_diameter / L, 3.08, 0.10 * 3.08);
}

TEST(Manoeuvre, Kvlcc2FullScaleTurnsWithin20PercentOfThePublishedFullScaleSimulation) {
  // Yasukawa & Yoshimura 2015, Table 6: the MMG standard model at full scale (320 m, 15.5 kn)
  // turning with 35 deg of rudder, calculated: starboard advance 3.62 L, tactical diameter
  // 3.71 L; port 3.56 L, 3.59 L (read, like the port figures above, from the secondary
  // source's transcription). For it the paper took a full-scale hull resistance from a 3-D
  // extrapolation (not printed) and full-scale propulsion; `kvlcc2-full` is the published
  // model-scale coefficients at 320 m (docs/vessels.md) and turns like the 7 m model, 14-16 %
  // tighter than Table 6. The paper's own full-scale circles are 9-10 % wider than its model
  // ones: 20 % (that scale effect plus the 10 % allowed at model scale) is asserted, and the
  // deviation documented rather than tuned away.
  const Hull& h = hull("kvlcc2-full");
  const double L = h.limits().length;
  const struct {
    Side side;
    double advance, tactical;
  } cases[] = {{Side::kStarboard, 3.62, 3.71}, {Side::kPort, 3.56, 3.59}};
  for (const auto& c : cases) {
    const TurningCircle tc = turning_circle(h, h.nominal_speed(), 35 * kDeg, c.side, 0.5);
    std::printf(
        "kvlcc2-full 35 deg turn to %s: advance %.2f L (%.2f), tactical diameter %.2f L "
        "(%.2f)\n",
        to_string(c.side), tc.advance / L, c.advance, tc.tactical_diameter / L, c.tactical);
    EXPECT_NEAR(tc.advance / L, c.advance, 0.20 * c.advance) << to_string(c.side);
    EXPECT_NEAR(tc.tactical_diameter / L, c.tactical, 0.20 * c.tactical) << to_string(c.side);
  }
}

TEST(Manoeuvre, TurnsAndZigzagsTakeASideStarboardByDefault) {
  for (const std::string name : {"lcontainer", "mariner-linear", "kvlcc2"}) {
    const Hull& h = hull(name);
    const double U = h.nominal_speed(), L = h.limits().length;
    const double rudder = (name == "kvlcc2" ? 35 : 10) * kDeg;
    // The default is starboard, bit for bit.
    const TurningCircle def = turning_circle(h, U, rudder);
    const TurningCircle stb = turning_circle(h, U, rudder, Side::kStarboard);
    const TurningCircle port = turning_circle(h, U, rudder, Side::kPort);
    EXPECT_EQ(def.advance, stb.advance) << name;
    EXPECT_EQ(def.transfer, stb.transfer) << name;
    EXPECT_EQ(def.tactical_diameter, stb.tactical_diameter) << name;
    EXPECT_EQ(def.steady_yaw_rate, stb.steady_yaw_rate) << name;
    const Zigzag zdef = zigzag(h, U, 10 * kDeg, 10 * kDeg);
    const Zigzag zstb = zigzag(h, U, 10 * kDeg, 10 * kDeg, Side::kStarboard);
    const Zigzag zport = zigzag(h, U, 10 * kDeg, 10 * kDeg, Side::kPort);
    EXPECT_EQ(zdef.first_overshoot, zstb.first_overshoot) << name;
    EXPECT_EQ(zdef.second_overshoot, zstb.second_overshoot) << name;
    // A port circle is measured towards port: positive distances, a negative yaw rate.
    EXPECT_GT(port.advance, 0.0) << name;
    EXPECT_GT(port.transfer, 0.0) << name;
    EXPECT_GT(port.tactical_diameter, 0.0) << name;
    EXPECT_LT(port.steady_yaw_rate, 0.0) << name;
    EXPECT_GT(zport.first_overshoot, 0.0) << name;
    EXPECT_GT(zport.second_overshoot, 0.0) << name;
    if (!h.nonlinear()) {
      // A linear hull is symmetric: port is starboard mirrored.
      EXPECT_NEAR(port.advance, stb.advance, 1e-9 * L) << name;
      EXPECT_NEAR(port.transfer, stb.transfer, 1e-9 * L) << name;
      EXPECT_NEAR(port.tactical_diameter, stb.tactical_diameter, 1e-9 * L) << name;
      EXPECT_NEAR(port.steady_yaw_rate, -stb.steady_yaw_rate, 1e-12) << name;
      EXPECT_NEAR(zport.first_overshoot, zstb.first_overshoot, 1e-9) << name;
      EXPECT_NEAR(zport.second_overshoot, zstb.second_overshoot, 1e-9) << name;
    } else {
      // The KVLCC2's published model is not (propeller wake and flow straightening switch
      // with the side): its port circle differs.
      EXPECT_GT(std::abs(port.tactical_diameter - stb.tactical_diameter), 0.01 * L) << name;
    }
  }
  EXPECT_STREQ(to_string(Side::kPort), "port");
  EXPECT_STREQ(to_string(Side::kStarboard), "starboard");
  Side s = Side::kStarboard;
  EXPECT_TRUE(parse_side("port", &s));
  EXPECT_EQ(s, Side::kPort);
  EXPECT_TRUE(parse_side("starboard", &s));
  EXPECT_EQ(s, Side::kStarboard);
  EXPECT_FALSE(parse_side("left", &s));
  EXPECT_EQ(s, Side::kStarboard);
}

TEST(Manoeuvre, NonlinearHullsLoseSpeedInATurn) {
  for (const ZooEntry& e : zoo()) {
    if (!e.hull->nonlinear()) continue;
    const double U = e.hull->nominal_speed();
    const TurningCircle tc = turning_circle(*e.hull, U, 35 * kDeg);
    const double ratio = tc.steady_speed / U;
    EXPECT_GT(ratio, 0.1) << e.name;
    // Ships lose 20-70 % in a 35 deg turn; the Otter (thrust-steered, no rudder drag) less.
    EXPECT_LT(ratio, e.hull->limits().length > 5.0 ? 0.85 : 0.97) << e.name;
  }
}

TEST(Manoeuvre, LinearHullsKeepTheirSpeedInATurn) {
  // The contrast that makes the nonlinear hulls necessary: a linear hull's surge ignores the
  // turn.
  const Hull& h = hull("lcontainer");
  ManoeuvreState s;
  s.x.u = 7.0;
  for (int i = 0; i < 6000; ++i) s = manoeuvre_step(h, s, 10 * kDeg, 1.0, 0.1);
  EXPECT_NEAR(s.x.u, 7.0, 1e-9);
}

TEST(Manoeuvre, IsDeterministic) {
  for (const std::string name : {"kvlcc2", "otter3dof"}) {
    const Hull& h = hull(name);
    const TurningCircle a = turning_circle(h, h.nominal_speed(), 35 * kDeg);
    const TurningCircle b = turning_circle(h, h.nominal_speed(), 35 * kDeg);
    EXPECT_EQ(a.advance, b.advance);
    EXPECT_EQ(a.tactical_diameter, b.tactical_diameter);
    EXPECT_EQ(a.steady_speed, b.steady_speed);
    const Zigzag z1 = zigzag(h, h.nominal_speed(), 20 * kDeg, 20 * kDeg);
    const Zigzag z2 = zigzag(h, h.nominal_speed(), 20 * kDeg, 20 * kDeg);
    EXPECT_EQ(z1.first_overshoot, z2.first_overshoot);
    EXPECT_EQ(z1.second_overshoot, z2.second_overshoot);
  }
  EXPECT_EQ(&zoo(), &zoo());
}

TEST(Manoeuvre, RudderServoHonoursSaturationAndRateLimit) {
  const Hull& h = hull("esso-tanker");
  const HullLimits lim = h.limits();
  ManoeuvreState s;
  s.x.u = 8.23;
  double prev = 0.0;
  for (int i = 0; i < 400; ++i) {
    s = manoeuvre_step(h, s, 90 * kDeg, 1.0, 0.1);
    EXPECT_LE(s.delta - prev, lim.max_rudder_rate * 0.1 * (1 + 1e-9));
    EXPECT_LE(s.delta, lim.max_rudder * (1 + 1e-9));
    prev = s.delta;
  }
  EXPECT_NEAR(s.delta, lim.max_rudder, 1e-3);
}

// --- The recorded KVLCC2 zigzags (HSVA, SIMMAN 2008) ----------------------------------

/// The shared data directory: $USV_FDI_SHARED, else ../shared beside the source tree.
std::string shared_dir() {
  const char* env = std::getenv("USV_FDI_SHARED");
  return env != nullptr ? env : std::string(USV_FDI_SOURCE_DIR) + "/../shared";
}

/// Heading [rad] column of an HSVA csv, relative to its first value; empty if unreadable.
std::vector<double> recorded_heading(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> psi;
  std::string line;
  int col = -1;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
    if (col < 0) {
      for (std::size_t i = 0; i < f.size(); ++i) col = f[i] == "psi" ? static_cast<int>(i) : col;
      if (col < 0) return {};
      continue;
    }
    psi.push_back(std::stod(f.at(col)));
  }
  for (double& p : psi) p -= psi.empty() ? 0.0 : psi.front();
  return psi;
}

/// First and second overshoot [rad] of a heading record whose first execute is to `first`.
std::pair<double, double> overshoots(const std::vector<double>& psi, double heading, Side first) {
  int executes = 0;
  double side = 1.0, extreme = 0.0, o1 = NAN, o2 = NAN;
  for (double q : psi) {
    const double p = side_sign(first) * q;  // mirrored when the first execute is to port
    if (executes >= 1) extreme = side < 0 ? std::max(extreme, p) : std::min(extreme, p);
    if (side * p >= heading) {
      if (executes == 1) o1 = extreme - heading;
      if (executes == 2) o2 = -extreme - heading;
      side = -side;
      extreme = p;
      if (++executes == 3) break;
    }
  }
  return {o1, o2};
}

TEST(Manoeuvre, Kvlcc2ZigzagsAgainstTheRecordedHsvaTests) {
  const std::string dir = shared_dir() + "/realdata/kvlcc2-hsva/";
  if (!std::ifstream(dir + "README.md")) {
    GTEST_SKIP() << "no " << dir << " (set USV_FDI_SHARED to the shared data directory)";
  }
  // The MMG model (Yasukawa & Yoshimura 2015) against HSVA's free-running 7 m model: the
  // model under-predicts the first overshoot by 20-50 % (measured 9.7 deg in the 10/10 to
  // either side, the model 5.0 deg starting to starboard, 7.2 deg to port), the second by up
  // to 40 %. Asserted: within 50 % and never above the measurement by more than 15 %. The
  // numbers are printed. (Those tests whose name has no _P or _S start to starboard.)
  const struct {
    const char* file;
    double rudder, heading;
    Side first;
  } cases[] = {{"HSVA_CPMC_KVLCC2_Z_10_10_S.csv", 10, 10, Side::kStarboard},
               {"HSVA_CPMC_KVLCC2_Z_10_10_P.csv", 10, 10, Side::kPort},
               {"HSVA_CPMC_KVLCC2_Z_20_10_S.csv", 20, 10, Side::kStarboard},
               {"HSVA_CPMC_KVLCC2_Z_20_10_P.csv", 20, 10, Side::kPort},
               {"HSVA_CPMC_KVLCC2_Z_10_05.csv", 10, 5, Side::kStarboard},
               {"HSVA_CPMC_KVLCC2_Z_20_05.csv", 20, 5, Side::kStarboard}};
  const Hull& h = hull("kvlcc2");
  for (const auto& c : cases) {
    const std::vector<double> psi = recorded_heading(dir + c.file);
    ASSERT_FALSE(psi.empty()) << c.file;
    const auto [m1, m2] = overshoots(psi, c.heading * kDeg, c.first);
    const Zigzag z = zigzag(h, 1.179, c.rudder * kDeg, c.heading * kDeg, c.first, 0.02);
    std::printf("%s: recorded %.2f / %.2f deg, MMG %.2f / %.2f deg\n", c.file, m1 / kDeg, m2 / kDeg,
                z.first_overshoot / kDeg, z.second_overshoot / kDeg);
    EXPECT_GT(z.first_overshoot, 0.5 * m1) << c.file;
    EXPECT_LT(z.first_overshoot, 1.15 * m1) << c.file;
    if (!std::isnan(m2)) {
      EXPECT_GT(z.second_overshoot, 0.5 * m2) << c.file;
      EXPECT_LT(z.second_overshoot, 1.15 * m2) << c.file;
    }
  }
}

}  // namespace
}  // namespace usvfdi::sim
