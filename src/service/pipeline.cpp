#include "usv_fdi/service/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>

namespace usvfdi {

// ---------------------------------------------------------------- SampleAssembler

void SampleAssembler::add_ins(const InsInput& s) {
  if (!std::isfinite(s.stamp)) return;
  auto it = ins_.end();
  while (it != ins_.begin() && std::prev(it)->stamp > s.stamp) --it;
  ins_.insert(it, s);
  newest_ins_ = std::max(newest_ins_, s.stamp);
}

void SampleAssembler::add_rudder(const RudderInput& s) {
  if (!s.valid || !std::isfinite(s.stamp) || !std::isfinite(s.delta)) return;
  auto it = rudder_.end();
  while (it != rudder_.begin() && std::prev(it)->stamp > s.stamp) --it;
  rudder_.insert(it, s);
  // Keep what interpolation of the pending samples can still need.
  const double oldest = ins_.empty() ? newest_ins_ : ins_.front().stamp;
  while (rudder_.size() > 2 && rudder_[1].stamp < oldest - timeout_) rudder_.pop_front();
}

double SampleAssembler::delta_at(double t) const {
  if (rudder_.empty()) return kNaN;
  std::size_t i = 0;
  while (i < rudder_.size() && rudder_[i].stamp < t) ++i;
  if (i < rudder_.size()) {
    const RudderInput& b = rudder_[i];
    if (b.stamp == t) return b.delta;
    if (i > 0) {
      const RudderInput& a = rudder_[i - 1];
      if (t - a.stamp > timeout_ && b.stamp - t > timeout_) return kNaN;
      const double w = (t - a.stamp) / (b.stamp - a.stamp);
      return a.delta + w * (b.delta - a.delta);
    }
    return b.stamp - t <= timeout_ ? b.delta : kNaN;
  }
  const RudderInput& last = rudder_.back();
  return t - last.stamp <= timeout_ ? last.delta : kNaN;
}

void SampleAssembler::drain(std::vector<Sample>* out, bool flush) {
  while (!ins_.empty()) {
    const InsInput& s = ins_.front();
    const bool later_rudder = !rudder_.empty() && rudder_.back().stamp >= s.stamp;
    if (!(flush || later_rudder || newest_ins_ - s.stamp >= wait_)) break;
    Sample out_s;
    out_s.t = s.stamp;
    out_s.v = s.v_valid ? s.v : kNaN;
    out_s.r = s.r_valid ? s.r : kNaN;
    out_s.delta = delta_at(s.stamp);
    out->push_back(out_s);
    ins_.pop_front();
  }
}

// ---------------------------------------------------------------- FdiPipeline

FdiPipeline::FdiPipeline(const EngineConfig& cfg, const PipelineOptions& opt, EventSink on_event,
                         StatusSink on_status, LogSink on_log)
    : cfg_((cfg.validate(), cfg)),
      opt_(opt),
      on_event_(std::move(on_event)),
      on_status_(std::move(on_status)),
      on_log_(std::move(on_log)),
      input_(opt.input_capacity),
      ident_q_(opt.ident_capacity),
      output_(opt.output_capacity),
      iso_(cfg.isolation, cfg.B),
      assembler_(opt.rudder_wait, opt.rudder_timeout),
      ident_(cfg.identification, cfg.B),
      gate_(cfg.identification_delay) {}

FdiPipeline::~FdiPipeline() { stop(); }

void FdiPipeline::restore(const FaultEvent& ev) {
  latches_[static_cast<int>(ev.sensor)].restore(ev);
  restored_.push_back(ev);
}

void FdiPipeline::start() {
  if (started_) return;
  started_ = true;
  pub_thread_ = std::thread([this] { publisher_loop(); });
  ident_thread_ = std::thread([this] { identification_loop(); });
  iso_thread_ = std::thread([this] { isolation_loop(); });
}

void FdiPipeline::stop() {
  if (!started_ || stopped_) return;
  stopped_ = true;
  input_.shutdown();
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

void FdiPipeline::log(int level, const std::string& msg) const {
  if (on_log_) on_log_(level, msg);
}

void FdiPipeline::emit(const FaultEvent& ev) { output_.push(ev); }

void FdiPipeline::process(const Sample& s) {
  std::vector<Detection> dets;
  const bool ok = iso_.update(s, &dets);
  for (const Detection& d : dets) {
    FaultEvent ev;
    if (latches_[static_cast<int>(d.sensor)].on_detection(d, iso_estimate_.A, &ev)) emit(ev);
  }
  if (!ok) {
    ++rejected_;
    return;
  }
  ++samples_;
  last_t_ = s.t;
  if (opt_.lockstep) {
    std::unique_lock<std::mutex> lock(step_m_);
    ++ident_pushed_;
    ident_q_.push(IdentItem{s, iso_.freeze_requested()});
    step_cv_.wait(lock, [&] { return ident_done_ >= ident_pushed_; });
  } else {
    ident_q_.push(IdentItem{s, iso_.freeze_requested()});
  }
  bool updated = false;
  {
    std::lock_guard<std::mutex> lock(snap_m_);
    if (snapshot_version_ != seen_version_) {
      iso_estimate_ = snapshot_;
      seen_version_ = snapshot_version_;
      updated = true;
    }
  }
  if (updated) iso_.set_estimate(iso_estimate_);
}

void FdiPipeline::handle_ack(const AckInput& a) {
  FaultEvent ev;
  if (!opt_.authorised_operators.empty() &&
      std::find(opt_.authorised_operators.begin(), opt_.authorised_operators.end(), a.who) ==
          opt_.authorised_operators.end()) {
    log(2, std::string("ack of ") + to_string(a.sensor) + " #" + std::to_string(a.sequence) +
               " refused: operator '" + a.who + "' is not authorised");
    return;
  }
  if (static_cast<int>(a.sensor) > 2) {
    log(2, "ack refused: unknown sensor " + std::to_string(static_cast<int>(a.sensor)));
    return;
  }
  FaultLatch& latch = latches_[static_cast<int>(a.sensor)];
  const std::uint64_t current = latch.current().sequence;
  const AckResult r = latch.acknowledge(a.sequence, last_t_, a.who, &ev);
  if (r == AckResult::kAccepted) {
    log(1, std::string("ack of ") + to_string(a.sensor) + " #" + std::to_string(a.sequence) +
               " by " + a.who + " accepted");
    emit(ev);
  } else {
    log(2, std::string("ack of ") + to_string(a.sensor) + " #" + std::to_string(a.sequence) +
               " by " + a.who + " refused: " + to_string(r) + " (current #" +
               std::to_string(current) + ", state " + to_string(latch.state()) + ")");
  }
}

PipelineStatus FdiPipeline::make_status() const {
  PipelineStatus st;
  st.stamp = last_t_;
  st.estimate = iso_estimate_;
  st.isolation = iso_.status();
  st.samples = samples_.load();
  st.rejected = rejected_.load();
  st.dropped_inputs = input_.dropped();
  st.dropped_ident = ident_q_.dropped();
  st.dropped_output = output_.dropped() + dropped_at_stop_.load();
  st.ins_silent = ins_silent_.load();
  st.rudder_missing = !st.isolation.input.delta_ok;
  return st;
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
  return st;
}

void FdiPipeline::isolation_loop() {
  using Clock = std::chrono::steady_clock;
  for (const FaultEvent& ev : restored_) emit(ev);
  auto last_status = Clock::now();
  auto last_ins = Clock::now();
  bool had_ins = false;
  std::vector<Sample> batch;
  const auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  for (;;) {
    Input in;
    const auto r = input_.pop_for(&in, std::chrono::milliseconds(50));
    if (r == BoundedQueue<Input>::PopResult::kShutdown) break;
    const auto now = Clock::now();
    if (r == BoundedQueue<Input>::PopResult::kValue) {
      if (const auto* ins = std::get_if<InsInput>(&in)) {
        assembler_.add_ins(*ins);
        last_ins = now;
        had_ins = true;
        if (ins_silent_.exchange(false)) log(1, "INS samples arrive again");
      } else if (const auto* rud = std::get_if<RudderInput>(&in)) {
        assembler_.add_rudder(*rud);
      } else {
        handle_ack(std::get<AckInput>(in));
      }
      batch.clear();
      assembler_.drain(&batch);
      for (const Sample& s : batch) process(s);
    }
    if (had_ins && !ins_silent_ && seconds(now - last_ins) > opt_.input_timeout) {
      ins_silent_ = true;
      log(2, "no INS sample for " + std::to_string(seconds(now - last_ins)) + " s");
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
  const PipelineStatus st = make_status();
  std::lock_guard<std::mutex> lock(snap_m_);
  last_status_ = st;
}

void FdiPipeline::identification_loop() {
  IdentItem it;
  double last_snapshot = -1e300;
  bool last_converged = false;
  while (ident_q_.pop(&it)) {
    gate_.push(it.s, it.freeze);
    Sample old;
    bool freeze = false;
    bool updated = false;
    while (gate_.pop(&old, &freeze)) {
      ident_.update(old, freeze);
      updated = true;
    }
    const Estimate& e = ident_.estimate();
    if (updated && (e.t - last_snapshot >= opt_.snapshot_period || e.converged != last_converged)) {
      std::lock_guard<std::mutex> lock(snap_m_);
      snapshot_ = e;
      ++snapshot_version_;
      last_snapshot = e.t;
      last_converged = e.converged;
    }
    if (opt_.lockstep) {
      {
        std::lock_guard<std::mutex> lock(step_m_);
        ++ident_done_;
      }
      step_cv_.notify_all();
    }
  }
}

void FdiPipeline::publisher_loop() {
  Output o;
  while (output_.pop(&o)) {
    const std::int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                    std::chrono::steady_clock::now().time_since_epoch())
                                    .count();
    if (now_ns > drain_deadline_ns_.load()) {
      ++dropped_at_stop_;  // stop() is waiting: never block shutdown on a slow writer
      continue;
    }
    try {
      if (const auto* ev = std::get_if<FaultEvent>(&o)) {
        if (on_event_) on_event_(*ev);
      } else if (on_status_) {
        on_status_(std::get<PipelineStatus>(o));
      }
    } catch (const std::exception& e) {
      log(3, std::string("publishing failed: ") + e.what());
    }
  }
  if (dropped_at_stop_.load() > 0) {
    log(2, std::to_string(dropped_at_stop_.load()) +
               " queued events/status not published: the writer was too slow at stop");
  }
}

}  // namespace usvfdi
