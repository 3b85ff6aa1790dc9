#include "usv_fdi/io/replay.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "usv_fdi/io/plausibility.hpp"

namespace usvfdi::io {

RunSummary replay(const EngineConfig& cfg, CsvSampleReader& input, JsonlWriter& out,
                  const ReplayOptions& options) {
  FdiEngine engine(cfg);
  RunSummary sum;
  std::vector<FaultEvent> events;
  double first_t = kNaN, last_t = kNaN, last_record = kNaN;
  bool last_converged = false, last_armed = false;
  PlausibilityCheck plausible;
  FaultState latched[3] = {FaultState::kNormal, FaultState::kNormal, FaultState::kNormal};

  const auto emit = [&](const FaultEvent& e) {
    out.event(e);
    ++sum.events;
    // A raise is a transition into raised; a refined kind republishes raised and is no raise.
    FaultState& before = latched[static_cast<int>(e.sensor)];
    if (e.state == FaultState::kRaised && before != FaultState::kRaised) {
      ++sum.raised[static_cast<int>(e.sensor)];
    }
    before = e.state;
  };
  const auto finish = [&] {
    if (!std::isnan(last_t)) {
      out.estimate(last_t, engine.estimate(), engine.isolation_status().armed);
    }
    sum.final_a = to_params(engine.estimate().A);
    sum.converged = engine.estimate().converged;
    sum.frozen_samples = engine.frozen_samples();
    sum.duration_s = std::isnan(first_t) ? 0.0 : last_t - first_t;
    sum.warnings = plausible.warnings();
    sum.not_converged = convergence_report(engine.estimate(), cfg.identification);
  };

  bool last_mismatch = false;
  Sample s;
  try {
    while (input.next(&s)) {
      ++sum.samples;
      plausible.add(s);
      events.clear();
      const bool accepted = engine.process(s, &events);
      if (!accepted && engine.last_was_duplicate()) {
        ++sum.duplicates;  // the previous row once more: dropped, not an error
        if (sum.first_duplicate_line == 0) sum.first_duplicate_line = input.line();
      } else if (!accepted) {
        ++sum.rejected;
        if (!std::isfinite(s.t)) ++sum.rejected_no_time;
        if (sum.first_rejected_line == 0) {
          sum.first_rejected_line = input.line();
          sum.first_rejected_t = s.t;
          sum.first_rejected_after = last_t;
        }
      }
      for (const FaultEvent& e : events) {
        emit(e);
        if (options.auto_ack &&
            (e.state == FaultState::kRaised || e.state == FaultState::kClearedUnacknowledged)) {
          FaultEvent ack;
          if (engine.acknowledge(e.sensor, e.sequence, s.t, "replay --auto-ack", &ack) ==
              AckResult::kAccepted) {
            emit(ack);
          }
        }
      }
      if (!std::isfinite(s.t)) continue;
      if (std::isnan(first_t)) first_t = s.t;
      if (std::isnan(last_t) || s.t > last_t) last_t = s.t;
      const IsolatorStatus& iso = engine.isolation_status();
      if (iso.model_mismatch != last_mismatch) {
        // Model mismatch: reported, counted, never a latched sensor fault.
        out.mismatch(s.t, iso.model_mismatch, iso.mismatch_reason);
        last_mismatch = iso.model_mismatch;
      }
      sum.model_mismatches = iso.mismatches;
      const bool converged = engine.estimate().converged;
      const bool armed = iso.armed;
      if (std::isnan(last_record) || s.t >= last_record + options.estimate_period ||
          converged != last_converged || armed != last_armed) {
        out.estimate(s.t, engine.estimate(), armed);
        last_record = s.t;
        last_converged = converged;
        last_armed = armed;
      }
    }
  } catch (const InputError& e) {
    finish();
    sum.complete = false;
    sum.error = e.what();
    out.summary(sum);
    out.flush();
    throw;
  }
  finish();
  out.summary(sum);
  out.flush();
  return sum;
}

}  // namespace usvfdi::io
