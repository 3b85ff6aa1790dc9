// The whole FDI pipeline in one thread, sample by sample (replay, tests, benchmark).
// The DDS service runs the same pieces in two threads: Identifier in the identification
// thread, Isolator + FaultLatch in the isolation thread.
#pragma once

#include <array>
#include <deque>
#include <vector>

#include "usv_fdi/core/identification.hpp"
#include "usv_fdi/core/isolation.hpp"
#include "usv_fdi/core/latch.hpp"

namespace usvfdi {

struct EngineConfig {
  Vec2 B = Vec2::Zero();  ///< known input vector B = M^-1 B_R (the only required setting)
  IdentificationParams identification;
  IsolationParams isolation;
  /// Identification consumes samples this much later than isolation, so that a fault
  /// detected within the delay never reaches the estimator [s].
  double identification_delay = 0.5;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// Holds samples for the identification thread and decides which to freeze: a sample of
/// time tau is frozen when a freeze was requested at any time >= tau.
class IdentificationGate {
 public:
  explicit IdentificationGate(double delay) : delay_(delay) {}
  void push(const Sample& s, bool freeze_requested);
  /// Pops the next sample old enough to be used; returns false when none is.
  bool pop(Sample* s, bool* freeze);

 private:
  double delay_;
  std::deque<Sample> q_;
  double last_freeze_t_ = -1e300;
  double newest_t_ = -1e300;
};

class FdiEngine {
 public:
  explicit FdiEngine(const EngineConfig& cfg);

  /// Processes one sample; appends latched-state changes to events. Returns false when the
  /// sample was rejected (its time did not increase).
  bool process(const Sample& s, std::vector<FaultEvent>* events);

  AckResult acknowledge(Sensor sensor, std::uint64_t sequence, double t, const std::string& who,
                        FaultEvent* event);

  const Estimate& estimate() const { return ident_.estimate(); }
  const IsolatorStatus& isolation_status() const { return iso_.status(); }
  const FaultLatch& latch(Sensor s) const { return latches_[static_cast<int>(s)]; }
  const Identifier& identifier() const { return ident_; }
  std::uint64_t frozen_samples() const { return frozen_samples_; }

 private:
  EngineConfig cfg_;
  Identifier ident_;
  Isolator iso_;
  IdentificationGate gate_;
  std::array<FaultLatch, 3> latches_{FaultLatch(Sensor::kAccelerometer), FaultLatch(Sensor::kGyro),
                                     FaultLatch(Sensor::kUnknown)};
  std::vector<Detection> detections_;
  std::uint64_t frozen_samples_ = 0;
};

}  // namespace usvfdi
