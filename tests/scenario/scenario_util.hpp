// Helpers for the seeded scenario tests: run the simulator through the engine and score
// every injected fault against the events.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/simulator.hpp"

namespace usvfdi::scenario {

struct RunResult {
  std::vector<FaultEvent> events;   ///< every latched-state change
  std::vector<Estimate> estimates;  ///< one per second
  double t_armed = kNaN;
  IsolatorStatus final_status;
  Estimate final_estimate;
};

/// Called after every sample the engine processed, with that sample and the engine.
using EachSample = std::function<void(const SimRow&, const FdiEngine&)>;

inline RunResult run(const SimConfig& sim, const EngineConfig& cfg,
                     const EachSample& each = nullptr) {
  RunResult out;
  FdiEngine engine(cfg);
  Simulator simulator(sim);
  SimRow row;
  double next_estimate = 0.0;
  std::vector<FaultEvent> events;
  while (simulator.next(&row)) {
    events.clear();
    engine.process(Sample{row.t, row.v, row.r, row.delta}, &events);
    for (FaultEvent& e : events) {
      // Acknowledge every event at once, as an attentive operator would: the latch then
      // returns to normal when the condition clears and the next fault raises afresh.
      FaultEvent ack;
      if (e.state == FaultState::kRaised || e.state == FaultState::kClearedUnacknowledged) {
        out.events.push_back(e);
        engine.acknowledge(e.sensor, e.sequence, row.t, "test", &ack);
      } else {
        out.events.push_back(e);
      }
    }
    if (std::isnan(out.t_armed) && engine.isolation_status().armed) out.t_armed = row.t;
    if (each) each(row, engine);
    if (row.t >= next_estimate) {
      out.estimates.push_back(engine.estimate());
      next_estimate += 1.0;
    }
  }
  out.final_status = engine.isolation_status();
  out.final_estimate = engine.estimate();
  return out;
}

/// A transition into "raised" (not the re-published record of a refined kind).
inline bool is_raise(const FaultEvent& e) {
  return e.state == FaultState::kRaised && e.message.rfind("kind refined", 0) != 0;
}
/// A transition out of an active state (not the record of an acknowledgement).
inline bool is_clear(const FaultEvent& e) {
  return (e.state == FaultState::kClearedUnacknowledged || e.state == FaultState::kAcknowledged) &&
         e.message.rfind("acknowledged by", 0) != 0;
}

/// How one injected fault was seen.
struct FaultScore {
  FaultInjection fault;
  bool detected = false;                 ///< a raise on any sensor within the fault window (+grace)
  bool isolated = false;                 ///< the first raise named the right sensor
  FaultKind kind = FaultKind::kUnknown;  ///< kind of the first raise
  double delay = kNaN;                   ///< first raise - onset [s]
  double recovery = kNaN;                ///< clear of that raise - fault end [s]
  /// Raises of the faulty sensor within the window (+grace): 1 when one fault is one event
  /// (a raise, clear and raise again while the fault lasts is a flicker).
  int raises = 0;
  /// Raises of the other sensor or of "unknown" within the window (+grace): misisolations.
  int misisolations = 0;
  /// The faulty sensor's condition cleared before the fault ended (while it was still there).
  bool early_clear = false;
};

inline std::vector<FaultScore> score(const SimConfig& sim, const RunResult& r, double grace = 2.0) {
  std::vector<FaultScore> scores;
  for (const FaultInjection& f : sim.faults) {
    FaultScore s;
    s.fault = f;
    for (const FaultEvent& e : r.events) {
      if (!is_raise(e) || e.t < f.t_start || e.t > f.t_end + grace) continue;
      if (e.sensor == f.sensor) {
        ++s.raises;
      } else {
        ++s.misisolations;
      }
    }
    for (const FaultEvent& e : r.events) {
      if (!is_raise(e)) continue;
      if (e.t < f.t_start || e.t > f.t_end + grace) continue;
      s.detected = true;
      s.isolated = e.sensor == f.sensor;
      s.kind = e.kind;
      for (const FaultEvent& u : r.events)
        if (u.sensor == e.sensor && u.t > e.t && u.t <= f.t_end + grace &&
            u.message.rfind("kind refined", 0) == 0)
          s.kind = u.kind;
      s.delay = e.t - f.t_start;
      for (const FaultEvent& c : r.events) {
        if (c.sensor == e.sensor && c.t > e.t && is_clear(c)) {
          s.recovery = c.t - f.t_end;
          break;
        }
      }
      break;
    }
    // The first clear of the faulty sensor after its first raise comes after the fault ended
    // (1e-9: a condition that ends with the fault's last sample clears at the fault's end).
    s.early_clear = s.detected && s.isolated && s.recovery < -1e-9;
    scores.push_back(s);
  }
  return scores;
}

/// Raises that no injected fault explains (outside every fault window + grace).
inline std::vector<FaultEvent> false_alarms(const SimConfig& sim, const RunResult& r,
                                            double grace = 10.0) {
  std::vector<FaultEvent> out;
  for (const FaultEvent& e : r.events) {
    if (e.state != FaultState::kRaised) continue;
    bool explained = false;
    for (const FaultInjection& f : sim.faults) {
      if (e.t >= f.t_start && e.t <= f.t_end + grace) explained = true;
    }
    if (!explained) out.push_back(e);
  }
  return out;
}

/// One fault of every kind on each sensor, spaced by healthy gaps, starting at t0.
inline std::vector<FaultInjection> every_kind(const VesselModel& v, double t0, double length,
                                              double gap) {
  const double sv = v.sigma_v, sr = v.sigma_r;
  struct K {
    FaultKind kind;
    double mag_sigmas;  // in units of the channel's noise (scale: relative gain)
  };
  const std::vector<K> kinds = {
      {FaultKind::kBias, 10.0}, {FaultKind::kDrift, 20.0 / 30.0}, {FaultKind::kStuck, 0.0},
      {FaultKind::kNoise, 6.0}, {FaultKind::kSpikes, 25.0},       {FaultKind::kScale, 0.5},
      {FaultKind::kStale, 0.0}, {FaultKind::kInvalid, 0.0},
  };
  std::vector<FaultInjection> out;
  double t = t0;
  for (const K& k : kinds) {
    for (Sensor s : {Sensor::kAccelerometer, Sensor::kGyro}) {
      const double sigma = s == Sensor::kAccelerometer ? sv : sr;
      FaultInjection f;
      f.sensor = s;
      f.kind = k.kind;
      f.t_start = t;
      f.t_end = t + length;
      f.magnitude = k.kind == FaultKind::kScale ? k.mag_sigmas : k.mag_sigmas * sigma;
      f.spike_rate = 2.0;
      out.push_back(f);
      t += length + gap;
    }
  }
  return out;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace usvfdi::scenario
