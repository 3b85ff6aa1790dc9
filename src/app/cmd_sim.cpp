// usv-fdi sim: simulate a voyage (optionally with INS faults) into a CSV for replay, or, with
// --publish, as INS and rudder samples on DDS for one or many vessels (sim_publish.cpp).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "open_output.hpp"
#include "sim_voyage.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/nmea_log.hpp"
#include "usv_fdi/io/output_file.hpp"
#include "usv_fdi/io/scenarios.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea_udp/udp.hpp"
#include "usv_fdi/sim/voyage.hpp"
#ifdef USV_FDI_APP_WITH_DDS
#include "dds_options.hpp"
#include "sim_publish.hpp"
#include "usv_fdi/dds_service/service.hpp"
#include "usv_fdi/io/config.hpp"
#endif

namespace usvfdi::app {
namespace {

/// The options every scenario takes (VoyageCommon: vessel, scenario, output, rate, duration,
/// seed, noise scale, faults), then those of the classic scenarios, the voyages and --publish.
struct SimArgs : VoyageCommon {
  SimArgs() {
    vessel = "otter";
    scenario = "paper";
  }
  std::string steering;  ///< empty: the scenario's
  VoyageArgs voyage;     ///< options of the voyage scenarios (sim_voyage.cpp)
  double speed = 1.0;    ///< --publish, --udp: data time per wall time
  std::string udp;       ///< --nmea --udp GROUP:PORT: send IEC 61162-450 datagrams there
  std::string udp_interface = "127.0.0.1";  ///< IP_MULTICAST_IF
  int udp_ttl = 1;                          ///< IP_MULTICAST_TTL
#ifdef USV_FDI_APP_WITH_DDS
  bool publish = false;
  std::vector<std::uint32_t> mmsi;
  std::vector<std::uint32_t> healthy;  ///< vessels without the scenario's / shared faults
  PublishOptions pub;
  DdsCli dds;
#endif
};

/// Splits an optional "MMSI@" prefix off a --fault spec (0: every vessel).
bool split_fault_target(const std::string& spec, std::uint32_t* mmsi, std::string* rest,
                        std::string* why) {
  const auto at = spec.find('@');
  *mmsi = 0;
  *rest = spec;
  if (at == std::string::npos) return true;
  const std::string m = spec.substr(0, at);
  try {
    std::size_t used = 0;
    const unsigned long long v = std::stoull(m, &used);
    if (used != m.size() || v == 0 || v > 999999999ull) throw std::invalid_argument(m);
    *mmsi = static_cast<std::uint32_t>(v);
  } catch (const std::exception&) {
    *why = "fault '" + spec + "': '" + m + "' before '@' is not an MMSI (1..999999999)";
    return false;
  }
  *rest = spec.substr(at + 1);
  return true;
}

bool is_classic(const std::string& scenario) {
  return scenario == "paper" || scenario == "healthy" || scenario == "faults";
}

#ifdef USV_FDI_APP_WITH_DDS
int publish_voyages(const SimArgs& a);
#endif

/// A voyage scenario: the voyage simulator over any hull (sim_voyage.cpp).
int run_voyage_scenario(const SimArgs& a) {
  if (!a.udp.empty()) {
    spdlog::error("--udp sends the classic scenarios (paper, healthy, faults) only");
    return kExitUsage;
  }
  if (!a.steering.empty()) {
    spdlog::error("--steering applies to the classic scenarios (paper, healthy, faults) only");
    return kExitUsage;
  }
#ifdef USV_FDI_APP_WITH_DDS
  if (a.publish) return publish_voyages(a);
  if (!a.mmsi.empty() || !a.healthy.empty()) {
    spdlog::error("--mmsi and --healthy only apply with --publish");
    return kExitUsage;
  }
#endif
  if (a.output.empty()) {
    spdlog::error("sim: give --output FILE");
    return kExitUsage;
  }
  return run_voyage_sim(a, a.voyage);
}

/// Faults given as MMSI@spec: for that vessel only (--publish).
using TargetedFaults = std::map<std::uint32_t, std::vector<FaultInjection>>;

/// The shipped vessel a classic scenario runs; false (logged) when the options do not fit one.
bool classic_vessel(const SimArgs& a, VesselModel* vessel) {
  if (!find_vessel(a.vessel, vessel)) {
    spdlog::error(
        "--vessel '{}': the classic scenarios (paper, healthy, faults) run the shipped "
        "vessels only; give a voyage scenario (--scenario course, voyage, ...)",
        a.vessel);
    return false;
  }
  if (a.voyage.any()) {
    spdlog::error(
        "--sea-state, --current, --wind, --sensor, --fault-set, --fault-sigma, --dither "
        "and --side need a voyage scenario (course, zigzag10, zigzag20, turn, speed, "
        "slow, voyage, hold), not '{}'",
        a.scenario);
    return false;
  }
  return true;
}

/// The classic scenario with the options applied: the --fault specs without MMSI@ join its
/// faults, the others go to *targeted. False (logged) for a bad --fault.
bool classic_config(const SimArgs& a, const VesselModel& vessel, SimConfig* config,
                    TargetedFaults* targeted) {
  SimConfig& c = *config;
  if (a.scenario == "paper") {
    c = paper_scenario(vessel, a.rate_hz, a.seed);
  } else if (a.scenario == "healthy") {
    c = io::healthy_scenario(vessel, a.rate_hz, a.seed);
  } else {
    c = io::faults_scenario(vessel, a.rate_hz, a.seed);
  }
  for (const std::string& text : a.faults) {
    FaultInjection f;
    std::string why, spec;
    std::uint32_t target = 0;
    if (!split_fault_target(text, &target, &spec, &why) || !io::parse_fault_spec(spec, &f, &why)) {
      spdlog::error("--fault: {}", why);
      return false;
    }
    if (target == 0) {
      c.faults.push_back(f);
    } else {
      (*targeted)[target].push_back(f);
    }
  }
  if (a.duration) c.duration = *a.duration;
  if (a.steering == "autopilot") c.steering = Steering::kAutopilot;
  if (a.steering == "sine") c.steering = Steering::kSine;
  c.sigma_v = a.noise_scale * vessel.sigma_v;
  c.sigma_r = a.noise_scale * vessel.sigma_r;
  return true;
}

#ifdef USV_FDI_APP_WITH_DDS
/// The vessels --publish simulates: --mmsi, else service.mmsi of --config. Returns kExitOk,
/// or the exit code after logging why they do not fit (also MMSI@ faults and --healthy that
/// name none of them).
int published_mmsis(const SimArgs& a, const TargetedFaults& targeted,
                    std::vector<std::uint32_t>* out) {
  std::vector<std::uint32_t>& mmsis = *out;
  mmsis = a.mmsi;
  if (mmsis.empty() && !a.dds.config.empty()) {
    try {
      const std::uint32_t m = dds_service::load_service_config(a.dds.config).mmsi;
      if (m != 0) mmsis.push_back(m);
    } catch (const io::ConfigError& e) {
      spdlog::error("{}", e.what());
      return kExitConfig;
    }
  }
  if (mmsis.empty()) {
    spdlog::error(
        "--publish needs the vessels' MMSIs: --mmsi (repeatable) or service.mmsi in --config");
    return kExitUsage;
  }
  const std::set<std::uint32_t> unique(mmsis.begin(), mmsis.end());
  if (unique.size() != mmsis.size()) {
    spdlog::error("--mmsi: every vessel needs its own MMSI (a value is repeated)");
    return kExitUsage;
  }
  for (const auto& kv : targeted) {
    if (!unique.count(kv.first)) {
      spdlog::error("--fault {}@...: {} is not one of the published vessels (--mmsi)", kv.first,
                    kv.first);
      return kExitUsage;
    }
  }
  for (const std::uint32_t h : a.healthy) {
    if (!unique.count(h)) {
      spdlog::error("--healthy {}: not one of the published vessels (--mmsi)", h);
      return kExitUsage;
    }
  }
  return kExitOk;
}

/// The DDS configuration and publishing options of --publish (RELIABLE also when
/// service.reliable_inputs of --config says so); false (logged) on a configuration error.
bool publish_setup(const SimArgs& a, usvfdi::dds::DdsConfig* dds, PublishOptions* opt) {
  bool config_reliable = false;
  try {
    *dds = make_dds_config(a.dds, &config_reliable);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  *opt = a.pub;
  opt->speed = a.speed;
  opt->reliable = a.pub.reliable || config_reliable;
  return true;
}

/// One simulation per vessel: seed + i, without the shared faults if --healthy, with its own
/// MMSI@ faults.
std::vector<std::pair<std::uint32_t, SimConfig>> vessel_simulations(
    const SimArgs& a, const VesselModel& vessel, const SimConfig& c,
    const std::vector<std::uint32_t>& mmsis, const TargetedFaults& targeted) {
  std::vector<std::pair<std::uint32_t, SimConfig>> vessels;
  for (std::size_t i = 0; i < mmsis.size(); ++i) {
    SimConfig vc = c;
    vc.seed = c.seed + i;  // independent noise per vessel
    if (std::find(a.healthy.begin(), a.healthy.end(), mmsis[i]) != a.healthy.end()) {
      vc.faults.clear();
    }
    const auto it = targeted.find(mmsis[i]);
    if (it != targeted.end())
      vc.faults.insert(vc.faults.end(), it->second.begin(), it->second.end());
    spdlog::info("vessel MMSI {}: {} {} Hz {} s seed {}", mmsis[i], vessel.name, vc.rate_hz,
                 vc.duration, vc.seed);
    for (const FaultInjection& f : vc.faults) spdlog::info("  fault {}", io::format_fault_spec(f));
    vessels.emplace_back(mmsis[i], vc);
  }
  return vessels;
}

/// --publish: the classic scenario on DDS for every vessel (sim_publish.cpp).
int publish_classic(const SimArgs& a, const VesselModel& vessel, const SimConfig& c,
                    const TargetedFaults& targeted) {
  std::vector<std::uint32_t> mmsis;
  const int rc = published_mmsis(a, targeted, &mmsis);
  if (rc != kExitOk) return rc;
  const auto vessels = vessel_simulations(a, vessel, c, mmsis, targeted);
  usvfdi::dds::DdsConfig dds;
  PublishOptions opt;
  if (!publish_setup(a, &dds, &opt)) return kExitConfig;
  return publish_simulation(vessels, dds, opt);
}

/// A voyage as --publish gives it: its measured samples, and its surge speed as a speed log
/// would (SpeedSample).
class VoyageSource : public RowSource {
 public:
  explicit VoyageSource(std::unique_ptr<sim::Voyage> v) : voyage_(std::move(v)) {}
  bool next(SimRow* row, double* u) override {
    if (!voyage_->next(&row_)) return false;
    *row = row_;
    *u = row_.u_true;
    return true;
  }
  bool has_speed() const override { return true; }

 private:
  std::unique_ptr<sim::Voyage> voyage_;
  sim::VoyageRow row_;
};

/// --publish with a voyage scenario: one voyage per vessel (seed + i, the same faults), with
/// the surge speed on the speed topic.
int publish_voyages(const SimArgs& a) {
  if (!a.healthy.empty()) {
    spdlog::error("--healthy applies to the classic scenarios (paper, healthy, faults) only");
    return kExitUsage;
  }
  if (!a.output.empty()) {
    spdlog::error("sim: --publish and --output do not go together");
    return kExitUsage;
  }
  std::vector<std::uint32_t> mmsis;
  const int rc = published_mmsis(a, {}, &mmsis);
  if (rc != kExitOk) return rc;
  PublishedVessels vessels;
  for (std::size_t i = 0; i < mmsis.size(); ++i) {
    std::unique_ptr<sim::Voyage> v = make_voyage(a, a.voyage, a.seed + i);
    if (!v) return kExitUsage;
    spdlog::info("vessel MMSI {}: {} voyage '{}', {} Hz, seed {}, U0 {:.3g} m/s", mmsis[i],
                 a.vessel, a.scenario, a.rate_hz, a.seed + i, v->linearisation().u0);
    vessels.emplace_back(mmsis[i], std::make_unique<VoyageSource>(std::move(v)));
  }
  usvfdi::dds::DdsConfig dds;
  PublishOptions opt;
  if (!publish_setup(a, &dds, &opt)) return kExitConfig;
  return publish_rows(std::move(vessels), a.rate_hz, dds, opt);
}
#endif

/// --nmea --udp GROUP:PORT: the classic scenario as IEC 61162-450 datagrams, one per sample
/// ("UdPbC\0", then ROT, RSA, VBW (and HDT) each after its TAG block with s:, n: and c:),
/// paced at --speed times real time. The receiver's time is the TAG c:, never the arrival.
int send_classic_udp(const SimArgs& a, const VesselModel& vessel, const SimConfig& c) {
  std::unique_ptr<Simulator> sim;
  std::unique_ptr<nmea_udp::NmeaUdpSender> sender;
  nmea_udp::Endpoint to;
  try {
    sim = std::make_unique<Simulator>(c);
    to = nmea_udp::parse_endpoint(a.udp);
    sender = std::make_unique<nmea_udp::NmeaUdpSender>(to, a.udp_interface, a.udp_ttl);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  std::ostringstream lines;
  io::NmeaOutputOptions o;
  o.b2 = vessel.B(1);
  o.surge_speed = vessel.u0;
  o.heading = a.nmea_heading;
  io::NmeaSimWriter writer(lines, o);
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  SimRow row;
  std::size_t rows = 0, refused = 0;
  const bool sent = write_rows(
      [&] {
        if (!sim->next(&row)) return false;
        lines.str("");
        writer.write(row);
        std::this_thread::sleep_until(t0 + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(row.t / a.speed)));
        if (!sender->send(std::string(nmea::kIec450Header) + lines.str())) ++refused;
        return true;
      },
      &rows);
  if (!sent) return kExitFailure;
  spdlog::info(
      "sent {} samples as IEC 61162-450 datagrams (ROT, RSA, VBW with TAG times) to {}:{} "
      "(interface {}, TTL {}), vessel {}, scenario {}, {} Hz, {} s at {:g}x real time{}",
      rows, to.address, to.port, a.udp_interface.empty() ? "default" : a.udp_interface, a.udp_ttl,
      vessel.name, a.scenario, c.rate_hz, c.duration, a.speed,
      refused > 0 ? "; " + std::to_string(refused) + " refused by the system" : std::string());
  return refused > 0 ? kExitFailure : kExitOk;
}

/// The classic scenario into the --output CSV or NMEA log (a temporary file renamed at the end).
int write_classic(const SimArgs& a, const VesselModel& vessel, const SimConfig& c) {
  std::unique_ptr<Simulator> sim;
  try {
    sim = std::make_unique<Simulator>(c);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  const bool to_stdout = a.output == "-";
  const std::unique_ptr<io::OutputFile> output = open_output(a.output);
  if (output == nullptr) return kExitOutput;
  std::optional<io::SimCsvWriter> csv;
  std::optional<io::NmeaSimWriter> nmea;
  if (a.nmea) {
    io::NmeaOutputOptions o;
    o.b2 = vessel.B(1);
    o.surge_speed = vessel.u0;
    o.heading = a.nmea_heading;
    nmea.emplace(output->stream(), o);
  } else {
    csv.emplace(output->stream());
  }
  SimRow row;
  std::size_t rows = 0;
  const bool written = write_rows(
      [&] {
        if (!sim->next(&row)) return false;
        nmea ? nmea->write(row) : csv->write(row);
        return true;
      },
      &rows);
  if (!written) return kExitFailure;
  try {
    output->commit();
  } catch (const io::OutputError& e) {
    spdlog::error("{}", e.what());  // names the file and the system's reason
    return kExitOutput;
  }
  spdlog::info(
      "{}: {} {}, vessel {}, scenario {}, {} Hz, {} s, seed {}, {} steering, noise "
      "sigma_v {:.3g} m/s sigma_r {:.3g} rad/s",
      to_stdout ? std::string("stdout") : a.output, rows,
      a.nmea ? "samples as NMEA (ROT, RSA, VBW with TAG times)" : "rows", vessel.name, a.scenario,
      c.rate_hz, c.duration, c.seed, c.steering == Steering::kSine ? "sine" : "autopilot",
      c.sigma_v, c.sigma_r);
  for (const FaultInjection& f : c.faults) spdlog::info("  fault {}", io::format_fault_spec(f));
  if (c.faults.empty()) spdlog::info("  no faults");
  return kExitOk;
}

int run_sim(const SimArgs& a) {
  if (!is_classic(a.scenario)) return run_voyage_scenario(a);
  VesselModel vessel;
  if (!classic_vessel(a, &vessel)) return kExitUsage;
  SimConfig c;
  TargetedFaults targeted;
  if (!classic_config(a, vessel, &c, &targeted)) return kExitUsage;
#ifdef USV_FDI_APP_WITH_DDS
  if (a.publish) return publish_classic(a, vessel, c, targeted);
#endif
  if (!a.udp.empty()) {
    if (!a.nmea || !a.output.empty()) {
      spdlog::error("sim: --udp goes with --nmea and without --output");
      return kExitUsage;
    }
  } else if (a.output.empty()) {
    spdlog::error("sim: give --output FILE (or --publish, or --nmea --udp GROUP:PORT)");
    return kExitUsage;
  }
#ifdef USV_FDI_APP_WITH_DDS
  if (!targeted.empty() || !a.healthy.empty()) {
    spdlog::error("sim: MMSI@ faults and --healthy only apply with --publish");
    return kExitUsage;
  }
#else
  if (!targeted.empty()) {  // --publish and --healthy exist in a build with DDS only
    spdlog::error("sim: MMSI@ faults only apply with --publish (a build with DDS)");
    return kExitUsage;
  }
#endif
  return a.udp.empty() ? write_classic(a, vessel, c) : send_classic_udp(a, vessel, c);
}

/// --vessel, --scenario, --rate, --duration, --seed, --fault.
void add_scenario_options(CLI::App* sub, SimArgs* args) {
  std::vector<std::string> names;
  for (const VesselModel& m : shipped_vessels()) names.push_back(m.name);
  for (const std::string& n : voyage_vessel_names()) {
    if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  }
  sub->add_option("--vessel", args->vessel,
                  "vessel: a shipped model, or with a voyage scenario any hull of "
                  "`usv-fdi vessels`")
      ->check(CLI::IsMember(names))
      ->capture_default_str();
  std::vector<std::string> scenarios = {"paper", "healthy", "faults"};
  for (const std::string& n : sim::scenario_names()) scenarios.push_back(n);
  sub->add_option("--scenario", args->scenario,
                  "classic (shipped vessels, core simulator): paper: gyro bias (20,40) s, "
                  "accelerometer bias (60,80) s, sine rudder; healthy: autopilot voyage without "
                  "faults; faults: one fault of every kind on alternating sensors after the "
                  "engine has learned. Voyages (voyage simulator): hold, course (+-10 deg), "
                  "zigzag10, zigzag20, turn (turning circles), speed (throttle -30 %/+30 %), "
                  "slow (50 % throttle), voyage (all of them)")
      ->check(CLI::IsMember(scenarios))
      ->capture_default_str();
  sub->add_option("--rate", args->rate_hz, "sample rate [Hz]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--duration", args->duration, "duration [s] (default: the scenario's)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--seed", args->seed, "noise seed")->capture_default_str();
  sub->add_option("--fault", args->faults,
                  "extra fault [MMSI@]sensor:kind:start:end[:magnitude[:spike_rate]] "
                  "(e.g. gyro:bias:20:40:0.005; MMSI@ limits it to one vessel with --publish); "
                  "repeatable");
}

#ifdef USV_FDI_APP_WITH_DDS
/// --publish and the options that go with it, then the DDS options.
void add_publish_options(CLI::App* sub, SimArgs* args) {
  sub->add_flag("--publish", args->publish,
                "publish INS and rudder samples on DDS instead of writing a CSV");
  sub->add_option("--mmsi", args->mmsi,
                  "--publish: a vessel's MMSI (repeatable: one simulation per vessel, seed+i)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_option("--healthy", args->healthy,
                  "--publish: this vessel gets neither the scenario's faults nor the --fault "
                  "specs without MMSI@ (repeatable)")
      ->check(CLI::Range(1u, 999999999u));
  sub->add_flag("--reliable", args->pub.reliable,
                "--publish: RELIABLE INS and rudder writers (they match best-effort and "
                "reliable sidecars; a sidecar with reliable_inputs: true needs them)");
  sub->add_option("--wait-readers", args->pub.wait_readers,
                  "--publish: wait up to this long for a sidecar's readers before starting [s]")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--min-readers", args->pub.min_readers,
                  "--publish: start once this many INS and rudder readers (sidecars) are matched")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  sub->add_option("--linger", args->pub.linger,
                  "--publish: keep the writers this long after the last sample [s]")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  add_dds_options(sub, &args->dds);
}
#endif

}  // namespace

void register_sim_command(CommandRegistry& registry) {
  auto args = std::make_shared<SimArgs>();
  CLI::App* sub = registry.add(
      "sim",
      "Simulate a vessel with optional INS faults and write CSV rows "
      "(t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g; voyage "
      "scenarios add u and more; %.17g), or with --nmea NMEA 0183 sentences with TAG times",
      [args] { return run_sim(*args); });
  add_scenario_options(sub, args.get());
  add_voyage_options(sub, &args->voyage);
  sub->add_flag("--nmea", args->nmea,
                "write NMEA 0183 sentences instead of CSV: per sample "
                "$HEROT (r, deg/min, 3 decimals), $AGRSA (delta, deg, 3 decimals, RSA sign: > 0 "
                "bow to starboard), $VDVBW (v and the vessel's nominal u, kn, 4 decimals), each "
                "after a TAG block with c: = 2026-01-01T00:00:00Z + t (ms)");
  sub->add_flag("--nmea-heading", args->nmea_heading, "--nmea: also $HEHDT (psi, deg)");
  sub->add_option("--udp", args->udp,
                  "--nmea: send the samples as IEC 61162-450 datagrams (one per sample, TAG "
                  "times) to this multicast group or unicast address, ADDRESS:PORT (e.g. "
                  "239.192.0.1:60001), paced by --speed, instead of writing --output");
  sub->add_option("--udp-interface", args->udp_interface,
                  "--udp: the multicast interface's address (IP_MULTICAST_IF; '' : the "
                  "system's choice)")
      ->capture_default_str();
  sub->add_option("--udp-ttl", args->udp_ttl,
                  "--udp: multicast TTL (0: this host only, 1: the local network)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  sub->add_option("--speed", args->speed,
                  "--publish, --udp: data time per wall time (1 real time, 20 twenty times "
                  "faster)")
      ->check(CLI::Range(0.01, 10000.0))
      ->capture_default_str();
  sub->add_option("--steering", args->steering, "autopilot or sine (default: the scenario's)")
      ->check(CLI::IsMember({"autopilot", "sine"}));
  sub->add_option("--noise-scale", args->noise_scale,
                  "factor on the vessel's realistic sensor noise (0: noise-free)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
#ifdef USV_FDI_APP_WITH_DDS
  sub->add_option("--output", args->output, "output CSV ('-': stdout); or --publish");
  add_publish_options(sub, args.get());
#else
  sub->add_option("--output", args->output, "output CSV ('-': stdout)")->required();
#endif
}

}  // namespace usvfdi::app
