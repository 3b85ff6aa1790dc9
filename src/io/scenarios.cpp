#include "usv_fdi/io/scenarios.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "usv_fdi/io/csv.hpp"

namespace usvfdi::io {

double first_fault_time(const VesselModel& vessel) {
  return std::max(300.0, 5.0 * vessel.turn_period);
}

std::vector<FaultInjection> every_kind_script(const VesselModel& vessel, double t0, double length,
                                              double gap) {
  struct K {
    FaultKind kind;
    double size;  ///< in units of the channel's sigma (scale: relative gain error)
  };
  const K kinds[] = {
      {FaultKind::kBias, 10.0}, {FaultKind::kDrift, 20.0 / 30.0}, {FaultKind::kStuck, 0.0},
      {FaultKind::kNoise, 6.0}, {FaultKind::kSpikes, 25.0},       {FaultKind::kScale, 0.5},
      {FaultKind::kStale, 0.0},
  };
  std::vector<FaultInjection> out;
  double t = t0;
  bool accel = true;
  for (const K& k : kinds) {
    FaultInjection f;
    f.sensor = accel ? Sensor::kAccelerometer : Sensor::kGyro;
    f.kind = k.kind;
    f.t_start = t;
    f.t_end = t + length;
    const double sigma = accel ? vessel.sigma_v : vessel.sigma_r;
    f.magnitude = k.kind == FaultKind::kScale ? k.size : k.size * sigma;
    f.spike_rate = 2.0;
    out.push_back(f);
    t += length + gap;
    accel = !accel;
  }
  return out;
}

SimConfig healthy_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed) {
  SimConfig c;
  c.vessel = vessel;
  c.rate_hz = rate_hz;
  c.seed = seed;
  c.steering = Steering::kAutopilot;
  c.duration = first_fault_time(vessel) + 300.0;
  return c;
}

SimConfig faults_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed) {
  SimConfig c = healthy_scenario(vessel, rate_hz, seed);
  c.faults = every_kind_script(vessel, first_fault_time(vessel));
  c.duration = c.faults.back().t_end + 60.0;
  return c;
}

bool parse_fault_spec(const std::string& spec, FaultInjection* out, std::string* error) {
  std::vector<std::string> f;
  std::size_t start = 0;
  while (true) {
    const std::size_t colon = spec.find(':', start);
    f.push_back(spec.substr(start, colon == std::string::npos ? colon : colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  const auto bad = [&](const std::string& why) {
    *error = "fault '" + spec + "': " + why +
             " (expected sensor:kind:start:end[:magnitude[:spike_rate]], e.g. "
             "gyro:bias:20:40:0.005)";
    return false;
  };
  if (f.size() < 4 || f.size() > 6) return bad("expected 4 to 6 fields");
  FaultInjection inj;
  if (f[0] == "accelerometer" || f[0] == "acc" || f[0] == "a") {
    inj.sensor = Sensor::kAccelerometer;
  } else if (f[0] == "gyro" || f[0] == "g") {
    inj.sensor = Sensor::kGyro;
  } else {
    return bad("sensor '" + f[0] + "' is not accelerometer or gyro");
  }
  if (!parse_fault_kind(f[1], &inj.kind) || inj.kind == FaultKind::kUnknown) {
    return bad("unknown kind '" + f[1] +
               "' (bias, drift, stuck, noise, spikes, scale, stale, invalid)");
  }
  const char* names[] = {"start", "end", "magnitude", "spike_rate"};
  double* targets[] = {&inj.t_start, &inj.t_end, &inj.magnitude, &inj.spike_rate};
  for (std::size_t i = 2; i < f.size(); ++i) {
    double x = 0.0;
    if (!parse_csv_number(f[i], &x) || !std::isfinite(x)) {
      return bad(std::string(names[i - 2]) + " '" + f[i] + "' is not a finite number");
    }
    *targets[i - 2] = x;
  }
  if (!(inj.t_end > inj.t_start)) return bad("end must be after start");
  if (inj.spike_rate < 0) return bad("spike_rate must be >= 0");
  *out = inj;
  return true;
}

std::string format_fault_spec(const FaultInjection& f) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s:%s:%g:%g:%g", to_string(f.sensor), to_string(f.kind),
                f.t_start, f.t_end, f.magnitude);
  std::string s = buf;
  if (f.kind == FaultKind::kSpikes) {
    std::snprintf(buf, sizeof buf, ":%g", f.spike_rate);
    s += buf;
  }
  return s;
}

}  // namespace usvfdi::io
