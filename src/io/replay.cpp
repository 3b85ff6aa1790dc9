#include "usv_fdi/io/replay.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "usv_fdi/io/plausibility.hpp"

namespace usvfdi::io {

namespace {

/// One replay: the engine fed row by row, the summary it adds up and the records it writes.
class Replay {
 public:
  Replay(const EngineConfig& cfg, JsonlWriter& out, const ReplayOptions& options)
      : cfg_(cfg), out_(out), options_(options), engine_(cfg) {}

  /// Feeds one row (read from line `line` of the input) to the engine and writes what it
  /// changed: events (acknowledged at once with --auto-ack), mismatch and estimate records.
  void add(const Sample& s, std::size_t line) {
    ++sum_.samples;
    plausible_.add(s);
    events_.clear();
    const bool accepted = engine_.process(s, &events_);
    if (!accepted) count_dropped(s, line);
    for (const FaultEvent& e : events_) {
      emit(e);
      if (options_.auto_ack) acknowledge(e, s.t);
    }
    if (!std::isfinite(s.t)) return;
    if (std::isnan(first_t_)) first_t_ = s.t;
    if (std::isnan(last_t_) || s.t > last_t_) last_t_ = s.t;
    record_mismatch(s.t);
    record_estimate(s.t);
    record_signal(s.t);
  }

  /// The final estimate record and the summary's totals (the caller writes the summary).
  RunSummary& finish() {
    if (!std::isnan(last_t_)) {
      out_.estimate(last_t_, engine_.estimate(), engine_.isolation_status().armed);
    }
    sum_.final_a = to_params(engine_.estimate().A);
    sum_.converged = engine_.estimate().converged;
    sum_.frozen_samples = engine_.frozen_samples();
    sum_.unconvergences = engine_.estimate().unconvergences;
    sum_.duration_s = std::isnan(first_t_) ? 0.0 : last_t_ - first_t_;
    sum_.warnings = plausible_.warnings();
    sum_.not_converged = convergence_report(engine_.estimate(), cfg_.identification);
    return sum_;
  }

 private:
  /// A row the engine did not take: counted as a duplicate or as rejected, with the first
  /// line of each.
  void count_dropped(const Sample& s, std::size_t line) {
    if (engine_.last_was_duplicate()) {
      ++sum_.duplicates;  // the previous row once more: dropped, not an error
      if (sum_.first_duplicate_line == 0) sum_.first_duplicate_line = line;
      return;
    }
    ++sum_.rejected;
    if (!std::isfinite(s.t)) ++sum_.rejected_no_time;
    if (sum_.first_rejected_line == 0) {
      sum_.first_rejected_line = line;
      sum_.first_rejected_t = s.t;
      sum_.first_rejected_after = last_t_;
    }
  }

  void emit(const FaultEvent& e) {
    out_.event(e);
    ++sum_.events;
    // A raise is a transition into raised; a refined kind republishes raised and is no raise.
    FaultState& before = latched_[static_cast<int>(e.sensor)];
    if (e.state == FaultState::kRaised && before != FaultState::kRaised) {
      ++sum_.raised[static_cast<int>(e.sensor)];
    }
    before = e.state;
  }

  /// --auto-ack: a raised or cleared event acknowledged at once, as an attentive operator would.
  void acknowledge(const FaultEvent& e, double t) {
    if (e.state != FaultState::kRaised && e.state != FaultState::kClearedUnacknowledged) return;
    FaultEvent ack;
    if (engine_.acknowledge(e.sensor, e.sequence, t, "replay --auto-ack", &ack) ==
        AckResult::kAccepted) {
      emit(ack);
    }
  }

  /// Model mismatch: reported, counted, never a latched sensor fault.
  void record_mismatch(double t) {
    const IsolatorStatus& iso = engine_.isolation_status();
    if (iso.model_mismatch != last_mismatch_) {
      out_.mismatch(t, iso.model_mismatch, iso.mismatch_reason);
      last_mismatch_ = iso.model_mismatch;
    }
    sum_.model_mismatches = iso.mismatches;
  }

  /// An estimate record every estimate_period, and whenever convergence or arming changes.
  void record_estimate(double t) {
    const bool converged = engine_.estimate().converged;
    const bool armed = engine_.isolation_status().armed;
    if (std::isnan(last_record_) || t >= last_record_ + options_.estimate_period ||
        converged != last_converged_ || armed != last_armed_) {
      out_.estimate(t, engine_.estimate(), armed);
      last_record_ = t;
      last_converged_ = converged;
      last_armed_ = armed;
    }
  }

  /// A signal record every signal_period (none when it is 0).
  void record_signal(double t) {
    if (options_.signal_period <= 0.0) return;
    // On the grid k * signal_period (the first sample at or after each grid time): the
    // records do not drift with the samples' jitter.
    const double period = options_.signal_period;
    if (std::isnan(next_signal_) || t >= next_signal_ - 1e-6 * period) {  // round-off of k dt
      out_.signal(t, engine_.isolation_status());
      next_signal_ = (std::floor(t / period + 1e-6) + 1.0) * period;
    }
  }

  const EngineConfig& cfg_;
  JsonlWriter& out_;
  const ReplayOptions& options_;
  FdiEngine engine_;
  RunSummary sum_;
  std::vector<FaultEvent> events_;
  double first_t_ = kNaN, last_t_ = kNaN, last_record_ = kNaN, next_signal_ = kNaN;
  bool last_converged_ = false, last_armed_ = false, last_mismatch_ = false;
  PlausibilityCheck plausible_;
  FaultState latched_[3] = {FaultState::kNormal, FaultState::kNormal, FaultState::kNormal};
};

/// The replay of any reader with next(Sample*) and line() (CSV or NMEA).
template <class Reader>
RunSummary replay_from(const EngineConfig& cfg, Reader& input, JsonlWriter& out,
                       const ReplayOptions& options) {
  Replay run(cfg, out, options);
  Sample s;
  try {
    while (input.next(&s)) run.add(s, input.line());
  } catch (const InputError& e) {
    RunSummary& sum = run.finish();
    sum.complete = false;
    sum.error = e.what();
    out.summary(sum);
    out.flush();
    throw;
  }
  const RunSummary& sum = run.finish();
  out.summary(sum);
  out.flush();
  return sum;
}

}  // namespace

RunSummary replay(const EngineConfig& cfg, CsvSampleReader& input, JsonlWriter& out,
                  const ReplayOptions& options) {
  return replay_from(cfg, input, out, options);
}

RunSummary replay(const EngineConfig& cfg, NmeaSampleReader& input, JsonlWriter& out,
                  const ReplayOptions& options) {
  return replay_from(cfg, input, out, options);
}

}  // namespace usvfdi::io
