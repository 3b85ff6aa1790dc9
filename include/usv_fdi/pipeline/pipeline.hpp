// The service's threads, without the middleware (docs/design.md section 6):
//   listeners -> input queue -> isolation thread (assembles samples, observers, decision,
//   latch, acks) -> identification queue -> identification thread (DREM, publishes estimate
//   snapshots back to the isolation thread) ; isolation thread -> output queue -> publisher
//   thread (hands events and status to the sink, so a slow writer never blocks isolation).
// Operator acknowledgements have a bounded queue of their own: the isolation thread takes
// them only when no sensor sample is waiting, so a flood of acks can neither delay nor
// re-order sensor processing; refused acks are counted and logged with a rate limit (the
// first few of an ack_log_period in full, then one summary line with counts and an example).
// Overflow policy: every queue drops its oldest element when full and counts the drop; the
// latest state of every fault instance still reaches the sink after an output overflow.
// Input problems (bad stamps, invalid values, gaps, re-ordering, overflow, silent streams) are
// counted, flagged in the status and logged once per status period with an example.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
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
#include "usv_fdi/pipeline/bounded_queue.hpp"

namespace usvfdi::pipeline {

struct InsInput {
  double stamp = kNaN;  ///< source time [s]
  double v = kNaN;      ///< [m/s]
  double r = kNaN;      ///< [rad/s]
  bool v_valid = true;
  bool r_valid = true;
  std::uint64_t seq = 0;  ///< the source's sample number (InsSample.seq); 0: not numbered
  /// Surge speed [m/s] where the source gives it with the sample (NMEA); NaN: the speed
  /// stream's (SpeedInput), if any.
  double u = kNaN;
};

/// The optional surge speed (SpeedSample), any rate: each INS sample takes the speed sample
/// nearest to it in source time, within speed_max_age.
struct SpeedInput {
  double stamp = kNaN;  ///< source time [s]
  double u = kNaN;      ///< [m/s]
  bool valid = true;
};

struct RudderInput {
  double stamp = kNaN;  ///< source time [s]
  double delta = kNaN;  ///< [rad]
  bool valid = true;
  std::uint64_t seq = 0;  ///< the source's sample number (RudderSample.seq); 0: not numbered
};

struct AckInput {
  Sensor sensor = Sensor::kUnknown;
  std::uint64_t sequence = 0;
  std::string who;
  std::uint64_t incarnation = 0;  ///< FaultEvent::incarnation of the acknowledged event
};

/// Pairs INS samples with the rudder angle at the same source time: linear interpolation
/// between the rudder samples around it when both are within rudder_timeout (a longer gap
/// is not bridged: the near side is held, else nothing); when no later rudder sample
/// arrives within rudder_wait, both of source time and of wall-clock time since the INS
/// sample arrived (a replay faster than real time leaves little wall time between stamps,
/// and a rudder sample a few milliseconds late in the network must not be taken for a
/// missing one), the last one is held if it is younger than rudder_timeout, else delta is
/// missing (NaN) and the FDI pauses. INS samples are re-ordered by stamp inside the wait;
/// samples with a non-finite stamp are ignored (the pipeline counts them before).
class SampleAssembler {
 public:
  /// wall_wait: the wall-clock part of the wait [s] (0: source time only); speed_max_age:
  /// the largest distance in source time between an INS sample and the speed it takes [s].
  SampleAssembler(double rudder_wait, double rudder_timeout, double wall_wait = 0.0,
                  double speed_max_age = 2.0)
      : wait_(rudder_wait),
        timeout_(rudder_timeout),
        wall_wait_(wall_wait),
        speed_max_age_(speed_max_age) {}
  /// arrival: when the sample arrived, on any monotonic wall clock [s].
  void add_ins(const InsInput& s, double arrival = 0.0);
  void add_rudder(const RudderInput& s);
  /// A valid speed sample with a finite stamp and speed. Once one has come, an INS sample
  /// also waits (as for its rudder angle) for a speed sample at or after its stamp, unless
  /// the newest is more than speed_max_age older (the stream has stopped).
  void add_speed(const SpeedInput& s);
  /// Appends the samples that are ready at wall-clock time `now` (the clock of add_ins);
  /// flush = true releases everything.
  void drain(std::vector<Sample>* out, bool flush = false, double now = 0.0);
  std::size_t pending() const { return ins_.size(); }
  /// The engine's time base is now at t (it re-synchronised, or rejected a stamp): samples
  /// more than span away from it are dropped, so that they neither hold the others back
  /// nor push the new base's rudder samples out.
  void rebase(double t, double span);

 private:
  struct PendingIns {
    InsInput s;
    double arrival;
  };
  double delta_at(double t) const;
  double speed_at(double t) const;
  double wait_, timeout_, wall_wait_, speed_max_age_;
  std::deque<PendingIns> ins_;      ///< sorted by stamp
  std::deque<RudderInput> rudder_;  ///< valid rudder samples, sorted by stamp
  std::deque<SpeedInput> speed_;    ///< valid speed samples, sorted by stamp
  double newest_ins_ = -1e300;
};

struct PipelineOptions {
  std::size_t input_capacity = 4096;   ///< listener -> isolation thread (INS, rudder)
  std::size_t ack_capacity = 64;       ///< listener -> isolation thread (acks; oldest dropped)
  std::size_t ident_capacity = 16384;  ///< isolation -> identification thread
  std::size_t output_capacity = 4096;  ///< isolation -> publisher thread
  double rudder_wait = 0.1;            ///< [s, source time and wall clock]
  double rudder_timeout = 0.5;         ///< [s, source time]
  /// An INS sample takes the speed sample nearest in source time within this [s]; none
  /// there: the engine holds the last speed ratio (core/speed.hpp).
  double speed_max_age = 2.0;
  /// Surge speeds beyond this are dropped as absurd (counted as invalid values) [m/s].
  double max_abs_u = 50.0;
  double input_timeout = 1.0;  ///< INS silent this long (wall clock): stale [s]
  double status_period = 1.0;  ///< FdiStatus period (wall clock) [s]
  /// A fault restored at start (raised or active-acknowledged) whose sensor-level condition
  /// (stale, stuck, invalid) is no longer seen for this long is cleared [s, source time];
  /// a residual fault once the re-armed detector has learned and sees none.
  double restore_recheck = 5.0;
  /// stop(): events and status still queued for the sink are handed over for at most this
  /// long (wall clock); what is left after it is dropped and counted (dropped_output) [s].
  double stop_drain_timeout = 0.5;
  /// Before each sample the isolation thread takes the estimate that the identification
  /// thread made from all the earlier samples, as the offline replay does (FdiEngine): the
  /// results depend on the samples alone, never on how the threads are scheduled. Waiting
  /// for it takes no time when samples arrive at their rate (identification needs about a
  /// microsecond per sample); it is bounded by this wall-clock time, after which isolation
  /// goes on with the estimate it has, logs that the identification thread lags behind, and
  /// waits again once it has caught up [s]. 0: never waits (the isolation thread takes
  /// whatever estimate is there; results then depend on scheduling).
  double estimate_wait = 5.0;
  /// Operators allowed to acknowledge (empty: anyone who can write the ack topic).
  std::vector<std::string> authorised_operators;
  /// Refused acks are logged in full 5 times per this period (wall clock) [s] at most, the
  /// others in one summary line at its end (counts by reason, an example).
  double ack_log_period = 5.0;
  /// This run's incarnation, carried by every event it issues (FaultEvent::incarnation):
  /// (incarnation, sequence) never repeats across restarts, and an ack must name the
  /// incarnation of the event it acknowledges. The sidecar sets its start time, microseconds
  /// since the Unix epoch (above every restored event's). 0: no incarnations (replay, tests):
  /// events keep theirs and acks are not checked for one.
  std::uint64_t incarnation = 0;
};

/// Input problems (PipelineStatus::input_flags). The values are those of the INPUT_*
/// constants of idl/usv_fdi.idl (FdiStatus.input_flags).
enum InputFlag : std::uint32_t {
  kInputInsSilent = 1u << 0,      ///< no INS sample for input_timeout (wall clock)
  kInputRudderMissing = 1u << 1,  ///< no usable rudder angle: identification, isolation paused
  kInputAccelUnusable = 1u << 2,  ///< accelerometer channel v stale, invalid or stuck
  kInputGyroUnusable = 1u << 3,   ///< gyro channel r stale, invalid or stuck
  // Since the previous status:
  kInputBadTimestamps = 1u << 4,  ///< stamps that repeat, go backwards or are not finite
  kInputInvalidValues = 1u << 5,  ///< NaN (flagged valid), infinite or absurd values
  kInputGaps = 1u << 6,           ///< gaps between INS samples longer than stale_timeout
  kInputReordered = 1u << 7,      ///< samples delivered out of order (re-sorted)
  kInputQueueDrops = 1u << 8,     ///< input queue overflow: oldest samples dropped
  kInputSamplesLost = 1u << 9,    ///< gaps in the sources' seq: samples lost before the sidecar
  /// Set by the DDS service, not the pipeline: another DDS writer published this vessel's
  /// FaultEvents within the last 10 s (a second sidecar with the same MMSI, or a forger).
  kInputOtherEventWriter = 1u << 10,
};

/// Why identification or isolation is paused (PipelineStatus::identification_paused,
/// isolation_paused; the PAUSE_* constants of idl/usv_fdi.idl). 0: running.
enum PauseReason : std::uint32_t {
  kPauseNotArmed = 1u << 0,       ///< isolation: A not identified yet (not armed)
  kPauseLearning = 1u << 1,       ///< isolation: observers settling / learning healthy statistics
  kPauseRudderMissing = 1u << 2,  ///< no usable rudder angle
  kPauseInsUnusable = 1u << 3,    ///< identification: an INS channel stale, invalid or stuck
  kPauseInsSilent = 1u << 4,      ///< no INS samples at all
  kPauseFault = 1u << 5,          ///< identification: a fault suspected, active or just cleared
  kPauseObserver = 1u << 6,       ///< isolation: observer design refused (see observer_problem)
  /// isolation: the residuals contradict the model on both channels (model mismatch, not a
  /// sensor fault): no sensor fault is raised from them until the model holds again
  kPauseModelMismatch = 1u << 7,
};

/// Names of the set bits ("ins_silent", "rudder_missing", ...), comma-separated.
std::string input_flag_names(std::uint32_t flags);
std::string pause_reason_names(std::uint32_t reasons);

/// What the status topic reports.
struct PipelineStatus {
  double stamp = kNaN;  ///< source time of the last sample
  Estimate estimate;
  IsolatorStatus isolation;
  std::uint64_t samples = 0;         ///< samples assembled
  std::uint64_t dropped_inputs = 0;  ///< input queue overflow
  std::uint64_t dropped_ident = 0;   ///< identification queue overflow
  std::uint64_t dropped_output = 0;  ///< output queue overflow, and events left at stop()
  std::uint64_t rejected = 0;        ///< samples the engine refused for their stamp
  std::uint64_t duplicates = 0;      ///< exact repeats of the previous sample, dropped
  std::uint64_t clock_resyncs = 0;   ///< new time bases adopted (the engine restarted on each)
  bool ins_silent = false;           ///< no INS sample for input_timeout
  bool rudder_missing = false;       ///< the last sample had no rudder angle
  // Input problems, counted since start (see InputFlag for the per-period flags).
  std::uint32_t input_flags = 0;          ///< InputFlag bits
  std::uint64_t rejected_timestamps = 0;  ///< repeated/backward (engine) + non-finite stamps
  std::uint64_t invalid_values = 0;       ///< NaN flagged valid, Inf, absurd magnitudes
  std::uint64_t gaps = 0;                 ///< gaps longer than stale_timeout
  std::uint64_t reordered = 0;            ///< INS samples older than one already received
  /// Samples lost before they reached the sidecar (in DDS or the source): gaps in the seq of
  /// InsSample / RudderSample, since start (a late sample of a gap is taken off again).
  std::uint64_t lost_ins = 0, lost_rudder = 0;
  std::uint32_t identification_paused = 0;  ///< PauseReason bits (0: identifying)
  std::uint32_t isolation_paused = 0;       ///< PauseReason bits (0: detecting)
  // Operator acknowledgements since start.
  std::uint64_t acks_accepted = 0;
  std::uint64_t acks_refused = 0;  ///< unauthorised, unknown sensor, stale or unknown sequence...
  std::uint64_t acks_dropped = 0;  ///< ack queue overflow (a flood), oldest dropped
  std::uint64_t incarnation = 0;   ///< this run (PipelineOptions::incarnation)
  /// The surge speed of the last sample [m/s] (NaN: none); the ratio and the reference speed
  /// the model is scaled with are estimate.speed_ratio and estimate.reference_speed.
  double surge_speed = kNaN;
  /// Faults raised by this run per Sensor (published transitions into raised; a refined kind
  /// and a restored event are none).
  std::array<std::uint64_t, 3> raises{0, 0, 0};
  /// Per channel [accelerometer, gyro]: the largest J_N since the previous status (NaN: none
  /// computed), and the enter (raise) and leave thresholds in force (0: none yet).
  std::array<double, 2> j_peak{kNaN, kNaN}, j_raise{0.0, 0.0}, j_leave{0.0, 0.0};
};

/// Wall-clock seconds since each thread last went round its loop (an idle thread still goes
/// round every 50-100 ms), and since the last INS / rudder sample arrived (negative: none yet).
struct PipelineLiveness {
  double isolation = 0.0, identification = 0.0, publisher = 0.0;
  double ins_age = -1.0, rudder_age = -1.0;
};

class FdiPipeline {
 public:
  using EventSink = std::function<void(const FaultEvent&)>;
  using StatusSink = std::function<void(const PipelineStatus&)>;
  /// level: 0 debug, 1 info, 2 warning, 3 error. Called from every thread of the pipeline.
  using LogSink = std::function<void(int level, const std::string&)>;

  /// Throws std::invalid_argument on a bad configuration.
  FdiPipeline(const EngineConfig& cfg, const PipelineOptions& opt, EventSink on_event,
              StatusSink on_status, LogSink on_log);
  ~FdiPipeline();
  FdiPipeline(const FdiPipeline&) = delete;
  FdiPipeline& operator=(const FdiPipeline&) = delete;

  /// Restores latched events (restart without loss); call before start(). Each one is
  /// re-published on start with its sequence; later events of its instance continue the
  /// sequence. A restored active fault (raised, active-acknowledged) is checked again: see
  /// PipelineOptions::restore_recheck.
  void restore(const FaultEvent& ev);

  void start();
  /// Shuts the queues down in order and joins every thread. Idempotent.
  void stop();

  // Called from middleware listeners: copy into the input queue, never block.
  // The seq of each stream is checked here, before the input queue: gaps are losses before
  // the sidecar (the queue counts its own drops).
  bool push_ins(const InsInput& s) {
    last_ins_ns_.store(now_ns(), std::memory_order_relaxed);
    ins_seq_.see(s.seq);
    return input_.push(s);
  }
  bool push_rudder(const RudderInput& s) {
    last_rudder_ns_.store(now_ns(), std::memory_order_relaxed);
    rudder_seq_.see(s.seq);
    return input_.push(s);
  }
  bool push_speed(const SpeedInput& s) { return input_.push(s); }
  /// Acks have their own queue: they never take a sensor sample's place nor go before it.
  bool push_ack(const AckInput& a) { return acks_.push(a); }

  PipelineStatus status() const;
  /// The incarnation of this run (see PipelineOptions::incarnation).
  std::uint64_t incarnation() const { return incarnation_; }

  /// Gaps in a stream's sample numbers (lock-free: listeners may call from several threads).
  /// The first number seen starts the count; a number more than kRestartWindow below the
  /// highest is taken as the source restarting its count (not a loss); one below it but
  /// within the window is a late sample of a gap, taken off the count.
  class SeqGaps {
   public:
    static constexpr std::uint64_t kRestartWindow = 1000;
    void see(std::uint64_t seq);
    std::uint64_t lost() const { return lost_.load(std::memory_order_relaxed); }
    std::uint64_t restarts() const { return restarts_.load(std::memory_order_relaxed); }

   private:
    std::atomic<std::uint64_t> highest_{0}, lost_{0}, restarts_{0};
  };

  /// Inputs (INS, rudder, acks) the isolation thread has handled, and the events it has
  /// handed to the publisher since start. A caller that pushes one sample, waits for the
  /// first and for its sink to have received the second, sees each sample's events before
  /// the next sample is processed (an operator's ack then lands where replay puts it).
  std::uint64_t inputs_handled() const { return inputs_handled_.load(); }
  std::uint64_t events_emitted() const { return events_emitted_.load(); }
  /// For a health check: how recently each thread went round its loop.
  PipelineLiveness liveness() const;

 private:
  using Input = std::variant<InsInput, RudderInput, SpeedInput>;
  using Output = std::variant<FaultEvent, PipelineStatus>;
  /// A restored active fault awaiting its re-check.
  struct Recheck {
    bool pending = false;
    FaultKind kind = FaultKind::kUnknown;
    double ok_since = kNaN;  ///< source time since when its condition is not seen
  };
  /// Counters of input problems found by the pipeline itself (the engine counts the rest),
  /// with the latest example of each for the log.
  struct InputProblems {
    std::uint64_t bad_stamps = 0;  ///< non-finite stamps (INS and rudder), dropped
    std::uint64_t invalid = 0;     ///< NaN flagged valid (INS), unusable rudder angles
    std::uint64_t reordered = 0;
    /// The first few examples since the last log, per kind (stamps, values, gaps, order).
    enum Kind { kStamp = 0, kValue, kGap, kOrder };
    std::array<std::vector<std::string>, 4> examples;
    void example(Kind k, std::string text) {
      if (examples[k].size() < 3) examples[k].push_back(std::move(text));
    }
    std::string examples_of(Kind k);  ///< "a; b; c", and forgets them
  };
  /// What the previous status period's log summary had seen.
  struct ProblemCounts {
    std::uint64_t rejected_timestamps = 0, invalid_values = 0, gaps = 0, reordered = 0,
                  dropped_inputs = 0, lost = 0, seq_restarts = 0, duplicates = 0;
  };

  static std::int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  void isolation_loop();
  void identification_loop();
  void publisher_loop();
  void accept_ins(const InsInput& in);
  void accept_rudder(const RudderInput& in);
  void accept_speed(const SpeedInput& in);
  /// |u| <= max_abs_u; otherwise counts it as an invalid value, logs an example, false.
  bool speed_in_range(double u, double stamp);
  void process(const Sample& s);
  /// Installs the identification thread's latest estimate, if there is a new one.
  /// Waits (bounded by estimate_wait) until the identification thread has handled every
  /// sample handed to it, then installs its estimate.
  void await_estimate();
  /// Wall-clock seconds since start() (steady clock).
  double wall_seconds() const;
  void take_estimate();
  void recheck_restored(const Sample& s);
  /// Hands an event of this run (stamped with its incarnation) to the output queue;
  /// restored = true: a restored event, re-published with the incarnation that issued it.
  void emit(const FaultEvent& ev, bool restored = false);
  void publish(const FaultEvent& ev);
  void publish_latest();
  void handle_ack(const AckInput& a);
  void refuse_ack(const AckInput& a, const std::string& reason, const std::string& detail);
  void log_ack_summary(bool force);
  void log(int level, const std::string& msg) const;
  void log_input_changes(const PipelineStatus& st);
  PipelineStatus make_status();

  EngineConfig cfg_;
  PipelineOptions opt_;
  EventSink on_event_;
  StatusSink on_status_;
  LogSink on_log_;

  BoundedQueue<Input> input_;
  BoundedQueue<AckInput> acks_;
  SeqGaps ins_seq_, rudder_seq_;
  BoundedQueue<IdentificationInput> ident_q_;
  BoundedQueue<Output> output_;

  // Isolation thread state.
  IsolationStage iso_;
  std::vector<FaultEvent> events_;  ///< of the sample being processed
  std::uint64_t resyncs_seen_ = 0;  ///< clock re-synchronisations logged
  SampleAssembler assembler_;
  std::vector<FaultEvent> restored_;
  std::uint64_t incarnation_ = 0;
  /// The incarnation of each instance's current event (isolation thread): an ack must name it.
  std::array<std::uint64_t, 3> current_incarnation_{0, 0, 0};
  std::array<Recheck, 3> recheck_{};
  double last_t_ = kNaN;
  double last_u_ = kNaN;                      ///< surge speed of the last sample processed
  std::array<double, 2> j_peak_{kNaN, kNaN};  ///< largest J_N per channel since the last status
  double newest_ins_stamp_ = -1e300;
  std::uint64_t seen_version_ = 0;
  InputProblems problems_;
  ProblemCounts logged_;        ///< counts at the previous status (per-period flags, log)
  bool rudder_paused_ = false;  ///< logged state of the rudder pause
  double newest_rudder_stamp_ = -1e300;
  bool had_ins_ = false;           ///< an INS sample has arrived since start
  bool never_ins_logged_ = false;  ///< "no INS sample since start" was logged
  std::chrono::steady_clock::time_point started_at_{};
  /// Refused acks (isolation thread): counts since start, and what the current log period
  /// has not logged yet.
  struct AckRefusals {
    std::uint64_t total = 0;
    std::uint64_t unlogged = 0;  ///< refused in this period after the first (not logged yet)
    std::uint64_t dropped_logged = 0;
    std::vector<std::pair<std::string, std::uint64_t>> by_reason;  ///< this period
    std::string example;       ///< the latest unlogged refusal, in full
    int logged_in_period = 0;  ///< refusals logged in full in this period
    std::chrono::steady_clock::time_point period_start{};
  };
  AckRefusals refusals_;
  std::atomic<std::uint64_t> acks_accepted_{0}, acks_refused_{0};

  // Identification thread state.
  IdentificationStage ident_;

  // Shared, under snap_m_.
  mutable std::mutex snap_m_;
  Estimate snapshot_;
  std::uint64_t snapshot_version_ = 0;
  PipelineStatus last_status_;

  // The latest event of each instance (isolation thread writes, publisher reads), under
  // latest_m_: after an overflow of the output queue the publisher still writes each
  // instance's latest state. Published sequences: publisher thread only.
  std::mutex latest_m_;
  std::array<FaultEvent, 3> latest_{};
  std::array<std::uint64_t, 3> published_seq_{0, 0, 0};
  std::array<FaultState, 3> published_state_{FaultState::kNormal, FaultState::kNormal,
                                             FaultState::kNormal};  ///< publisher thread
  std::array<std::atomic<std::uint64_t>, 3> raises_{};              ///< PipelineStatus::raises

  std::atomic<std::uint64_t> samples_{0}, rejected_{0};
  std::atomic<std::uint64_t> inputs_handled_{0}, events_emitted_{0};
  // Estimate hand-over: samples handed to the identification thread (isolation thread only)
  // and handled by it (under step_m_); ident_lagging_: the last wait timed out (isolation).
  std::mutex step_m_;
  std::condition_variable step_cv_;
  std::uint64_t ident_pushed_ = 0, ident_done_ = 0;
  bool ident_lagging_ = false;
  std::atomic<bool> ins_silent_{false};
  // Liveness (steady_clock ns): each thread's last loop, the last INS / rudder arrival.
  std::atomic<std::int64_t> beat_iso_{0}, beat_ident_{0}, beat_pub_{0};
  std::atomic<std::int64_t> last_ins_ns_{0}, last_rudder_ns_{0};
  /// Set by stop() before the output queue shuts down: the publisher thread drops (and
  /// counts) what it cannot hand over before this steady_clock time (ns since its epoch).
  std::atomic<std::int64_t> drain_deadline_ns_{INT64_MAX};
  std::atomic<std::uint64_t> dropped_at_stop_{0};
  std::thread iso_thread_, ident_thread_, pub_thread_;
  bool started_ = false, stopped_ = false;
};

}  // namespace usvfdi::pipeline
