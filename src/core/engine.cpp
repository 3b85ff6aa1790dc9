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
  identification.validate();
  isolation.validate();
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
    : ident_((cfg.validate(), cfg.identification), cfg.B), gate_(cfg.identification_delay) {}

bool IdentificationStage::push(const IdentificationInput& in) {
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
    : iso_((cfg.validate(), cfg.isolation), cfg.B) {}

bool IsolationStage::process(const Sample& s, std::vector<FaultEvent>* events,
                             IdentificationInput* handover) {
  detections_.clear();
  const bool accepted = iso_.update(s, &detections_);
  // Even a rejected sample may raise a timing fault.
  for (const Detection& d : detections_) {
    FaultEvent ev;
    if (apply(d, &ev)) events->push_back(ev);
  }
  if (!accepted) return false;
  const IsolatorStatus& st = iso_.status();
  handover->sample = s;
  handover->freeze = iso_.freeze_requested();
  handover->supervised = st.armed && !st.learning && !st.settling;
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
