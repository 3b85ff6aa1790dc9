// The detectors of the detection benchmark, each run over a whole sample stream: the engine
// as a user runs it, and the oracle (docs/benchmark.md). Every raised or cleared event is
// acknowledged at once, so that each latch can raise again; the result is the list of alarm
// condition changes that scoring.hpp judges.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scoring.hpp"
#include "usv_fdi/core/engine.hpp"

namespace usvfdi::bench {

/// A model-mismatch verdict of the isolation stage: when, and the reason it gave.
struct MismatchVerdict {
  double t = kNaN;
  std::string reason;
};

struct MethodResult {
  std::vector<Alarm> alarms;
  std::vector<MismatchVerdict> mismatches;  ///< in time order
  /// First sample at which detection was live (armed, settled, learned); NaN: never.
  double t_armed = kNaN;
  /// Every span during which detection was live, the first from t_armed (the engine un-arms
  /// when its estimate loses convergence, and arms again).
  std::vector<LiveSpan> live;
  /// Times the engine un-armed detection because its estimate lost convergence
  /// (IsolatorStatus::unarms at the end; 0 for the oracle).
  std::uint64_t unarms = 0;
  Mat2 A_final = Mat2::Zero();
  bool converged = false;  ///< the estimate said so at the end
  /// Samples of the run, and those on which identification was frozen (the estimate said so;
  /// the oracle has no identification: has_identification false).
  std::size_t samples = 0, frozen_samples = 0;
  bool has_identification = false;
  RunScore score;  ///< filled by the caller (run_case) from the alarms
};

/// The oracle: the engine's isolation stage (Isolator + FaultLatch, default IsolationParams)
/// given a converged Estimate with A_ref from the first sample on.
MethodResult run_oracle(const IsolationParams& params, const Vec2& B, const Mat2& A,
                        const std::vector<Sample>& samples);
/// The engine (FdiEngine) with cfg, every event acknowledged at once.
MethodResult run_engine(const EngineConfig& cfg, const std::vector<Sample>& samples);

}  // namespace usvfdi::bench
