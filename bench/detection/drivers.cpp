// The detectors of the benchmark, each fed sample by sample: the engine (FdiEngine) and the
// oracle (the isolation stage alone, handed A). Kept small and apart from the run list so
// that the oracle can move onto the engine's own isolation stage once it is split out.
#include "drivers.hpp"

#include <array>
#include <cmath>
#include <cstdint>

namespace usvfdi::bench {

namespace {

/// Turns latched-state changes into alarm condition changes (raised / cleared).
class AlarmTracker {
 public:
  void on_event(const FaultEvent& e, std::vector<Alarm>* out) {
    const bool active =
        e.state == FaultState::kRaised || e.state == FaultState::kActiveAcknowledged;
    bool& was = active_[static_cast<int>(e.sensor)];
    if (active != was) out->push_back(Alarm{e.t, e.sensor, active, e.kind});
    was = active;
  }

 private:
  std::array<bool, 3> active_{false, false, false};
};

/// Detection is live: armed, settled and learned. The flags are those of the last update, so
/// the sample on which set_estimate arms (after its update) does not count yet. Each span of
/// live samples is recorded: the engine un-arms when its estimate loses convergence.
class ArmingClock {
 public:
  void after_sample(double t, const IsolatorStatus& st, MethodResult* r) {
    const bool live = armed_before_ && st.armed && !st.learning && !st.settling;
    const bool was_live = !r->live.empty() && std::isinf(r->live.back().to);
    if (live && !was_live) {
      r->live.push_back(LiveSpan{t});
      if (std::isnan(r->t_armed)) r->t_armed = t;
    } else if (!live && was_live) {
      r->live.back().to = t;
    }
    armed_before_ = st.armed;
  }

 private:
  bool armed_before_ = false;
};

/// Each new model-mismatch verdict of the isolation stage, with its reason.
class MismatchLog {
 public:
  void after_sample(double t, const IsolatorStatus& st, std::vector<MismatchVerdict>* out) {
    if (st.mismatches > seen_) out->push_back(MismatchVerdict{t, st.mismatch_reason});
    seen_ = st.mismatches;
  }

 private:
  std::uint64_t seen_ = 0;
};

}  // namespace

MethodResult run_engine(const EngineConfig& cfg, const std::vector<Sample>& samples) {
  MethodResult r;
  FdiEngine engine(cfg);
  AlarmTracker tracker;
  ArmingClock clock;
  MismatchLog verdicts;
  std::vector<FaultEvent> events;
  for (const Sample& s : samples) {
    events.clear();
    engine.process(s, &events);
    for (const FaultEvent& e : events) {
      tracker.on_event(e, &r.alarms);
      if (e.state == FaultState::kRaised || e.state == FaultState::kClearedUnacknowledged) {
        FaultEvent ack;
        if (engine.acknowledge(e.sensor, e.sequence, s.t, "bench", &ack) == AckResult::kAccepted) {
          tracker.on_event(ack, &r.alarms);
        }
      }
    }
    clock.after_sample(s.t, engine.isolation_status(), &r);
    verdicts.after_sample(s.t, engine.isolation_status(), &r.mismatches);
    ++r.samples;
    if (engine.estimate().frozen) ++r.frozen_samples;
  }
  r.has_identification = true;
  r.unarms = engine.isolation_status().unarms;
  r.A_final = engine.estimate().A;
  r.converged = engine.estimate().converged;
  return r;
}

MethodResult run_oracle(const IsolationParams& params, const Vec2& B, const Mat2& A,
                        const std::vector<Sample>& samples) {
  MethodResult r;
  Isolator iso(params, B);
  std::array<FaultLatch, 3> latches{FaultLatch(Sensor::kAccelerometer), FaultLatch(Sensor::kGyro),
                                    FaultLatch(Sensor::kUnknown)};
  Estimate est;
  est.A = A;
  est.converged = true;
  est.warming_up = false;
  est.status = IdentStatus::kConverged;
  est.excitation = 1.0;
  AlarmTracker tracker;
  ArmingClock clock;
  MismatchLog verdicts;
  std::vector<Detection> dets;
  bool given = false;
  for (const Sample& s : samples) {
    dets.clear();
    iso.update(s, &dets);
    for (const Detection& d : dets) {
      FaultLatch& latch = latches[static_cast<int>(d.sensor)];
      FaultEvent e;
      if (!latch.on_detection(d, A, &e)) continue;
      tracker.on_event(e, &r.alarms);
      if (e.state == FaultState::kRaised || e.state == FaultState::kClearedUnacknowledged) {
        FaultEvent ack;
        if (latch.acknowledge(e.sequence, s.t, "bench", &ack) == AckResult::kAccepted) {
          tracker.on_event(ack, &r.alarms);
        }
      }
    }
    if (!given) {
      est.t = s.t;
      iso.set_estimate(est);
      given = true;
    }
    clock.after_sample(s.t, iso.status(), &r);
    verdicts.after_sample(s.t, iso.status(), &r.mismatches);
    ++r.samples;
  }
  r.A_final = A;
  r.converged = true;
  return r;
}

}  // namespace usvfdi::bench
