// usv-fdi health: the container health check. Judges the file that `usv-fdi run
// --health-file` rewrites every status period (usv_fdi/dds_service/health.hpp): exit 0 when it
// is fresh, says running (or starting) and every pipeline thread advances; else exit 1. One
// line on stdout either way (Docker keeps it in the container's health log).
#include <chrono>
#include <cstdio>
#include <string>

#include "commands.hpp"
#include "usv_fdi/dds_service/health.hpp"

namespace usvfdi::app {
namespace {

struct HealthArgs {
  std::string file;
  double max_age = 0.0;
};

int run_health(const HealthArgs& a) {
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const dds_service::HealthVerdict v = dds_service::check_health_file(a.file, a.max_age, now);
  std::printf("%s\n", v.line.c_str());
  std::fflush(stdout);
  return v.healthy ? kExitOk : kExitFailure;
}

}  // namespace

void register_health_command(CommandRegistry& registry) {
  static HealthArgs args;
  CLI::App* sub = registry.add(
      "health",
      "container health check: exit 0 if the sidecar's --health-file is fresh and its threads "
      "advance, else 1 with the reason",
      [] { return run_health(args); });
  sub->add_option("--health-file", args.file, "the file given to `usv-fdi run --health-file`")
      ->required();
  sub->add_option("--max-age", args.max_age,
                  "oldest acceptable file and longest thread stall [s] (default: 3 status "
                  "periods, at least 3 s)")
      ->check(CLI::PositiveNumber);
}

}  // namespace usvfdi::app
