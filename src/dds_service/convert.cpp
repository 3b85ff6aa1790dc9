#include "usv_fdi/dds_service/convert.hpp"

#include "usv_fdi/core/text.hpp"

#include <string>

namespace usvfdi::dds_service {

// The pipeline's flag values are the IDL's constants (FdiStatus carries them as they are).
static_assert(pipeline::kInputInsSilent == fdi::INPUT_INS_SILENT &&
                  pipeline::kInputRudderMissing == fdi::INPUT_RUDDER_MISSING &&
                  pipeline::kInputAccelUnusable == fdi::INPUT_ACCELEROMETER_UNUSABLE &&
                  pipeline::kInputGyroUnusable == fdi::INPUT_GYRO_UNUSABLE &&
                  pipeline::kInputBadTimestamps == fdi::INPUT_BAD_TIMESTAMPS &&
                  pipeline::kInputInvalidValues == fdi::INPUT_INVALID_VALUES &&
                  pipeline::kInputGaps == fdi::INPUT_GAPS &&
                  pipeline::kInputReordered == fdi::INPUT_REORDERED &&
                  pipeline::kInputQueueDrops == fdi::INPUT_QUEUE_DROPS &&
                  pipeline::kInputSamplesLost == fdi::INPUT_SAMPLES_LOST &&
                  pipeline::kInputOtherEventWriter == fdi::INPUT_OTHER_EVENT_WRITER,
              "InputFlag differs from idl/usv_fdi.idl INPUT_*");
static_assert(pipeline::kPauseNotArmed == fdi::PAUSE_NOT_ARMED &&
                  pipeline::kPauseLearning == fdi::PAUSE_LEARNING &&
                  pipeline::kPauseRudderMissing == fdi::PAUSE_RUDDER_MISSING &&
                  pipeline::kPauseInsUnusable == fdi::PAUSE_INS_UNUSABLE &&
                  pipeline::kPauseInsSilent == fdi::PAUSE_INS_SILENT &&
                  pipeline::kPauseFault == fdi::PAUSE_FAULT &&
                  pipeline::kPauseObserver == fdi::PAUSE_OBSERVER &&
                  pipeline::kPauseModelMismatch == fdi::PAUSE_MODEL_MISMATCH,
              "PauseReason differs from idl/usv_fdi.idl PAUSE_*");

fdi::FaultEvent to_dds(const FaultEvent& e, std::uint32_t mmsi) {
  fdi::FaultEvent d;
  d.mmsi(mmsi);
  d.sensor(static_cast<std::uint8_t>(e.sensor));
  d.state(static_cast<std::uint8_t>(e.state));
  d.kind(static_cast<std::uint8_t>(e.kind));
  d.c_a(e.c_a);
  d.c_g(e.c_g);
  d.statistic(e.statistic);
  d.threshold(e.threshold);
  d.onset_time(e.onset_time);
  d.detection_time(e.detection_time);
  d.stamp(e.t);
  d.sequence(e.sequence);
  d.incarnation(e.incarnation);
  d.a({e.A(0, 0), e.A(0, 1), e.A(1, 0), e.A(1, 1)});
  d.message(e.message.substr(0, 127).c_str());
  return d;
}

bool from_dds(const fdi::FaultEvent& d, FaultEvent* out) {
  if (d.sensor() > static_cast<std::uint8_t>(Sensor::kUnknown) ||
      d.state() > static_cast<std::uint8_t>(FaultState::kAcknowledged) ||
      d.kind() > static_cast<std::uint8_t>(FaultKind::kInvalid)) {
    return false;
  }
  FaultEvent e;
  e.sensor = static_cast<Sensor>(d.sensor());
  e.state = static_cast<FaultState>(d.state());
  e.kind = static_cast<FaultKind>(d.kind());
  e.c_a = d.c_a();
  e.c_g = d.c_g();
  e.statistic = d.statistic();
  e.threshold = d.threshold();
  e.onset_time = d.onset_time();
  e.detection_time = d.detection_time();
  e.t = d.stamp();
  e.sequence = d.sequence();
  e.incarnation = d.incarnation();
  e.A << d.a()[0], d.a()[1], d.a()[2], d.a()[3];
  e.message = escape_text(d.message().to_string());  // a peer's text: never raw
  *out = e;
  return true;
}

fdi::FdiStatus to_dds(const pipeline::PipelineStatus& s, std::uint32_t mmsi,
                      const IsolationParams& p) {
  fdi::FdiStatus d;
  d.mmsi(mmsi);
  d.stamp(s.stamp);
  const Mat2& A = s.estimate.A;
  d.a({A(0, 0), A(0, 1), A(1, 0), A(1, 1)});
  d.converged(s.estimate.converged);
  d.armed(s.isolation.armed);
  d.excitation(s.estimate.excitation);
  d.sigma_v(s.isolation.sigma_s(0));
  d.sigma_r(s.isolation.sigma_s(1));
  d.poles_v({p.poles_v(0), p.poles_v(1)});
  d.poles_g({p.poles_g(0), p.poles_g(1)});
  const InputHealth& in = s.isolation.input;
  d.ins_healthy(!s.ins_silent && in.v_ok && in.r_ok);
  d.rudder_healthy(in.delta_ok);
  d.samples(s.samples);
  d.dropped(s.dropped_inputs + s.dropped_ident + s.dropped_output);
  d.input_flags(s.input_flags);
  d.rejected_timestamps(s.rejected_timestamps);
  d.invalid_values(s.invalid_values);
  d.gaps(s.gaps);
  d.reordered(s.reordered);
  d.dropped_inputs(s.dropped_inputs);
  d.lost_ins(s.lost_ins);
  d.lost_rudder(s.lost_rudder);
  d.acks_refused(s.acks_refused);
  d.acks_dropped(s.acks_dropped);
  d.incarnation(s.incarnation);
  d.identification_paused(s.identification_paused);
  d.isolation_paused(s.isolation_paused);
  d.surge_speed(s.surge_speed);
  d.speed_ratio(s.estimate.speed_ratio);
  d.reference_speed(s.estimate.reference_speed);
  d.j_peak({s.j_peak[0], s.j_peak[1]});
  d.j_raise({s.j_raise[0], s.j_raise[1]});
  d.j_leave({s.j_leave[0], s.j_leave[1]});
  d.c_a(s.isolation.c_a);
  d.c_g(s.isolation.c_g);
  d.model_mismatch(s.isolation.model_mismatch);
  std::string msg;
  // First, so that the 128 characters keep it: the residuals contradict the model.
  if (s.isolation.model_mismatch) {
    msg += "model mismatch, not a sensor fault (" + std::to_string(s.isolation.mismatches) +
           " so far): " + s.isolation.mismatch_reason + "; ";
  }
  if (s.ins_silent) msg += "INS silent; ";
  if (!in.delta_ok) msg += "rudder missing: identification and isolation paused; ";
  if (!in.v_ok) msg += "accelerometer channel unusable; ";
  if (!in.r_ok) msg += "gyro channel unusable; ";
  if (!s.isolation.observer_problem.empty()) msg += s.isolation.observer_problem + "; ";
  if (!s.isolation.armed) {
    // Why A has not converged, in words ("identifying A: excitation too low").
    std::string why = to_string(s.estimate.status);
    const std::string prefix = "not converged: ";
    if (why.rfind(prefix, 0) == 0) why = why.substr(prefix.size());
    msg += s.estimate.converged ? "converged, arming; " : "identifying A: " + why + "; ";
  } else if (s.isolation.learning || s.isolation.settling) {
    msg += "armed, learning healthy statistics; ";
  } else {
    msg += "armed; ";
    if (s.isolation.design_held) {
      msg += "estimate of A lost convergence: observer design held; ";
    }
    // (said, because the channel's residual path is closed until then)
    for (int c = 0; c < 2; ++c) {
      if (s.isolation.awaiting_onset[c]) {
        msg += std::string(c == 0 ? "accelerometer" : "gyro") +
               " residual above its bar since going live: raises nothing until it falls; ";
      } else if (s.isolation.bar_unreachable[c]) {
        msg += std::string(c == 0 ? "accelerometer" : "gyro") +
               " residual bar out of J_N's reach: raises nothing; ";
      }
    }
  }
  if (s.identification_paused & pipeline::kPauseFault) msg += "identification frozen (fault); ";
  if (s.rejected > 0) msg += std::to_string(s.rejected) + " samples rejected; ";
  if (s.lost_ins + s.lost_rudder > 0)
    msg += std::to_string(s.lost_ins + s.lost_rudder) + " samples lost; ";
  d.message(msg.substr(0, 127).c_str());
  return d;
}

pipeline::InsInput from_dds(const fdi::InsSample& s) {
  return pipeline::InsInput{s.stamp(), s.v(), s.r(), s.v_valid(), s.r_valid(), s.seq()};
}

pipeline::RudderInput from_dds(const fdi::RudderSample& s) {
  return pipeline::RudderInput{s.stamp(), s.delta(), s.valid(), s.seq()};
}

pipeline::SpeedInput from_dds(const fdi::SpeedSample& s) {
  return pipeline::SpeedInput{s.stamp(), s.u(), s.valid()};
}

pipeline::AckInput from_dds(const fdi::FaultAck& a) {
  pipeline::AckInput out;
  out.sensor = static_cast<Sensor>(a.sensor());
  out.sequence = a.sequence();
  out.who = escape_text(a.operator_id().to_string());  // a peer's text: never raw
  out.incarnation = a.incarnation();
  return out;
}

}  // namespace usvfdi::dds_service
