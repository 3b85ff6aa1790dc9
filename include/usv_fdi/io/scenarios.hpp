// Built-in simulation scripts of `usv-fdi sim` and the --fault SPEC syntax. Built on the
// core's public Simulator types only.
#pragma once

#include <string>
#include <vector>

#include "usv_fdi/core/simulator.hpp"

namespace usvfdi::io {

/// Time by which identification has converged and isolation has learned its scales on a
/// shipped vessel under its autopilot: max(300 s, 5 course-change periods) (Otter 300 s,
/// Mariner 600 s).
double first_fault_time(const VesselModel& vessel);

/// One fault of each kind (bias, drift, stuck, noise, spikes, scale, stale) on alternating
/// sensors (accelerometer first), each `length` long, separated by healthy `gap`s, from t0.
/// Magnitudes in units of the vessel's noise: bias 10 sigma, drift 20 sigma over 30 s,
/// noise +6 sigma, spikes 25 sigma at 2/s, scale +50 %.
std::vector<FaultInjection> every_kind_script(const VesselModel& vessel, double t0,
                                              double length = 30.0, double gap = 60.0);

/// Healthy voyage under the autopilot: first_fault_time + 300 s, no faults.
SimConfig healthy_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed);
/// every_kind_script from first_fault_time, 60 s of healthy data after the last fault.
SimConfig faults_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed);

/// Parses `sensor:kind:start:end[:magnitude[:spike_rate]]`, e.g. `gyro:bias:20:40:0.005`.
/// sensor: accelerometer|acc|a|gyro|g; kind: bias|drift|stuck|noise|spikes|scale|stale|
/// invalid. Returns false and explains why in *error.
bool parse_fault_spec(const std::string& spec, FaultInjection* out, std::string* error);
/// The SPEC text of an injection (inverse of parse_fault_spec).
std::string format_fault_spec(const FaultInjection& f);

}  // namespace usvfdi::io
