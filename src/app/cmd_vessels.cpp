// usv-fdi vessels: the vessel zoo (hull models from published sources, linearised), and
// `--yaml NAME [--speed U]`: the engine configuration a user of that hull would write.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::app {
namespace {

struct VesselsArgs {
  std::string yaml;    // hull name for --yaml
  double speed = 0.0;  // [m/s]; 0: the hull's nominal speed
};

struct Summary {
  sim::Linearisation lin;
  Eigen::Vector2cd eig;
  bool stable = false;
};

Summary summarise(const sim::Hull& hull, double u0) {
  Summary s;
  s.lin = sim::linearise(hull, u0);
  s.eig = Eigen::EigenSolver<Mat2>(s.lin.A).eigenvalues();
  s.stable = s.eig(0).real() < 0.0 && s.eig(1).real() < 0.0;
  return s;
}

std::string eig_text(const Eigen::Vector2cd& e) {
  char buf[96];
  if (e(0).imag() == 0.0) {
    std::snprintf(buf, sizeof buf, "%.4g, %.4g", e(0).real(), e(1).real());
  } else {
    std::snprintf(buf, sizeof buf, "%.4g +- %.4gi", e(0).real(), std::abs(e(0).imag()));
  }
  return buf;
}

const char* turn_side(const sim::Linearisation& lin) {
  return lin.B(1) > 0.0 ? "starboard (r > 0)" : "port (r < 0)";
}

int list_zoo() {
  std::printf("%-17s %8s %8s %-9s %11s %-22s %-16s\n", "name", "U [m/s]", "L [m]", "model", "det A",
              "eigenvalues [1/s]", "stability");
  for (const sim::ZooEntry& e : sim::zoo()) {
    for (double U : e.speeds) {
      const Summary s = summarise(*e.hull, U);
      std::printf("%-17s %8.4g %8.4g %-9s %11.3e %-22s %-16s\n", e.name.c_str(), U,
                  e.hull->limits().length, e.hull->nonlinear() ? "nonlinear" : "linear",
                  s.lin.A.determinant(), eig_text(s.eig).c_str(),
                  s.stable ? "stable" : "course-unstable");
    }
  }
  std::printf("\nsources (docs/vessels.md has the table, signs and speeds):\n");
  for (const sim::ZooEntry& e : sim::zoo()) {
    std::printf("  %-17s %s\n", e.name.c_str(), e.hull->source().c_str());
  }
  std::printf("\nusv-fdi vessels --yaml NAME [--speed U] prints the configuration for a hull.\n");
  std::printf("\nshipped linear models of usv-fdi sim --vessel (with their INS noise):\n");
  for (const VesselModel& m : shipped_vessels()) {
    std::printf(
        "  %-8s u0 %.6g m/s, B: [%.6g, %.6g], sigma_v %.3g m/s, sigma_r %.3g rad/s, "
        "config/vessels/%s.yaml\n",
        m.name.c_str(), m.u0, m.B(0), m.B(1), m.sigma_v, m.sigma_r, m.name.c_str());
  }
  return std::fflush(stdout) == 0 ? kExitOk : kExitOutput;
}

int print_yaml(const VesselsArgs& a) {
  const sim::ZooEntry* e = sim::find_hull(a.yaml);
  if (e == nullptr) {
    std::fprintf(stderr, "vessels --yaml: no hull '%s' (usv-fdi vessels lists them)\n",
                 a.yaml.c_str());
    return kExitUsage;
  }
  const sim::Hull& h = *e->hull;
  const double U = a.speed > 0.0 ? a.speed : h.nominal_speed();
  Summary s;
  try {
    s = summarise(h, U);
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "vessels --yaml %s --speed %g: %s\n", a.yaml.c_str(), U, ex.what());
    return kExitUsage;
  }
  const sim::HullLimits lim = h.limits();
  const Mat2& A = s.lin.A;
  std::printf("# usv-fdi configuration for the hull '%s' at u0 = %.6g m/s\n", e->name.c_str(), U);
  std::printf(
      "# (usv-fdi vessels --yaml %s --speed %.6g; config/default.yaml documents every key)\n",
      e->name.c_str(), U);
  std::printf("# Hull: %s\n", h.source().c_str());
  std::printf("# L = %.6g m, %s model, rudder max %.3g deg, rate %.3g deg/s\n", lim.length,
              h.nonlinear() ? "nonlinear 3-DOF" : "linear sway-yaw", lim.max_rudder * 180 / M_PI,
              lim.max_rudder_rate * 180 / M_PI);
  std::printf("# Rudder sign (the hull's published convention): delta > 0 turns to %s\n",
              turn_side(s.lin));
  std::printf(
      "# Linearised about straight running at u0 (central differences, docs/vessels.md):\n");
  std::printf("#   x' = A x + B delta, x = [v r]\n");
  std::printf("#   A = [[%.6g, %.6g], [%.6g, %.6g]]  (the engine identifies A; not a key)\n",
              A(0, 0), A(0, 1), A(1, 0), A(1, 1));
  std::printf("#   det A = %.4g 1/s^2, eigenvalues %s 1/s: %s\n", A.determinant(),
              eig_text(s.eig).c_str(), s.stable ? "course-stable" : "course-unstable");
  std::printf("#   B at another speed: usv-fdi vessels --yaml %s --speed U\n", e->name.c_str());
  std::printf("model:\n");
  std::printf("  B: [%.6g, %.6g]  # [m/s^2/rad, 1/s^2]\n", s.lin.B(0), s.lin.B(1));
  return std::fflush(stdout) == 0 ? kExitOk : kExitOutput;
}

int run_vessels(const VesselsArgs& a) { return a.yaml.empty() ? list_zoo() : print_yaml(a); }

}  // namespace

void register_vessels_command(CommandRegistry& registry) {
  auto args = std::make_shared<VesselsArgs>();
  CLI::App* sub = registry.add(
      "vessels",
      "List the vessel zoo (speed, length, det A, eigenvalues, stability, source), or print the "
      "configuration for one hull (--yaml NAME)",
      [args] { return run_vessels(*args); });
  sub->add_option("--yaml", args->yaml, "print the configuration (model.B) for this hull");
  sub->add_option("--speed", args->speed, "speed of the linearisation [m/s] (default: nominal)")
      ->check(CLI::PositiveNumber);
}

}  // namespace usvfdi::app
