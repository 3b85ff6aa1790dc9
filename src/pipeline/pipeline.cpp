#include "usv_fdi/pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <initializer_list>
#include <stdexcept>
#include <utility>

namespace usvfdi::pipeline {

// ---------------------------------------------------------------- SampleAssembler

void SampleAssembler::add_ins(const InsInput& s, double arrival) {
  if (!std::isfinite(s.stamp)) return;
  auto it = ins_.end();
  while (it != ins_.begin() && std::prev(it)->s.stamp > s.stamp) --it;
  ins_.insert(it, PendingIns{s, arrival});
  // Far behind the newest (an INS clock that restarted): the newest of the old time base
  // must not hold back, nor prune the rudder samples of, the new one.
  newest_ins_ =
      s.stamp < newest_ins_ - (wait_ + timeout_) ? s.stamp : std::max(newest_ins_, s.stamp);
}

void SampleAssembler::add_rudder(const RudderInput& s) {
  if (!s.valid || !std::isfinite(s.stamp) || !std::isfinite(s.delta)) return;
  auto it = rudder_.end();
  while (it != rudder_.begin() && std::prev(it)->stamp > s.stamp) --it;
  rudder_.insert(it, s);
  // Keep what interpolation of the pending samples can still need.
  const double oldest = ins_.empty() ? newest_ins_ : ins_.front().s.stamp;
  while (rudder_.size() > 2 && rudder_[1].stamp < oldest - timeout_) rudder_.pop_front();
}

void SampleAssembler::add_speed(const SpeedInput& s) {
  if (!s.valid || !std::isfinite(s.stamp) || !std::isfinite(s.u)) return;
  auto it = speed_.end();
  while (it != speed_.begin() && std::prev(it)->stamp > s.stamp) --it;
  speed_.insert(it, s);
  const double oldest = ins_.empty() ? newest_ins_ : ins_.front().s.stamp;
  while (speed_.size() > 2 && speed_[1].stamp < oldest - speed_max_age_) speed_.pop_front();
  constexpr std::size_t kMaxSpeedSamples = 4096;  // a speed stream far ahead of the INS
  while (speed_.size() > kMaxSpeedSamples) speed_.pop_front();
}

double SampleAssembler::speed_at(double t) const {
  double best = kNaN, best_distance = speed_max_age_;
  for (const SpeedInput& s : speed_) {
    const double d = std::abs(s.stamp - t);
    if (d <= best_distance) {
      best = s.u;
      best_distance = d;
    }
    if (s.stamp > t) break;  // sorted: the later ones are farther
  }
  return best;
}

double SampleAssembler::delta_at(double t) const {
  if (rudder_.empty()) return kNaN;
  std::size_t i = 0;
  while (i < rudder_.size() && rudder_[i].stamp < t) ++i;
  if (i < rudder_.size()) {
    const RudderInput& b = rudder_[i];
    if (b.stamp == t) return b.delta;
    if (i > 0) {
      // Interpolate between neighbours within rudder_timeout; across a longer gap in the
      // rudder stream only the near side is used (held), and nothing when neither is near.
      const RudderInput& a = rudder_[i - 1];
      const bool a_near = t - a.stamp <= timeout_, b_near = b.stamp - t <= timeout_;
      if (a_near && b_near) {
        const double w = (t - a.stamp) / (b.stamp - a.stamp);
        return a.delta + w * (b.delta - a.delta);
      }
      if (a_near) return a.delta;
      return b_near ? b.delta : kNaN;
    }
    return b.stamp - t <= timeout_ ? b.delta : kNaN;
  }
  const RudderInput& last = rudder_.back();
  return t - last.stamp <= timeout_ ? last.delta : kNaN;
}

void SampleAssembler::rebase(double t, double span) {
  const auto far = [t, span](double stamp) { return std::abs(stamp - t) > span; };
  ins_.erase(
      std::remove_if(ins_.begin(), ins_.end(), [&](const PendingIns& p) { return far(p.s.stamp); }),
      ins_.end());
  rudder_.erase(std::remove_if(rudder_.begin(), rudder_.end(),
                               [&](const RudderInput& s) { return far(s.stamp); }),
                rudder_.end());
  speed_.erase(std::remove_if(speed_.begin(), speed_.end(),
                              [&](const SpeedInput& s) { return far(s.stamp); }),
               speed_.end());
  if (far(newest_ins_)) newest_ins_ = ins_.empty() ? t : ins_.back().s.stamp;
}

void SampleAssembler::drain(std::vector<Sample>* out, bool flush, double now) {
  while (!ins_.empty()) {
    const InsInput& s = ins_.front().s;
    const bool later_rudder = !rudder_.empty() && rudder_.back().stamp >= s.stamp;
    // Once a speed stream exists, its sample of this instant too (a slower stream: the wait),
    // unless the stream has stopped (nothing valid for speed_max_age).
    const bool later_speed = speed_.empty() || std::isfinite(s.u) ||
                             speed_.back().stamp >= s.stamp ||
                             s.stamp - speed_.back().stamp > speed_max_age_;
    const bool waited = newest_ins_ - s.stamp >= wait_ && now - ins_.front().arrival >= wall_wait_;
    if (!(flush || (later_rudder && later_speed) || waited)) break;
    Sample out_s;
    out_s.t = s.stamp;
    out_s.v = s.v_valid ? s.v : kNaN;
    out_s.r = s.r_valid ? s.r : kNaN;
    out_s.delta = delta_at(s.stamp);
    out_s.u = std::isfinite(s.u) ? s.u : speed_at(s.stamp);
    out->push_back(out_s);
    ins_.pop_front();
  }
}

// ---------------------------------------------------------------- flags

namespace {

std::string bit_names(std::uint32_t bits,
                      std::initializer_list<std::pair<std::uint32_t, const char*>> table) {
  std::string out;
  for (const auto& [bit, name] : table) {
    if (!(bits & bit)) continue;
    if (!out.empty()) out += ",";
    out += name;
  }
  return out;
}

std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

int index_of(Sensor s) { return static_cast<int>(s); }

/// Acks handled in one go when no sensor sample is waiting (then the input queue is looked
/// at again).
constexpr int kAckBatch = 16;
/// Refused acks logged in full per ack_log_period before the rest are only summarised.
constexpr int kAckLogBurst = 5;

bool sensor_level(FaultKind k) {
  return k == FaultKind::kStale || k == FaultKind::kStuck || k == FaultKind::kInvalid;
}

}  // namespace

std::string input_flag_names(std::uint32_t flags) {
  return bit_names(flags, {{kInputInsSilent, "ins_silent"},
                           {kInputRudderMissing, "rudder_missing"},
                           {kInputAccelUnusable, "accelerometer_unusable"},
                           {kInputGyroUnusable, "gyro_unusable"},
                           {kInputBadTimestamps, "bad_timestamps"},
                           {kInputInvalidValues, "invalid_values"},
                           {kInputGaps, "gaps"},
                           {kInputReordered, "reordered"},
                           {kInputQueueDrops, "queue_drops"},
                           {kInputSamplesLost, "samples_lost"},
                           {kInputOtherEventWriter, "other_event_writer"}});
}

std::string pause_reason_names(std::uint32_t reasons) {
  return bit_names(reasons, {{kPauseNotArmed, "not_armed"},
                             {kPauseLearning, "learning"},
                             {kPauseRudderMissing, "rudder_missing"},
                             {kPauseInsUnusable, "ins_unusable"},
                             {kPauseInsSilent, "ins_silent"},
                             {kPauseFault, "fault"},
                             {kPauseObserver, "observer"},
                             {kPauseModelMismatch, "model_mismatch"}});
}

// ---------------------------------------------------------------- FdiPipeline

void FdiPipeline::SeqGaps::see(std::uint64_t seq) {
  if (seq == 0) return;
  std::uint64_t high = highest_.load(std::memory_order_relaxed);
  for (;;) {
    if (high != 0 && seq <= high) {
      if (high - seq >= kRestartWindow) {
        // The source started counting again (a restart): follow it, nothing was lost.
        if (!highest_.compare_exchange_weak(high, seq, std::memory_order_relaxed)) continue;
        restarts_.fetch_add(1, std::memory_order_relaxed);
        return;
      }
      // A late sample of a gap counted already (DDS does not deliver duplicates).
      std::uint64_t lost = lost_.load(std::memory_order_relaxed);
      while (lost > 0 && !lost_.compare_exchange_weak(lost, lost - 1, std::memory_order_relaxed)) {
      }
      return;
    }
    if (highest_.compare_exchange_weak(high, seq, std::memory_order_relaxed)) {
      if (high != 0) lost_.fetch_add(seq - high - 1, std::memory_order_relaxed);
      return;
    }
  }
}

FdiPipeline::FdiPipeline(const EngineConfig& cfg, const PipelineOptions& opt, EventSink on_event,
                         StatusSink on_status, LogSink on_log)
    : cfg_((cfg.validate(), cfg)),
      opt_(opt),
      on_event_(std::move(on_event)),
      on_status_(std::move(on_status)),
      on_log_(std::move(on_log)),
      input_(opt.input_capacity),
      acks_(opt.ack_capacity),
      ident_q_(opt.ident_capacity),
      output_(opt.output_capacity),
      iso_(cfg),
      assembler_(opt.rudder_wait, opt.rudder_timeout, opt.rudder_wait, opt.speed_max_age),
      ident_(cfg) {
  incarnation_ = opt.incarnation;
}

FdiPipeline::~FdiPipeline() { stop(); }

void FdiPipeline::restore(const FaultEvent& ev) {
  if (started_) throw std::logic_error("FdiPipeline::restore() after start()");
  const int i = index_of(ev.sensor);
  if (i < 0 || i > 2) throw std::invalid_argument("FdiPipeline::restore(): unknown sensor");
  iso_.restore(ev);
  restored_.push_back(ev);
  current_incarnation_[i] = ev.incarnation;
  {
    std::lock_guard<std::mutex> lock(latest_m_);
    latest_[i] = ev;
  }
  recheck_[i] = Recheck{};
  if (ev.state == FaultState::kRaised || ev.state == FaultState::kActiveAcknowledged) {
    recheck_[i].pending = true;
    recheck_[i].kind = ev.kind;
  }
}

void FdiPipeline::start() {
  if (started_) return;
  started_ = true;
  started_at_ = std::chrono::steady_clock::now();
  const std::int64_t now = now_ns();
  beat_iso_ = beat_ident_ = beat_pub_ = now;
  pub_thread_ = std::thread([this] { publisher_loop(); });
  ident_thread_ = std::thread([this] { identification_loop(); });
  iso_thread_ = std::thread([this] { isolation_loop(); });
}

void FdiPipeline::stop() {
  if (!started_ || stopped_) return;
  stopped_ = true;
  input_.shutdown();
  acks_.shutdown();
  if (iso_thread_.joinable()) iso_thread_.join();
  ident_q_.shutdown();
  if (ident_thread_.joinable()) ident_thread_.join();
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(opt_.stop_drain_timeout));
  drain_deadline_ns_ =
      std::chrono::duration_cast<std::chrono::nanoseconds>(deadline.time_since_epoch()).count();
  output_.shutdown();
  if (pub_thread_.joinable()) pub_thread_.join();
}

double FdiPipeline::wall_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_at_).count();
}

void FdiPipeline::log(int level, const std::string& msg) const {
  if (on_log_) on_log_(level, msg);
}

void FdiPipeline::emit(const FaultEvent& ev_in, bool restored) {
  FaultEvent ev = ev_in;
  if (!restored && incarnation_ != 0) ev.incarnation = incarnation_;
  current_incarnation_[index_of(ev.sensor)] = ev.incarnation;
  {
    std::lock_guard<std::mutex> lock(latest_m_);
    latest_[index_of(ev.sensor)] = ev;
  }
  ++events_emitted_;
  output_.push(ev);
}

void FdiPipeline::accept_ins(const InsInput& in) {
  if (!std::isfinite(in.stamp)) {
    ++problems_.bad_stamps;
    problems_.example(InputProblems::kStamp,
                      fmt("an INS sample with stamp %g was dropped", in.stamp));
    return;
  }
  for (int c = 0; c < 2; ++c) {
    const bool flagged_valid = c == 0 ? in.v_valid : in.r_valid;
    const double x = c == 0 ? in.v : in.r;
    if (flagged_valid && std::isnan(x)) {
      ++problems_.invalid;  // Inf and absurd magnitudes are counted by the engine
      problems_.example(InputProblems::kValue,
                        std::string(c == 0 ? "v" : "r") +
                            fmt(" = NaN flagged valid at t=%.3f s (used as missing)", in.stamp));
    }
  }
  if (in.stamp < newest_ins_stamp_) {
    ++problems_.reordered;
    problems_.example(InputProblems::kOrder,
                      fmt("INS t=%.3f s arrived after t=%.3f s", in.stamp, newest_ins_stamp_));
  }
  newest_ins_stamp_ = std::max(newest_ins_stamp_, in.stamp);
  if (std::isfinite(in.u) && !speed_in_range(in.u, in.stamp)) {
    InsInput without_u = in;
    without_u.u = kNaN;
    assembler_.add_ins(without_u, wall_seconds());
    return;
  }
  assembler_.add_ins(in, wall_seconds());
}

void FdiPipeline::accept_rudder(const RudderInput& in) {
  if (!std::isfinite(in.stamp)) {
    ++problems_.bad_stamps;
    problems_.example(InputProblems::kStamp,
                      fmt("a rudder sample with stamp %g was dropped", in.stamp));
    return;
  }
  const double limit = cfg_.isolation.max_abs_delta;
  if (in.valid && !(std::abs(in.delta) <= limit)) {
    ++problems_.invalid;
    problems_.example(InputProblems::kValue,
                      fmt("rudder angle %g rad at t=%.3f s (|delta| > max_abs_delta %g) dropped",
                          in.delta, in.stamp, limit));
    return;
  }
  if (in.valid && in.stamp < newest_rudder_stamp_) {
    ++problems_.reordered;
    problems_.example(InputProblems::kOrder, fmt("rudder t=%.3f s arrived after t=%.3f s", in.stamp,
                                                 newest_rudder_stamp_));
  }
  if (in.valid) newest_rudder_stamp_ = std::max(newest_rudder_stamp_, in.stamp);
  assembler_.add_rudder(in);
}

void FdiPipeline::accept_speed(const SpeedInput& in) {
  if (!in.valid) return;  // the source says it has no speed now: the engine holds the last
  if (!std::isfinite(in.stamp)) {
    ++problems_.bad_stamps;
    problems_.example(InputProblems::kStamp,
                      fmt("a speed sample with stamp %g was dropped", in.stamp));
    return;
  }
  if (speed_in_range(in.u, in.stamp)) assembler_.add_speed(in);
}

bool FdiPipeline::speed_in_range(double u, double stamp) {
  if (std::abs(u) <= opt_.max_abs_u) return true;
  ++problems_.invalid;
  problems_.example(InputProblems::kValue, fmt("surge speed %g m/s at t=%.3f s (|u| > %g) dropped",
                                               u, stamp, opt_.max_abs_u));
  return false;
}

void FdiPipeline::process(const Sample& s) {
  const double prev_t = last_t_;
  events_.clear();
  await_estimate();
  IdentificationInput handover;
  const bool ok = iso_.process(s, &events_, &handover);
  for (const Detection& d : iso_.detections()) {
    recheck_[index_of(d.sensor)].pending = false;  // the detector has taken the instance over
  }
  for (const FaultEvent& ev : events_) emit(ev);
  const bool resynced = iso_.clock().resyncs() != resyncs_seen_;
  if (resynced) {
    resyncs_seen_ = iso_.clock().resyncs();
    log(2, fmt("INS clock re-synchronised: stamps left the time base at t=%.3f s and continue "
               "consistently from t=%.3f s: detection and identification restarted",
               iso_.clock().resync_from(), s.t));
  }
  // The previous sample once more (a source or link repeated it): dropped, and counted by
  // the isolation stage.
  if (!ok && iso_.last_was_duplicate()) return;
  if (!ok || resynced) {
    assembler_.rebase(iso_.clock().last(), cfg_.clock_max_jump);
  }
  if (!ok) {
    ++rejected_;
    problems_.example(
        InputProblems::kStamp,
        fmt("INS sample t=%.3f s rejected: not after the previous one (t=%.3f s)", s.t, prev_t));
    return;
  }
  const IsolationParams& p = cfg_.isolation;
  if (std::isfinite(prev_t) && s.t - prev_t > p.stale_timeout) {
    problems_.example(InputProblems::kGap, fmt("no INS sample between t=%.3f and t=%.3f s (%.3f s)",
                                               prev_t, s.t, s.t - prev_t));
  }
  if (std::isinf(s.v) || std::abs(s.v) > p.max_abs_v) {
    problems_.example(InputProblems::kValue,
                      fmt("v = %g m/s at t=%.3f s (|v| > max_abs_v %g)", s.v, s.t, p.max_abs_v));
  }
  if (std::isinf(s.r) || std::abs(s.r) > p.max_abs_r) {
    problems_.example(InputProblems::kValue,
                      fmt("r = %g rad/s at t=%.3f s (|r| > max_abs_r %g)", s.r, s.t, p.max_abs_r));
  }
  ++samples_;
  last_t_ = s.t;
  last_u_ = s.u;
  // The largest J_N per channel until the next status (a peak between two statuses is shown).
  const IsolatorStatus& ist = iso_.status();
  if (ist.armed) {
    for (int c = 0; c < 2; ++c) {
      const double j = ist.J(c);
      if (std::isfinite(j) && !(j <= j_peak_[static_cast<std::size_t>(c)])) {
        j_peak_[static_cast<std::size_t>(c)] = j;
      }
    }
  }
  // The rudder pauses identification and isolation: say so when it starts and ends.
  const InputHealth& in = iso_.status().input;
  if (!in.delta_ok && !rudder_paused_) {
    rudder_paused_ = true;
    log(2, newest_rudder_stamp_ > -1e299
               ? fmt("rudder: no usable rudder angle since t=%.3f s (the last rudder sample, "
                     "%.2f s before t=%.3f s): identification and isolation paused until "
                     "rudder samples arrive",
                     newest_rudder_stamp_, s.t - newest_rudder_stamp_, s.t)
               : fmt("rudder: no usable rudder angle since the first INS sample (t=%.3f s): "
                     "identification and isolation paused until rudder samples arrive",
                     s.t));
  } else if (in.delta_ok && rudder_paused_) {
    rudder_paused_ = false;
    log(1,
        fmt("rudder: rudder angles again at t=%.3f s: identification and isolation resume", s.t));
  }
  recheck_restored(s);
  ++ident_pushed_;
  ident_q_.push(handover);
}

void FdiPipeline::await_estimate() {
  if (ident_pushed_ > 0 && opt_.estimate_wait > 0.0) {
    using Clock = std::chrono::steady_clock;
    std::unique_lock<std::mutex> lock(step_m_);
    // Dropped hand-overs (a full queue, oldest first) will never be handled.
    const auto behind = [&] {
      const std::uint64_t settled = ident_done_ + ident_q_.dropped();
      return settled >= ident_pushed_ ? 0 : ident_pushed_ - settled;
    };
    if (ident_lagging_) {
      if (behind() == 0) {
        ident_lagging_ = false;
        lock.unlock();
        log(1,
            "identification: the identification thread has caught up: isolation again uses "
            "the estimate of all earlier samples");
      }
    } else {
      const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(opt_.estimate_wait));
      while (behind() > 0) {
        const auto now = Clock::now();
        beat_iso_.store(now_ns(), std::memory_order_relaxed);
        if (now >= deadline) {
          ident_lagging_ = true;
          const std::uint64_t n = behind();
          lock.unlock();
          log(2, "identification: the identification thread is " + std::to_string(n) +
                     " sample(s) behind after " + fmt("%g s", opt_.estimate_wait) +
                     " (estimate_wait): isolation goes on with the estimate it has, so its "
                     "results now depend on how the threads are scheduled");
          break;
        }
        step_cv_.wait_until(lock, std::min(deadline, now + std::chrono::milliseconds(100)));
      }
    }
  }
  take_estimate();
}

void FdiPipeline::take_estimate() {
  Estimate est;
  {
    std::lock_guard<std::mutex> lock(snap_m_);
    if (snapshot_version_ == seen_version_) return;
    est = snapshot_;
    seen_version_ = snapshot_version_;
  }
  iso_.set_estimate(est);
}

void FdiPipeline::recheck_restored(const Sample& s) {
  const IsolatorStatus& st = iso_.status();
  for (int i = 0; i < 3; ++i) {
    Recheck& rc = recheck_[i];
    if (!rc.pending) continue;
    bool absent = false;
    std::string why;
    if (sensor_level(rc.kind)) {
      // Stale, stuck, invalid: the sensor checks run from the first sample.
      absent = i == 0 ? st.input.v_ok : (i == 1 ? st.input.r_ok : true);
      why = "its channel has been healthy for";
    } else {
      // A residual fault: only a re-armed detector that has learned can tell.
      absent = st.armed && !st.learning && !st.settling && st.observer_problem.empty() &&
               st.input.delta_ok;
      why = "the re-armed detector has seen no fault for";
    }
    if (!absent) {
      rc.ok_since = kNaN;
      continue;
    }
    if (std::isnan(rc.ok_since)) rc.ok_since = s.t;
    if (s.t - rc.ok_since < opt_.restore_recheck) continue;
    rc.pending = false;
    Detection d;
    d.sensor = static_cast<Sensor>(i);
    d.active = false;
    d.kind = rc.kind;
    d.detection_time = s.t;
    d.statistic = i < 2 ? st.J(i) : st.J.maxCoeff();
    d.threshold = i < 2 ? st.thresholds(i) : st.threshold;
    d.message = "not present after the restart: " + why + fmt(" %.1f s", opt_.restore_recheck);
    FaultEvent ev;
    if (iso_.apply(d, &ev)) {
      log(1, std::string("restored ") + to_string(d.sensor) + " fault (" + to_string(rc.kind) +
                 ") " + d.message + ": now #" + std::to_string(ev.sequence) + " " +
                 to_string(ev.state));
      emit(ev);
    }
  }
}

void FdiPipeline::handle_ack(const AckInput& a) {
  FaultEvent ev;
  const std::string what =
      std::string("ack of ") +
      (static_cast<int>(a.sensor) > 2 ? "sensor " + std::to_string(static_cast<int>(a.sensor))
                                      : std::string(to_string(a.sensor))) +
      " #" + std::to_string(a.sequence) + " by " + a.who;
  if (!opt_.authorised_operators.empty() &&
      std::find(opt_.authorised_operators.begin(), opt_.authorised_operators.end(), a.who) ==
          opt_.authorised_operators.end()) {
    refuse_ack(a, "not authorised", what + " refused: operator '" + a.who + "' is not authorised");
    return;
  }
  if (static_cast<int>(a.sensor) > 2) {
    refuse_ack(a, "unknown sensor", what + " refused: unknown sensor");
    return;
  }
  const FaultLatch& latch = iso_.latch(a.sensor);
  const std::uint64_t current = latch.current().sequence;
  const std::uint64_t inc = current_incarnation_[static_cast<int>(a.sensor)];
  if (incarnation_ != 0 && a.incarnation != inc) {
    // Sequences start again in a new run without a state directory: an ack of another run's
    // event must not acknowledge this run's event of the same number.
    refuse_ack(a, "other incarnation",
               what + " refused: incarnation " + std::to_string(a.incarnation) +
                   " is not that of the current event (#" + std::to_string(current) +
                   ", incarnation " + std::to_string(inc) + "): it acknowledges an event of " +
                   (a.incarnation < inc ? "an earlier" : "another") + " run of the sidecar");
    return;
  }
  // Stamp: the time of the last sample (before any sample after a restart: the event's own).
  const double t = std::isfinite(last_t_) ? last_t_ : latch.current().t;
  const AckResult r = iso_.acknowledge(a.sensor, a.sequence, t, a.who, &ev);
  if (r == AckResult::kAccepted) {
    ++acks_accepted_;
    log(1, std::string("ack of ") + to_string(a.sensor) + " #" + std::to_string(a.sequence) +
               " by " + a.who + " accepted");
    emit(ev);
  } else {
    refuse_ack(a, to_string(r),
               what + " refused: " + to_string(r) + " (current #" + std::to_string(current) +
                   ", state " + to_string(latch.state()) + ")");
  }
}

void FdiPipeline::refuse_ack(const AckInput&, const std::string& reason,
                             const std::string& detail) {
  ++acks_refused_;
  AckRefusals& r = refusals_;
  ++r.total;
  if (r.logged_in_period < kAckLogBurst) {
    // The first few refusals of a period are logged at once, in full: an operator who
    // mistyped a sequence sees why.
    ++r.logged_in_period;
    log(2, detail);
    return;
  }
  ++r.unlogged;
  auto it = std::find_if(r.by_reason.begin(), r.by_reason.end(),
                         [&](const auto& x) { return x.first == reason; });
  if (it == r.by_reason.end()) {
    r.by_reason.emplace_back(reason, 1);
  } else {
    ++it->second;
  }
  r.example = detail;
}

void FdiPipeline::log_ack_summary(bool force) {
  AckRefusals& r = refusals_;
  const auto now = std::chrono::steady_clock::now();
  const double age = std::chrono::duration<double>(now - r.period_start).count();
  if (!force && age < opt_.ack_log_period) return;
  const std::uint64_t dropped = acks_.dropped();
  if (r.unlogged > 0 || dropped > r.dropped_logged) {
    std::string reasons;
    for (const auto& [why, n] : r.by_reason) {
      reasons += (reasons.empty() ? "" : ", ") + std::to_string(n) + " " + why;
    }
    std::string msg = "acks: " + std::to_string(r.unlogged) + " more ack(s) refused in the last " +
                      fmt("%.1f s", age) + " (" + std::to_string(r.total) + " since start" +
                      (reasons.empty() ? std::string() : "; " + reasons) + ")";
    if (dropped > r.dropped_logged) {
      msg += "; " + std::to_string(dropped - r.dropped_logged) +
             " dropped unread: the ack queue (" + std::to_string(acks_.capacity()) +
             ") was full (" + std::to_string(dropped) + " since start)";
    }
    if (!r.example.empty()) msg += "; e.g. " + r.example;
    log(2, msg);
  }
  r.dropped_logged = dropped;
  r.unlogged = 0;
  r.by_reason.clear();
  r.example.clear();
  r.logged_in_period = 0;
  r.period_start = now;
}

PipelineStatus FdiPipeline::make_status() {
  PipelineStatus st;
  st.stamp = last_t_;
  st.surge_speed = last_u_;
  st.estimate = iso_.estimate();
  st.isolation = iso_.status();
  st.j_peak = j_peak_;
  j_peak_ = {kNaN, kNaN};
  for (int c = 0; c < 2; ++c) {
    st.j_raise[static_cast<std::size_t>(c)] = st.isolation.thresholds(c);
    st.j_leave[static_cast<std::size_t>(c)] =
        cfg_.isolation.exit_ratio * st.isolation.thresholds(c);
  }
  st.samples = samples_.load();
  st.rejected = rejected_.load();
  st.duplicates = iso_.duplicate_samples();
  st.clock_resyncs = iso_.clock().resyncs();
  st.dropped_inputs = input_.dropped();
  st.dropped_ident = ident_q_.dropped();
  st.dropped_output = output_.dropped() + dropped_at_stop_.load();
  const InputHealth& in = st.isolation.input;
  const double since_start =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_at_).count();
  // An INS that has not published since start is as silent as one that stopped.
  st.ins_silent = ins_silent_.load() || (!had_ins_ && since_start > opt_.input_timeout);
  st.rudder_missing = !in.delta_ok;
  st.rejected_timestamps = in.rejected_time + problems_.bad_stamps;
  st.invalid_values = in.invalid_values + problems_.invalid;
  st.gaps = in.gaps;
  st.reordered = problems_.reordered;
  st.lost_ins = ins_seq_.lost();
  st.lost_rudder = rudder_seq_.lost();
  std::uint32_t f = 0;
  if (st.ins_silent) f |= kInputInsSilent;
  if (!in.delta_ok) f |= kInputRudderMissing;
  if (!in.v_ok) f |= kInputAccelUnusable;
  if (!in.r_ok) f |= kInputGyroUnusable;
  if (st.rejected_timestamps > logged_.rejected_timestamps) f |= kInputBadTimestamps;
  if (st.invalid_values > logged_.invalid_values) f |= kInputInvalidValues;
  if (st.gaps > logged_.gaps) f |= kInputGaps;
  if (st.reordered > logged_.reordered) f |= kInputReordered;
  if (st.dropped_inputs > logged_.dropped_inputs) f |= kInputQueueDrops;
  if (st.lost_ins + st.lost_rudder > logged_.lost) f |= kInputSamplesLost;
  st.input_flags = f;
  // Why identification and isolation do not run.
  std::uint32_t id = 0, iso = 0;
  if (st.ins_silent || st.samples == 0) {
    id |= kPauseInsSilent;
    iso |= kPauseInsSilent;
  }
  if (iso_.freeze_requested()) {
    if (!in.delta_ok) id |= kPauseRudderMissing;
    if (!in.v_ok || !in.r_ok) id |= kPauseInsUnusable;
    if (!(id & (kPauseRudderMissing | kPauseInsUnusable))) id |= kPauseFault;
  }
  if (!st.isolation.armed) {
    iso |= kPauseNotArmed;
  } else if (st.isolation.learning || st.isolation.settling) {
    iso |= kPauseLearning;
  }
  if (!in.delta_ok) iso |= kPauseRudderMissing;
  if (!st.isolation.observer_problem.empty()) iso |= kPauseObserver;
  if (st.isolation.model_mismatch) iso |= kPauseModelMismatch;
  st.identification_paused = id;
  st.isolation_paused = iso;
  st.acks_accepted = acks_accepted_.load();
  st.acks_refused = acks_refused_.load();
  st.acks_dropped = acks_.dropped();
  st.incarnation = incarnation_;
  return st;
}

std::string FdiPipeline::InputProblems::examples_of(Kind k) {
  std::string out;
  for (const std::string& e : examples[k]) out += (out.empty() ? "" : "; ") + e;
  examples[k].clear();
  return out;
}

void FdiPipeline::log_input_changes(const PipelineStatus& st) {
  const auto more = [](std::uint64_t now, std::uint64_t before) {
    return std::to_string(now - before);
  };
  if (st.rejected_timestamps > logged_.rejected_timestamps) {
    log(2, "inputs: " + more(st.rejected_timestamps, logged_.rejected_timestamps) +
               " sample(s) with a repeated, backward or non-finite timestamp dropped (" +
               std::to_string(st.rejected_timestamps) + " since start), e.g. " +
               problems_.examples_of(InputProblems::kStamp));
  }
  if (st.invalid_values > logged_.invalid_values) {
    log(2, "inputs: " + more(st.invalid_values, logged_.invalid_values) +
               " invalid value(s): NaN flagged valid, infinite or absurd (" +
               std::to_string(st.invalid_values) + " since start), e.g. " +
               problems_.examples_of(InputProblems::kValue));
  }
  if (st.gaps > logged_.gaps) {
    log(2, "inputs: " + more(st.gaps, logged_.gaps) + " gap(s) longer than stale_timeout " +
               fmt("%g s", cfg_.isolation.stale_timeout) + " (" + std::to_string(st.gaps) +
               " since start), e.g. " + problems_.examples_of(InputProblems::kGap));
  }
  if (st.reordered > logged_.reordered) {
    log(1, "inputs: " + more(st.reordered, logged_.reordered) +
               " sample(s) delivered out of order (re-sorted within rudder_wait, later ones "
               "rejected), e.g. " +
               problems_.examples_of(InputProblems::kOrder));
  }
  if (st.dropped_inputs > logged_.dropped_inputs) {
    log(2, "inputs: input queue full (" + std::to_string(input_.capacity()) +
               "): " + more(st.dropped_inputs, logged_.dropped_inputs) +
               " sample(s) dropped, oldest first (" + std::to_string(st.dropped_inputs) +
               " since start): samples arrive faster than the isolation thread processes them");
  }
  const std::uint64_t lost = st.lost_ins + st.lost_rudder;
  if (lost > logged_.lost) {
    log(2, "inputs: " + more(lost, logged_.lost) +
               " sample(s) lost before reaching the sidecar (gaps in the sources' seq; " +
               std::to_string(st.lost_ins) + " INS and " + std::to_string(st.lost_rudder) +
               " rudder since start)");
  }
  if (st.duplicates > logged_.duplicates) {
    log(1, "inputs: " + more(st.duplicates, logged_.duplicates) +
               " exact repeat(s) of the previous INS sample dropped (" +
               std::to_string(st.duplicates) + " since start)");
  }
  logged_.duplicates = st.duplicates;
  const std::uint64_t restarts = ins_seq_.restarts() + rudder_seq_.restarts();
  if (restarts > logged_.seq_restarts) {
    log(1,
        "inputs: an INS or rudder source started numbering its samples again (seq far "
        "below the highest seen): taken as a restart of the source, not as a loss");
  }
  if (st.ins_silent && !had_ins_ && !never_ins_logged_) {
    never_ins_logged_ = true;
    log(2,
        fmt("no INS sample since start (%.1f s): detection is not running",
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started_at_).count()));
  }
  logged_.rejected_timestamps = st.rejected_timestamps;
  logged_.invalid_values = st.invalid_values;
  logged_.gaps = st.gaps;
  logged_.reordered = st.reordered;
  logged_.dropped_inputs = st.dropped_inputs;
  logged_.lost = lost;
  logged_.seq_restarts = restarts;
}

PipelineStatus FdiPipeline::status() const {
  PipelineStatus st;
  {
    std::lock_guard<std::mutex> lock(snap_m_);
    st = last_status_;
  }
  // The counters are read live (the snapshot is refreshed at the status period only).
  st.dropped_inputs = input_.dropped();
  st.dropped_ident = ident_q_.dropped();
  st.dropped_output = output_.dropped() + dropped_at_stop_.load();
  st.acks_accepted = acks_accepted_.load();
  st.acks_refused = acks_refused_.load();
  st.acks_dropped = acks_.dropped();
  for (std::size_t i = 0; i < st.raises.size(); ++i) st.raises[i] = raises_[i].load();
  return st;
}

PipelineLiveness FdiPipeline::liveness() const {
  PipelineLiveness l;
  if (!started_) return l;
  const std::int64_t now = now_ns();
  const auto age = [now](const std::atomic<std::int64_t>& t) {
    return static_cast<double>(now - t.load(std::memory_order_relaxed)) * 1e-9;
  };
  if (!stopped_) {
    l.isolation = age(beat_iso_);
    l.identification = age(beat_ident_);
    l.publisher = age(beat_pub_);
  }
  if (last_ins_ns_.load(std::memory_order_relaxed) != 0) l.ins_age = age(last_ins_ns_);
  if (last_rudder_ns_.load(std::memory_order_relaxed) != 0) l.rudder_age = age(last_rudder_ns_);
  return l;
}

void FdiPipeline::isolation_loop() {
  using Clock = std::chrono::steady_clock;
  for (const FaultEvent& ev : restored_) emit(ev, true);
  auto last_status = Clock::now();
  auto last_ins = Clock::now();
  refusals_.period_start = last_status;
  std::vector<Sample> batch;
  const auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  for (;;) {
    beat_iso_.store(now_ns(), std::memory_order_relaxed);
    Input in;
    // Acks waiting: look for a sensor sample without waiting, and take the acks only when
    // there is none (acks never go ahead of, nor delay, the sensor samples).
    const bool acks_waiting = acks_.size() > 0;
    const auto r = input_.pop_for(&in, std::chrono::milliseconds(acks_waiting ? 0 : 50));
    if (r == BoundedQueue<Input>::PopResult::kShutdown) break;
    if (r == BoundedQueue<Input>::PopResult::kTimeout && acks_waiting) {
      AckInput a;
      for (int k = 0; k < kAckBatch && acks_.pop_for(&a, std::chrono::milliseconds(0)) ==
                                           BoundedQueue<AckInput>::PopResult::kValue;
           ++k) {
        handle_ack(a);
        ++inputs_handled_;
      }
    }
    const auto now = Clock::now();
    if (r == BoundedQueue<Input>::PopResult::kValue) {
      if (const auto* ins = std::get_if<InsInput>(&in)) {
        accept_ins(*ins);
        last_ins = now;
        had_ins_ = true;
        if (ins_silent_.exchange(false)) log(1, "INS samples arrive again");
      } else if (const auto* rudder = std::get_if<RudderInput>(&in)) {
        accept_rudder(*rudder);
      } else {
        accept_speed(std::get<SpeedInput>(in));
      }
    }
    // Also without input: a sample may have waited long enough for its rudder angle now.
    if (assembler_.pending() > 0) {
      batch.clear();
      assembler_.drain(&batch, false, wall_seconds());
      for (const Sample& s : batch) process(s);
    }
    if (r == BoundedQueue<Input>::PopResult::kValue) ++inputs_handled_;
    if (had_ins_ && !ins_silent_ && seconds(now - last_ins) > opt_.input_timeout) {
      ins_silent_ = true;
      log(2, fmt("no INS sample for %.2f s (input_timeout %g s): both INS channels stale",
                 seconds(now - last_ins), opt_.input_timeout));
      batch.clear();
      assembler_.drain(&batch, true);
      for (const Sample& s : batch) process(s);
      // A missing sample at the silent time lets the stale checks see the silence.
      if (std::isfinite(last_t_))
        process(Sample{last_t_ + seconds(now - last_ins), kNaN, kNaN, kNaN});
    }
    if (seconds(now - last_status) >= opt_.status_period) {
      last_status = now;
      const PipelineStatus st = make_status();
      log_input_changes(st);
      log_ack_summary(false);
      {
        std::lock_guard<std::mutex> lock(snap_m_);
        last_status_ = st;
      }
      output_.push(st);
    }
  }
  batch.clear();
  assembler_.drain(&batch, true);
  for (const Sample& s : batch) process(s);
  log_ack_summary(true);
  const PipelineStatus st = make_status();
  std::lock_guard<std::mutex> lock(snap_m_);
  last_status_ = st;
}

void FdiPipeline::identification_loop() {
  IdentificationInput it;
  bool last_converged = false;
  for (;;) {
    beat_ident_.store(now_ns(), std::memory_order_relaxed);
    const auto r = ident_q_.pop_for(&it, std::chrono::milliseconds(100));
    if (r == BoundedQueue<IdentificationInput>::PopResult::kShutdown) break;
    if (r == BoundedQueue<IdentificationInput>::PopResult::kTimeout) continue;
    // Every new estimate goes to the isolation thread, as in FdiEngine.
    if (ident_.push(it)) {
      const Estimate& e = ident_.estimate();
      if (e.converged != last_converged) {
        const Mat2& A = e.A;
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "identification: A %s at t=%.2f s: A = [%.4g %.4g; %.4g %.4g], "
                      "excitation %.3g",
                      e.converged ? "converged" : "no longer converged", e.t, A(0, 0), A(0, 1),
                      A(1, 0), A(1, 1), e.excitation);
        log(1, buf);
      }
      {
        std::lock_guard<std::mutex> lock(snap_m_);
        snapshot_ = e;
        ++snapshot_version_;
      }
      last_converged = e.converged;
    }
    {
      std::lock_guard<std::mutex> lock(step_m_);
      ++ident_done_;
    }
    step_cv_.notify_all();
  }
}

void FdiPipeline::publish(const FaultEvent& ev) {
  std::uint64_t& published = published_seq_[index_of(ev.sensor)];
  if (ev.sequence <= published) return;  // already handed over (after an overflow)
  published = ev.sequence;
  FaultState& before = published_state_[index_of(ev.sensor)];
  if (ev.state == FaultState::kRaised && before != FaultState::kRaised &&
      ev.incarnation == incarnation_) {
    raises_[index_of(ev.sensor)].fetch_add(1, std::memory_order_relaxed);
  }
  before = ev.state;
  try {
    if (on_event_) on_event_(ev);
  } catch (const std::exception& e) {
    log(3, std::string("publishing failed: ") + e.what());
  }
}

void FdiPipeline::publish_latest() {
  std::array<FaultEvent, 3> latest;
  {
    std::lock_guard<std::mutex> lock(latest_m_);
    latest = latest_;
  }
  for (const FaultEvent& ev : latest) {
    if (ev.sequence <= published_seq_[index_of(ev.sensor)]) continue;
    log(2, std::string("output queue overflowed: publishing the latest state of ") +
               to_string(ev.sensor) + " (#" + std::to_string(ev.sequence) + " " +
               to_string(ev.state) + "); intermediate states were dropped");
    publish(ev);
  }
}

void FdiPipeline::publisher_loop() {
  Output o;
  std::uint64_t seen_drops = 0;
  for (;;) {
    beat_pub_.store(now_ns(), std::memory_order_relaxed);
    const auto r = output_.pop_for(&o, std::chrono::milliseconds(100));
    if (r == BoundedQueue<Output>::PopResult::kShutdown) break;
    // stop() is waiting: never block shutdown on a slow writer.
    const bool late = now_ns() > drain_deadline_ns_.load();
    if (r == BoundedQueue<Output>::PopResult::kValue) {
      if (late) {
        ++dropped_at_stop_;
        continue;
      }
      if (const auto* ev = std::get_if<FaultEvent>(&o)) {
        publish(*ev);
      } else if (on_status_) {
        try {
          on_status_(std::get<PipelineStatus>(o));
        } catch (const std::exception& e) {
          log(3, std::string("publishing the status failed: ") + e.what());
        }
      }
    }
    const std::uint64_t drops = output_.dropped();
    if (drops != seen_drops && !late) {
      seen_drops = drops;
      publish_latest();
    }
  }
  if (dropped_at_stop_.load() > 0) {
    log(2, std::to_string(dropped_at_stop_.load()) +
               " queued events/status not published: the writer was too slow at stop");
  }
}

}  // namespace usvfdi::pipeline
