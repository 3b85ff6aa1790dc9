// usv-fdi sim --scenario <voyage>: the voyage simulator over the hulls of src/sim.
#include "sim_voyage.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "command.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/nmea_log.hpp"
#include "usv_fdi/io/scenarios.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::app {
namespace {
constexpr double kDeg = M_PI / 180.0;

/// Splits "a[:b]" into one or two finite numbers; false on anything else.
bool parse_pair(const std::string& text, double* a, double* b, bool* has_b) {
  const auto colon = text.find(':');
  double x = 0, y = 0;
  if (!io::parse_csv_number(text.substr(0, colon), &x) || !std::isfinite(x)) return false;
  *has_b = colon != std::string::npos;
  if (*has_b && (!io::parse_csv_number(text.substr(colon + 1), &y) || !std::isfinite(y))) {
    return false;
  }
  *a = x;
  if (*has_b) *b = y;
  return true;
}

struct Built {
  sim::VoyageConfig cfg;
  std::string error;
};

bool set_environment(const VoyageArgs& a, sim::EnvironmentConfig* e, std::string* why) {
  try {
    if (a.sea_state) e->sea = sim::sea_state(*a.sea_state);
  } catch (const std::invalid_argument& ex) {
    *why = std::string("--sea-state: ") + ex.what();
    return false;
  }
  if (a.wave_period) {
    if (!a.sea_state || *a.sea_state == 0) {
      *why = "--wave-period needs a --sea-state of 3 or more";
      return false;
    }
    e->sea.tp = *a.wave_period;
  }
  double x = 0, y = 0;
  bool two = false;
  if (!a.current.empty()) {
    if (!parse_pair(a.current, &x, &y, &two) || x < 0) {
      *why = "--current '" + a.current + "': expected SPEED[:SET_DEG] with SPEED >= 0 [m/s]";
      return false;
    }
    e->current = x;
    e->current_sigma = 0.2 * x;
    if (two) e->current_direction = y * kDeg;
  }
  if (!a.wind.empty()) {
    y = -1;
    if (!parse_pair(a.wind, &x, &y, &two) || (two && y < 0)) {
      *why = "--wind '" + a.wind + "': expected DEG[:GUST_DEG] (equivalent rudder, gusts >= 0)";
      return false;
    }
    e->wind = x * kDeg;
    e->wind_sigma = two ? y * kDeg : 0.5 * std::abs(x) * kDeg;
  }
  return true;
}

bool set_sensors(const VoyageArgs& a, double sv, double sr, sim::SensorConfig* s,
                 std::string* why) {
  sim::sensor_preset("ideal", sv, sr, s);
  for (const std::string& text : a.sensor) {
    if (text.find('=') == std::string::npos) {
      if (!sim::sensor_preset(text, sv, sr, s)) {
        *why = "--sensor '" + text + "': unknown preset (ideal, mems) and not key=value";
        return false;
      }
      continue;
    }
    std::string e;
    if (!sim::apply_sensor_setting(text, s, &e)) {
      *why = "--sensor " + e;
      return false;
    }
  }
  return true;
}

bool set_faults(const VoyageCommon& c, const VoyageArgs& a, const sim::Hull& hull,
                sim::VoyageConfig* cfg, std::string* why) {
  for (const std::string& spec : c.faults) {
    FaultInjection f;
    if (!io::parse_fault_spec(spec, &f, why)) return false;
    cfg->faults.push_back(f);
  }
  for (const std::string& spec : a.sigma_faults) {
    FaultInjection f;
    if (!io::parse_fault_spec(spec, &f, why)) {
      *why = "--fault-sigma: " + *why;
      return false;
    }
    cfg->faults.push_back(
        sim::sigma_fault(*cfg, f.sensor, f.kind, f.t_start, f.t_end, f.magnitude, f.spike_rate));
  }
  if (a.fault_set == "standard") {
    const double t0 = std::max(300.0, 5.0 * sim::leg_period(hull));
    const auto set = sim::standard_faults(*cfg, t0);
    cfg->faults.insert(cfg->faults.end(), set.begin(), set.end());
  }
  return true;
}

/// One pass of the legs (a turning circle counted as 4 leg periods).
double default_duration(const std::vector<sim::Leg>& legs, const sim::Hull& hull) {
  double t = 0;
  for (const sim::Leg& l : legs) {
    t += l.kind == sim::Manoeuvre::kTurn ? 4.0 * sim::leg_period(hull) : l.duration;
  }
  return t;
}

bool build(const VoyageCommon& c, const VoyageArgs& a, const sim::Hull& hull,
           sim::VoyageConfig* cfg, std::string* why) {
  cfg->rate_hz = c.rate_hz;
  cfg->seed = c.seed;
  sim::Side first = sim::Side::kStarboard;
  if (!a.side.empty() && !sim::parse_side(a.side, &first)) {
    *why = "--side '" + a.side + "': expected starboard or port";
    return false;
  }
  try {
    cfg->legs = sim::scenario_legs(c.scenario, hull, first);
  } catch (const std::invalid_argument& e) {
    *why = e.what();
    return false;
  }
  cfg->duration = c.duration ? *c.duration : default_duration(cfg->legs, hull);
  // The channels' realistic sigma (that of the shipped vessels) is the unit of fault
  // magnitudes, whatever --noise-scale does to the white noise.
  const double sv = otter().sigma_v, sr = otter().sigma_r;
  cfg->sigma_v = sv;
  cfg->sigma_r = sr;
  if (!set_environment(a, &cfg->environment, why)) return false;
  if (!set_sensors(a, c.noise_scale * sv, c.noise_scale * sr, &cfg->sensors, why)) return false;
  if (!a.dither.empty()) {
    double amp = 0, period = 0;
    bool two = false;
    if (!parse_pair(a.dither, &amp, &period, &two) || amp < 0 || (two && period <= 0)) {
      *why = "--dither '" + a.dither + "': expected DEG[:PERIOD_S], DEG >= 0, PERIOD > 0";
      return false;
    }
    cfg->autopilot.dither = amp * kDeg;
    if (two) cfg->autopilot.dither_period = period;
  }
  return set_faults(c, a, hull, cfg, why);
}
}  // namespace

bool VoyageArgs::any() const {
  return sea_state || wave_period || !current.empty() || !wind.empty() || !sensor.empty() ||
         !fault_set.empty() || !sigma_faults.empty() || !dither.empty() || !side.empty();
}

std::vector<std::string> voyage_vessel_names() { return sim::voyage_hull_names(); }

std::shared_ptr<const sim::Hull> find_voyage_hull(const std::string& name) {
  return sim::voyage_hull(name);
}

void add_voyage_options(CLI::App* sub, VoyageArgs* a) {
  sub->add_option("--sea-state", a->sea_state,
                  "voyages: first-order wave motion of sea state 0 (calm), 3, 4, 5 or 6");
  sub->add_option("--wave-period", a->wave_period,
                  "voyages: peak period [s] (default: the sea state's)")
      ->check(CLI::Range(2.0, 30.0));
  sub->add_option("--current", a->current,
                  "voyages: current SPEED[:SET_DEG] [m/s], slowly varying (20 % Gauss-Markov, "
                  "drifting set; SET from the initial course, default 90)");
  sub->add_option("--wind", a->wind,
                  "voyages: wind yaw moment and sway force as an equivalent rudder DEG[:GUST_DEG] "
                  "(gusts: Gauss-Markov, default half the mean)");
  sub->add_option("--sensor", a->sensor,
                  "voyages: sensor preset (ideal, mems) or KEY=VALUE (e.g. gyro.gm=2.5e-4, "
                  "gyro.bias_rw=1e-5, rot=nmea, rudder.bias=0.5deg, rudder.lag=0.2, acc.digits=3, "
                  "jitter=0.002, drop=0.01, duplicate=0.002); repeatable, applied in order");
  sub->add_option("--fault-set", a->fault_set,
                  "voyages: standard = bias 10 sigma, stuck, drift 10 sigma/30 s, noise x8, "
                  "scale +50 %, spikes 25 sigma, stale, invalid, alternating sensors, 30 s each "
                  "every 90 s from max(300 s, 5 leg periods) to the end")
      ->check(CLI::IsMember({"standard"}));
  sub->add_option("--fault-sigma", a->sigma_faults,
                  "voyages: a fault like --fault with its magnitude in units of the channel's "
                  "sigma (scale: relative); repeatable");
  sub->add_option("--dither", a->dither, "voyages: rudder dither DEG[:PERIOD_S] (a sine)");
  sub->add_option("--side", a->side,
                  "voyages: side of the first zigzag execute and of the first turning circle "
                  "(starboard, default, or port)");
}

std::unique_ptr<sim::Voyage> make_voyage(const VoyageCommon& c, const VoyageArgs& a,
                                         std::uint64_t seed, sim::VoyageConfig* cfg_out) {
  const auto hull = find_voyage_hull(c.vessel);
  if (!hull) {
    spdlog::error("--vessel '{}': no such hull", c.vessel);
    return nullptr;
  }
  VoyageCommon seeded = c;
  seeded.seed = seed;
  sim::VoyageConfig cfg;
  std::string why;
  if (!build(seeded, a, *hull, &cfg, &why)) {
    spdlog::error("sim: {}", why);
    return nullptr;
  }
  if (cfg_out != nullptr) *cfg_out = cfg;
  try {
    return std::make_unique<sim::Voyage>(hull, cfg);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return nullptr;
  }
}

int run_voyage_sim(const VoyageCommon& c, const VoyageArgs& a) {
  sim::VoyageConfig cfg;
  std::unique_ptr<sim::Voyage> voyage = make_voyage(c, a, c.seed, &cfg);
  if (!voyage) return kExitUsage;
  const auto hull = find_voyage_hull(c.vessel);
  std::ofstream file;
  const bool to_stdout = c.output == "-";
  if (!to_stdout) {
    file.open(c.output, std::ios::binary | std::ios::trunc);
    if (!file) {
      spdlog::error("{}: cannot open for writing", c.output);
      return kExitOutput;
    }
  }
  std::ostream& os = to_stdout ? std::cout : file;
  const sim::Linearisation& lin = voyage->linearisation();
  std::optional<sim::VoyageCsvWriter> csv;
  std::optional<io::NmeaSimWriter> nmea;
  if (c.nmea) {
    io::NmeaOutputOptions o;
    o.b2 = lin.B(1);  // the sign of delta that a replay with this hull's B reads back
    o.surge_speed = lin.u0;
    o.heading = c.nmea_heading;
    nmea.emplace(os, o);
  } else {
    csv.emplace(os, cfg.sensors);
  }
  sim::VoyageRow row;
  std::size_t rows = 0;
  const bool written = write_rows(
      [&] {
        if (!voyage->next(&row)) return false;
        nmea ? nmea->write(row.t, row.v, row.r, row.delta, row.psi, row.u_true) : csv->write(row);
        return true;
      },
      &rows);
  if (!written) return kExitFailure;
  os.flush();
  if (!os) {
    spdlog::error("{}: write failed", c.output);
    return kExitOutput;
  }
  spdlog::info("{}: {} {}, hull {} ({}), scenario {}, {} Hz, {} s, seed {}, U0 {:.3g} m/s",
               to_stdout ? std::string("stdout") : c.output, rows,
               c.nmea ? "samples as NMEA (ROT, RSA, VBW with TAG times)" : "rows", hull->name(),
               hull->nonlinear() ? "nonlinear" : "linear", c.scenario, cfg.rate_hz, cfg.duration,
               cfg.seed, lin.u0);
  spdlog::info("  linearised B = [{:.6g}, {:.6g}], A = [{:.6g}, {:.6g}, {:.6g}, {:.6g}]", lin.B(0),
               lin.B(1), lin.A(0, 0), lin.A(0, 1), lin.A(1, 0), lin.A(1, 1));
  spdlog::info("  sea state {} (Hs {} m, Tp {} s), current {} m/s, wind {:.3g} deg",
               cfg.environment.sea.code, cfg.environment.sea.hs, cfg.environment.sea.tp,
               cfg.environment.current, cfg.environment.wind / kDeg);
  for (const FaultInjection& f : cfg.faults) spdlog::info("  fault {}", io::format_fault_spec(f));
  if (cfg.faults.empty()) spdlog::info("  no faults");
  return kExitOk;
}

}  // namespace usvfdi::app
