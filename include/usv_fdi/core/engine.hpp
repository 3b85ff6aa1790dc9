// The FDI engine as two stages with one wiring between them: the isolation stage (Isolator
// and the fault latches) hands every accepted sample to the identification stage with its
// freeze request and supervision flag (IdentificationInput); the identification stage (the
// delay gate and the Identifier) hands every new estimate back. FdiEngine runs them in
// sequence in one thread (replay, tests, benchmark); the service's pipeline runs each in a
// thread of its own (src/service/pipeline.cpp).
#pragma once

#include <array>
#include <deque>
#include <vector>

#include "usv_fdi/core/identification.hpp"
#include "usv_fdi/core/isolation.hpp"
#include "usv_fdi/core/latch.hpp"
#include "usv_fdi/core/speed.hpp"

namespace usvfdi {

struct EngineConfig {
  Vec2 B = Vec2::Zero();  ///< known input vector B = M^-1 B_R (the only required setting)
  IdentificationParams identification;
  IsolationParams isolation;
  SpeedParams speed;  ///< the optional speed input (core/speed.hpp)
  /// Identification consumes samples this much later than isolation, so that a fault
  /// detected within the delay never reaches the estimator [s].
  double identification_delay = 0.5;
  /// A stamp that goes back, repeats, or jumps ahead by more than this does not belong to
  /// the current time base: rejected alone, or adopted as a new base (SampleClock) [s].
  double clock_max_jump = 60.0;
  /// Consecutive samples consistent among themselves in a new time base that adopt it.
  int clock_confirm_samples = 5;

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// The source clock's time base. A stamp after the last accepted one by at most max_jump
/// is accepted. Any other (repeated, backward, far ahead) is rejected alone, unless it
/// starts a run of confirm_samples stamps that increase by at most max_jump each: that run
/// is a new time base (an INS clock that restarted at 0 or was re-set), adopted on its
/// last sample: the stages restart their filters on it. Constant memory.
class SampleClock {
 public:
  enum class Verdict : std::uint8_t { kAccept, kReject, kResync };
  SampleClock(double max_jump, int confirm) : max_jump_(max_jump), confirm_(confirm) {}
  Verdict check(double t);
  double last() const { return last_; }
  std::uint64_t resyncs() const { return resyncs_; }
  /// The time base left at the latest re-synchronisation: its last stamp [s].
  double resync_from() const { return resync_from_; }

 private:
  bool follows(double t, double after) const { return t > after && t - after <= max_jump_; }
  double max_jump_;
  int confirm_;
  double last_ = kNaN;
  double candidate_last_ = kNaN;
  int candidate_count_ = 0;
  std::uint64_t resyncs_ = 0;
  double resync_from_ = kNaN;
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

/// The one wiring from the isolation stage to the identification stage, handed over with
/// every sample the isolation stage accepted.
struct IdentificationInput {
  Sample sample;
  bool freeze = false;      ///< the detector suspects the data (Isolator::freeze_requested)
  bool supervised = false;  ///< the detector is armed and has learned (set_supervised)
  bool restart = false;     ///< a new time base begins with this sample (SampleClock)
};

/// Identification (the identification thread's part): the delay gate and the DREM
/// estimator. Each estimate it produces goes back to the isolation stage (set_estimate).
class IdentificationStage {
 public:
  explicit IdentificationStage(const EngineConfig& cfg);
  /// Takes one hand-over and feeds the estimator every sample the gate releases. Returns
  /// true when the estimate changed (hand it to IsolationStage::set_estimate).
  bool push(const IdentificationInput& in);
  const Estimate& estimate() const { return ident_.estimate(); }
  const Identifier& identifier() const { return ident_; }
  std::uint64_t frozen_samples() const { return frozen_samples_; }

 private:
  IdentificationParams params_;
  Vec2 B_;
  SpeedParams speed_;  ///< with the reference speed once known (kept over restarts)
  double delay_;
  Identifier ident_;
  IdentificationGate gate_;
  std::uint64_t frozen_samples_ = 0;
};

/// Detection, isolation and the fault latches (the isolation thread's part), with the
/// estimate of A in force.
class IsolationStage {
 public:
  explicit IsolationStage(const EngineConfig& cfg);
  /// Processes one sample; appends latched-state changes to events. Returns false when the
  /// sample was rejected (its time did not increase); else fills *handover.
  bool process(const Sample& s, std::vector<FaultEvent>* events, IdentificationInput* handover);
  /// Installs an estimate the identification stage produced.
  void set_estimate(const Estimate& est);
  /// Latches a change of condition found outside the detector (a restored fault's
  /// re-check). Returns true and fills *event when the latched state changed.
  bool apply(const Detection& d, FaultEvent* event);
  AckResult acknowledge(Sensor sensor, std::uint64_t sequence, double t, const std::string& who,
                        FaultEvent* event);
  /// Restores a persisted event (restart without loss).
  void restore(const FaultEvent& ev) { latches_[static_cast<int>(ev.sensor)].restore(ev); }

  /// The detections of the last process() call (before latching).
  const std::vector<Detection>& detections() const { return detections_; }
  const Estimate& estimate() const { return estimate_; }
  const Isolator& isolator() const { return iso_; }
  const IsolatorStatus& status() const { return iso_.status(); }
  bool freeze_requested() const { return iso_.freeze_requested(); }
  const FaultLatch& latch(Sensor s) const { return latches_[static_cast<int>(s)]; }
  const SampleClock& clock() const { return clock_; }
  /// Samples rejected for their stamp (not finite, or outside the time base).
  std::uint64_t rejected_samples() const { return rejected_; }
  /// Exact repeats of the previous accepted sample (same stamp, same values): a source or a
  /// link that delivered one sample twice. Dropped and counted; not a timing error (a
  /// second repeat of the same sample is: the source's clock stands still).
  std::uint64_t duplicate_samples() const { return duplicates_; }
  /// The last process() call dropped its sample as a duplicate.
  bool last_was_duplicate() const { return last_duplicate_; }

 private:
  /// A new time base: the detector starts afresh (its windows, observers and learned
  /// statistics belong to the old one); the latches keep their events and sequences.
  void restart(const Sample& s);

  IsolationParams params_;
  Vec2 B_;
  SpeedParams speed_;  ///< with the reference speed once known (kept over restarts)
  SampleClock clock_;
  std::uint64_t rejected_ = 0;
  std::uint64_t duplicates_ = 0;
  bool last_duplicate_ = false;
  bool repeated_ = false;  ///< last_accepted_ was repeated once already
  Sample last_accepted_{kNaN, kNaN, kNaN, kNaN};
  Isolator iso_;
  Estimate estimate_;  ///< in force (its A goes into every event)
  std::array<FaultLatch, 3> latches_{FaultLatch(Sensor::kAccelerometer), FaultLatch(Sensor::kGyro),
                                     FaultLatch(Sensor::kUnknown)};
  std::vector<Detection> detections_;
};

/// Both stages in one thread, in sequence (replay, tests, benchmark).
class FdiEngine {
 public:
  explicit FdiEngine(const EngineConfig& cfg);

  /// Processes one sample; appends latched-state changes to events. Returns false when the
  /// sample was rejected (its time did not increase).
  bool process(const Sample& s, std::vector<FaultEvent>* events);

  AckResult acknowledge(Sensor sensor, std::uint64_t sequence, double t, const std::string& who,
                        FaultEvent* event) {
    return iso_.acknowledge(sensor, sequence, t, who, event);
  }

  const Estimate& estimate() const { return ident_.estimate(); }
  const IsolatorStatus& isolation_status() const { return iso_.status(); }
  const FaultLatch& latch(Sensor s) const { return iso_.latch(s); }
  const Identifier& identifier() const { return ident_.identifier(); }
  std::uint64_t frozen_samples() const { return ident_.frozen_samples(); }
  /// Samples rejected for their stamp, and re-synchronisations of the time base.
  std::uint64_t rejected_samples() const { return iso_.rejected_samples(); }
  std::uint64_t clock_resyncs() const { return iso_.clock().resyncs(); }
  /// Exact repeats of the previous sample dropped (IsolationStage::duplicate_samples).
  std::uint64_t duplicate_samples() const { return iso_.duplicate_samples(); }
  bool last_was_duplicate() const { return iso_.last_was_duplicate(); }

 private:
  IsolationStage iso_;
  IdentificationStage ident_;
};

}  // namespace usvfdi
