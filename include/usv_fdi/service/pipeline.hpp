// The service's threads, without the middleware (DESIGN.md section 6):
//   listeners -> input queue -> isolation thread (assembles samples, observers, decision,
//   latch, acks) -> identification queue -> identification thread (DREM, publishes estimate
//   snapshots back to the isolation thread) ; isolation thread -> output queue -> publisher
//   thread (hands events and status to the sink, so a slow writer never blocks isolation).
// Overflow policy: every queue drops its oldest element when full and counts the drop.
#pragma once

#include <atomic>
#include <climits>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/service/bounded_queue.hpp"

namespace usvfdi {

struct InsInput {
  double stamp = kNaN;  ///< source time [s]
  double v = kNaN;      ///< [m/s]
  double r = kNaN;      ///< [rad/s]
  bool v_valid = true;
  bool r_valid = true;
};

struct RudderInput {
  double stamp = kNaN;  ///< source time [s]
  double delta = kNaN;  ///< [rad]
  bool valid = true;
};

struct AckInput {
  Sensor sensor = Sensor::kUnknown;
  std::uint64_t sequence = 0;
  std::string who;
};

/// Pairs INS samples with the rudder angle at the same source time: linear interpolation
/// between the rudder samples around it; when no later rudder sample arrives within
/// rudder_wait (source time), the last one is held if it is younger than rudder_timeout,
/// else delta is missing (NaN) and the FDI pauses. INS samples are re-ordered by stamp
/// inside the wait.
class SampleAssembler {
 public:
  SampleAssembler(double rudder_wait, double rudder_timeout)
      : wait_(rudder_wait), timeout_(rudder_timeout) {}
  void add_ins(const InsInput& s);
  void add_rudder(const RudderInput& s);
  /// Appends the samples that are ready; flush = true releases everything.
  void drain(std::vector<Sample>* out, bool flush = false);
  std::size_t pending() const { return ins_.size(); }

 private:
  double delta_at(double t) const;
  double wait_, timeout_;
  std::deque<InsInput> ins_;        ///< sorted by stamp
  std::deque<RudderInput> rudder_;  ///< valid rudder samples, sorted by stamp
  double newest_ins_ = -1e300;
};

struct PipelineOptions {
  std::size_t input_capacity = 4096;   ///< listener -> isolation thread
  std::size_t ident_capacity = 16384;  ///< isolation -> identification thread
  std::size_t output_capacity = 4096;  ///< isolation -> publisher thread
  double rudder_wait = 0.1;            ///< [s, source time]
  double rudder_timeout = 0.5;         ///< [s, source time]
  double input_timeout = 1.0;          ///< INS silent this long (wall clock): stale [s]
  double status_period = 1.0;          ///< FdiStatus period (wall clock) [s]
  double snapshot_period = 0.2;        ///< estimate snapshots (source time) [s]
  /// stop(): events and status still queued for the sink are handed over for at most this
  /// long (wall clock); what is left after it is dropped and counted (dropped_output) [s].
  double stop_drain_timeout = 0.5;
  /// Blocking mode: the isolation thread waits for the identification thread after each
  /// sample, so results do not depend on scheduling (replay at full speed, tests).
  bool lockstep = false;
  /// Operators allowed to acknowledge (empty: anyone who can write the ack topic).
  std::vector<std::string> authorised_operators;
};

/// What the status topic reports.
struct PipelineStatus {
  double stamp = kNaN;  ///< source time of the last sample
  Estimate estimate;
  IsolatorStatus isolation;
  std::uint64_t samples = 0;         ///< samples assembled
  std::uint64_t dropped_inputs = 0;  ///< input queue overflow
  std::uint64_t dropped_ident = 0;   ///< identification queue overflow
  std::uint64_t dropped_output = 0;  ///< output queue overflow, and events left at stop()
  std::uint64_t rejected = 0;        ///< samples the engine refused (time not increasing)
  bool ins_silent = false;           ///< no INS sample for input_timeout
  bool rudder_missing = false;       ///< the last sample had no rudder angle
};

class FdiPipeline {
 public:
  using EventSink = std::function<void(const FaultEvent&)>;
  using StatusSink = std::function<void(const PipelineStatus&)>;
  /// level: 0 debug, 1 info, 2 warning, 3 error.
  using LogSink = std::function<void(int level, const std::string&)>;

  /// Throws std::invalid_argument on a bad configuration.
  FdiPipeline(const EngineConfig& cfg, const PipelineOptions& opt, EventSink on_event,
              StatusSink on_status, LogSink on_log);
  ~FdiPipeline();
  FdiPipeline(const FdiPipeline&) = delete;
  FdiPipeline& operator=(const FdiPipeline&) = delete;

  /// Restores latched events (restart without loss); call before start(). Each one is
  /// re-published on start with its sequence.
  void restore(const FaultEvent& ev);

  void start();
  /// Shuts the queues down in order and joins every thread. Idempotent.
  void stop();

  // Called from middleware listeners: copy into the input queue, never block.
  bool push_ins(const InsInput& s) { return input_.push(s); }
  bool push_rudder(const RudderInput& s) { return input_.push(s); }
  bool push_ack(const AckInput& a) { return input_.push(a); }

  PipelineStatus status() const;

 private:
  using Input = std::variant<InsInput, RudderInput, AckInput>;
  using Output = std::variant<FaultEvent, PipelineStatus>;
  struct IdentItem {
    Sample s;
    bool freeze = false;
  };

  void isolation_loop();
  void identification_loop();
  void publisher_loop();
  void process(const Sample& s);
  void emit(const FaultEvent& ev);
  void handle_ack(const AckInput& a);
  void log(int level, const std::string& msg) const;
  PipelineStatus make_status() const;

  EngineConfig cfg_;
  PipelineOptions opt_;
  EventSink on_event_;
  StatusSink on_status_;
  LogSink on_log_;

  BoundedQueue<Input> input_;
  BoundedQueue<IdentItem> ident_q_;
  BoundedQueue<Output> output_;

  // Isolation thread state.
  Isolator iso_;
  std::array<FaultLatch, 3> latches_{FaultLatch(Sensor::kAccelerometer), FaultLatch(Sensor::kGyro),
                                     FaultLatch(Sensor::kUnknown)};
  SampleAssembler assembler_;
  std::vector<FaultEvent> restored_;
  double last_t_ = kNaN;
  std::uint64_t seen_version_ = 0;
  Estimate iso_estimate_;

  // Identification thread state.
  Identifier ident_;
  IdentificationGate gate_;

  // Shared, under snap_m_.
  mutable std::mutex snap_m_;
  Estimate snapshot_;
  std::uint64_t snapshot_version_ = 0;
  PipelineStatus last_status_;

  std::atomic<std::uint64_t> samples_{0}, rejected_{0};
  // Lockstep bookkeeping, under step_m_.
  std::mutex step_m_;
  std::condition_variable step_cv_;
  std::uint64_t ident_pushed_ = 0, ident_done_ = 0;
  std::atomic<bool> ins_silent_{false};
  /// Set by stop() before the output queue shuts down: the publisher thread drops (and
  /// counts) what it cannot hand over before this steady_clock time (ns since its epoch).
  std::atomic<std::int64_t> drain_deadline_ns_{INT64_MAX};
  std::atomic<std::uint64_t> dropped_at_stop_{0};
  std::thread iso_thread_, ident_thread_, pub_thread_;
  bool started_ = false, stopped_ = false;
};

}  // namespace usvfdi
