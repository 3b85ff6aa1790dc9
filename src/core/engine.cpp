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

FdiEngine::FdiEngine(const EngineConfig& cfg)
    : cfg_(cfg),
      ident_((cfg.validate(), cfg.identification), cfg.B),
      iso_(cfg.isolation, cfg.B),
      gate_(cfg.identification_delay) {}

bool FdiEngine::process(const Sample& s, std::vector<FaultEvent>* events) {
  detections_.clear();
  const bool accepted = iso_.update(s, &detections_);
  // Even a rejected sample may raise a timing fault.
  for (const Detection& d : detections_) {
    FaultEvent ev;
    if (latches_[static_cast<int>(d.sensor)].on_detection(d, ident_.estimate().A, &ev)) {
      events->push_back(ev);
    }
  }
  if (!accepted) return false;
  gate_.push(s, iso_.freeze_requested());
  const IsolatorStatus& st = iso_.status();
  ident_.set_supervised(st.armed && !st.learning && !st.settling);
  Sample old;
  bool freeze = false;
  bool updated = false;
  while (gate_.pop(&old, &freeze)) {
    if (freeze) ++frozen_samples_;
    ident_.update(old, freeze);
    updated = true;
  }
  if (updated) iso_.set_estimate(ident_.estimate());
  return true;
}

AckResult FdiEngine::acknowledge(Sensor sensor, std::uint64_t sequence, double t,
                                 const std::string& who, FaultEvent* event) {
  return latches_[static_cast<int>(sensor)].acknowledge(sequence, t, who, event);
}

}  // namespace usvfdi
