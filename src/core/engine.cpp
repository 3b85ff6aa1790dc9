#include "usv_fdi/core/engine.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace usvfdi {

void EngineConfig::validate() const {
  if (!B.allFinite() || B.isZero(0.0)) {
    throw std::invalid_argument("model.B = [" + std::to_string(B(0)) + ", " + std::to_string(B(1)) +
                                "]: must be finite and non-zero");
  }
  if (!(identification_delay >= 0) || !std::isfinite(identification_delay)) {
    throw std::invalid_argument("identification.delay = " + std::to_string(identification_delay) +
                                ": must be >= 0");
  }
  if (!(clock_max_jump > 0) || !std::isfinite(clock_max_jump)) {
    throw std::invalid_argument("clock.max_jump = " + std::to_string(clock_max_jump) +
                                ": must be > 0 and finite");
  }
  if (clock_confirm_samples < 2) {
    throw std::invalid_argument("clock.confirm_samples = " + std::to_string(clock_confirm_samples) +
                                ": must be >= 2");
  }
  identification.validate();
  isolation.validate();
  speed.validate();
}

SampleClock::Verdict SampleClock::check(double t) {
  if (std::isnan(last_) || follows(t, last_)) {
    last_ = t;
    candidate_count_ = 0;
    return Verdict::kAccept;
  }
  if (candidate_count_ > 0 && follows(t, candidate_last_)) {
    ++candidate_count_;
  } else {
    candidate_count_ = 1;
  }
  candidate_last_ = t;
  if (candidate_count_ < confirm_) return Verdict::kReject;
  resync_from_ = last_;
  last_ = t;
  candidate_count_ = 0;
  ++resyncs_;
  return Verdict::kResync;
}

void IdentificationGate::push(const Sample& s, bool freeze_requested) {
  if (freeze_requested) last_freeze_t_ = s.t;
  newest_t_ = s.t;
  q_.push_back(s);
}

bool IdentificationGate::pop(Sample* s, bool* freeze) {
  if (q_.empty() || q_.front().t > newest_t_ - delay_) return false;
  *s = q_.front();
  q_.pop_front();
  *freeze = last_freeze_t_ >= s->t;
  return true;
}

IdentificationStage::IdentificationStage(const EngineConfig& cfg)
    : params_((cfg.validate(), cfg.identification)),
      B_(cfg.B),
      speed_(cfg.speed),
      delay_(cfg.identification_delay),
      ident_(params_, B_, speed_),
      gate_(delay_) {}

bool IdentificationStage::push(const IdentificationInput& in) {
  if (in.restart) {
    // A new time base: the filters, memories and the samples waiting in the gate belong to
    // the old one. The estimator starts afresh, as at start-up.
    // B is given at the reference speed: a new time base keeps it.
    if (std::isfinite(ident_.speed().reference_speed())) {
      speed_.reference_speed = ident_.speed().reference_speed();
    }
    ident_ = Identifier(params_, B_, speed_);
    gate_ = IdentificationGate(delay_);
  }
  gate_.push(in.sample, in.freeze);
  ident_.set_supervised(in.supervised);
  Sample old;
  bool freeze = false;
  bool updated = false;
  while (gate_.pop(&old, &freeze)) {
    if (freeze) ++frozen_samples_;
    ident_.update(old, freeze);
    updated = true;
  }
  return updated;
}

IsolationStage::IsolationStage(const EngineConfig& cfg)
    : params_((cfg.validate(), cfg.isolation)),
      B_(cfg.B),
      speed_(cfg.speed),
      clock_(cfg.clock_max_jump, cfg.clock_confirm_samples),
      iso_(params_, B_, speed_) {}

void IsolationStage::restart(const Sample& s) {
  if (std::isfinite(iso_.speed().reference_speed())) {
    speed_.reference_speed = iso_.speed().reference_speed();
  }
  iso_ = Isolator(params_, B_, speed_);
  estimate_ = Estimate{};
  estimate_.t = s.t;
}

namespace {
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
}  // namespace

bool IsolationStage::process(const Sample& s, std::vector<FaultEvent>* events,
                             IdentificationInput* handover) {
  detections_.clear();
  // One sample delivered twice is dropped; a third copy is a clock that stands still.
  last_duplicate_ = !repeated_ && std::isfinite(s.t) && s.t == last_accepted_.t &&
                    same(s.v, last_accepted_.v) && same(s.r, last_accepted_.r) &&
                    same(s.delta, last_accepted_.delta) && same(s.u, last_accepted_.u);
  if (last_duplicate_) {
    ++duplicates_;
    repeated_ = true;
    return false;
  }
  SampleClock::Verdict verdict = SampleClock::Verdict::kAccept;
  if (std::isfinite(s.t)) verdict = clock_.check(s.t);
  if (verdict == SampleClock::Verdict::kResync) restart(s);
  const bool accepted = verdict == SampleClock::Verdict::kReject
                            ? iso_.reject_timestamp(&detections_)
                            : iso_.update(s, &detections_);
  if (!accepted) ++rejected_;
  // Even a rejected sample may raise a timing fault.
  for (const Detection& d : detections_) {
    FaultEvent ev;
    if (apply(d, &ev)) events->push_back(ev);
  }
  if (!accepted) return false;
  last_accepted_ = s;
  repeated_ = false;
  const IsolatorStatus& st = iso_.status();
  handover->sample = s;
  handover->freeze = iso_.freeze_requested();
  handover->supervised = st.armed && !st.learning && !st.settling;
  handover->restart = verdict == SampleClock::Verdict::kResync;
  return true;
}

void IsolationStage::set_estimate(const Estimate& est) {
  estimate_ = est;
  iso_.set_estimate(estimate_);
}

bool IsolationStage::apply(const Detection& d, FaultEvent* event) {
  return latches_[static_cast<int>(d.sensor)].on_detection(d, estimate_.A, event);
}

AckResult IsolationStage::acknowledge(Sensor sensor, std::uint64_t sequence, double t,
                                      const std::string& who, FaultEvent* event) {
  return latches_[static_cast<int>(sensor)].acknowledge(sequence, t, who, event);
}

FdiEngine::FdiEngine(const EngineConfig& cfg) : iso_(cfg), ident_(cfg) {}

bool FdiEngine::process(const Sample& s, std::vector<FaultEvent>* events) {
  IdentificationInput handover;
  if (!iso_.process(s, events, &handover)) return false;
  if (ident_.push(handover)) iso_.set_estimate(ident_.estimate());
  return true;
}

}  // namespace usvfdi
