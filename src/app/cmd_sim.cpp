// usv-fdi sim: simulate a voyage (optionally with INS faults) into a CSV for replay.
#include <spdlog/spdlog.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/scenarios.hpp"

namespace usvfdi::app {
namespace {

struct SimArgs {
  std::string vessel = "otter";
  std::string scenario = "paper";
  double rate_hz = 50.0;
  std::optional<double> duration;
  std::uint64_t seed = 1;
  std::vector<std::string> faults;
  std::string steering;  ///< empty: the scenario's
  double noise_scale = 1.0;
  std::string output;
};

int run_sim(const SimArgs& a) {
  VesselModel vessel;
  if (!find_vessel(a.vessel, &vessel)) {  // unreachable: CLI11 checks the name
    spdlog::error("unknown vessel '{}'", a.vessel);
    return kExitUsage;
  }
  SimConfig c;
  if (a.scenario == "paper") {
    c = paper_scenario(vessel, a.rate_hz, a.seed);
  } else if (a.scenario == "healthy") {
    c = io::healthy_scenario(vessel, a.rate_hz, a.seed);
  } else {
    c = io::faults_scenario(vessel, a.rate_hz, a.seed);
  }
  for (const std::string& spec : a.faults) {
    FaultInjection f;
    std::string why;
    if (!io::parse_fault_spec(spec, &f, &why)) {
      spdlog::error("--fault: {}", why);
      return kExitUsage;
    }
    c.faults.push_back(f);
  }
  if (a.duration) c.duration = *a.duration;
  if (a.steering == "autopilot") c.steering = Steering::kAutopilot;
  if (a.steering == "sine") c.steering = Steering::kSine;
  c.sigma_v = a.noise_scale * vessel.sigma_v;
  c.sigma_r = a.noise_scale * vessel.sigma_r;

  std::unique_ptr<Simulator> sim;
  try {
    sim = std::make_unique<Simulator>(c);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }

  std::ofstream file;
  const bool to_stdout = a.output == "-";
  if (!to_stdout) {
    file.open(a.output, std::ios::binary | std::ios::trunc);
    if (!file) {
      spdlog::error("{}: cannot open for writing", a.output);
      return kExitOutput;
    }
  }
  std::ostream& os = to_stdout ? std::cout : file;
  io::SimCsvWriter writer(os);
  SimRow row;
  std::size_t rows = 0;
  while (sim->next(&row)) {
    writer.write(row);
    ++rows;
  }
  os.flush();
  if (!os) {
    spdlog::error("{}: write failed", a.output);
    return kExitOutput;
  }
  spdlog::info(
      "{}: {} rows, vessel {}, scenario {}, {} Hz, {} s, seed {}, {} steering, noise "
      "sigma_v {:.3g} m/s sigma_r {:.3g} rad/s",
      to_stdout ? std::string("stdout") : a.output, rows, vessel.name, a.scenario, c.rate_hz,
      c.duration, c.seed, c.steering == Steering::kSine ? "sine" : "autopilot", c.sigma_v,
      c.sigma_r);
  for (const FaultInjection& f : c.faults) spdlog::info("  fault {}", io::format_fault_spec(f));
  if (c.faults.empty()) spdlog::info("  no faults");
  return kExitOk;
}

}  // namespace

void register_sim_command(CommandRegistry& registry) {
  auto args = std::make_shared<SimArgs>();
  CLI::App* sub =
      registry.add("sim",
                   "Simulate a shipped vessel with optional INS faults and write CSV rows "
                   "(t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g; %.17g)",
                   [args] { return run_sim(*args); });
  std::vector<std::string> names;
  for (const VesselModel& m : shipped_vessels()) names.push_back(m.name);
  sub->add_option("--vessel", args->vessel, "shipped vessel model")
      ->check(CLI::IsMember(names))
      ->capture_default_str();
  sub->add_option("--scenario", args->scenario,
                  "paper: gyro bias (20,40) s, accelerometer bias (60,80) s, sine rudder; "
                  "healthy: autopilot voyage without faults; faults: one fault of every kind "
                  "on alternating sensors after the engine has learned")
      ->check(CLI::IsMember({"paper", "healthy", "faults"}))
      ->capture_default_str();
  sub->add_option("--rate", args->rate_hz, "sample rate [Hz]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--duration", args->duration, "duration [s] (default: the scenario's)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--seed", args->seed, "noise seed")->capture_default_str();
  sub->add_option("--fault", args->faults,
                  "extra fault sensor:kind:start:end[:magnitude[:spike_rate]] "
                  "(e.g. gyro:bias:20:40:0.005); repeatable");
  sub->add_option("--steering", args->steering, "autopilot or sine (default: the scenario's)")
      ->check(CLI::IsMember({"autopilot", "sine"}));
  sub->add_option("--noise-scale", args->noise_scale,
                  "factor on the vessel's realistic sensor noise (0: noise-free)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--output", args->output, "output CSV ('-': stdout)")->required();
}

}  // namespace usvfdi::app
