// usv-fdi vessels: the shipped vessel models.
#include <cstdio>

#include "commands.hpp"
#include "usv_fdi/core/vessel.hpp"

namespace usvfdi::app {
namespace {

int run_vessels() {
  for (const VesselModel& m : shipped_vessels()) {
    std::printf("%s\n", m.name.c_str());
    std::printf("  source:  %s\n", m.source.c_str());
    std::printf("  u0:      %.6g m/s\n", m.u0);
    std::printf("  A:       [[%.6g, %.6g], [%.6g, %.6g]]  (x' = A x + B delta, x = [v r])\n",
                m.A(0, 0), m.A(0, 1), m.A(1, 0), m.A(1, 1));
    std::printf("  B:       [%.6g, %.6g]  (config: model.B)\n", m.B(0), m.B(1));
    std::printf("  noise:   sigma_v %.3g m/s, sigma_r %.3g rad/s\n", m.sigma_v, m.sigma_r);
    std::printf("  rudder:  max %.3g rad, rate %.3g rad/s, servo %.3g s\n", m.max_rudder,
                m.max_rudder_rate, m.rudder_time_constant);
    std::printf("  config:  config/vessels/%s.yaml\n", m.name.c_str());
  }
  return std::fflush(stdout) == 0 ? kExitOk : kExitOutput;
}

}  // namespace

void register_vessels_command(CommandRegistry& registry) {
  registry.add("vessels", "List the shipped vessel models (A, B, source)",
               [] { return run_vessels(); });
}

}  // namespace usvfdi::app
