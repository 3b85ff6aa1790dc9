#include "usv_fdi/metrics/metrics.hpp"

#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/registry.h>

#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

namespace usvfdi::metrics {

namespace {

using prometheus::Counter;
using prometheus::Gauge;
using prometheus::Labels;

/// The sensor's (or residual channel's) label value: core's name of the Sensor, index i.
const char* sensor_name(int i) { return to_string(static_cast<Sensor>(i)); }

/// A counter that follows a total counted elsewhere (prometheus-cpp counters only increase).
struct FollowedCounter {
  Counter* counter = nullptr;
  double last = 0.0;
  void follow(std::uint64_t total) {
    const auto x = static_cast<double>(total);
    if (x > last) counter->Increment(x - last);
    last = x;
  }
};

}  // namespace

struct SidecarMetrics::Impl {
  std::shared_ptr<prometheus::Registry> registry = std::make_shared<prometheus::Registry>();
  std::unique_ptr<prometheus::Exposer> exposer;
  Labels vessel;

  std::array<FollowedCounter, 3> raises;  // by Sensor: accelerometer, gyro, unknown
  std::array<Gauge*, 2> statistic{}, threshold{}, confidence{};
  Gauge *converged = nullptr, *armed = nullptr, *mismatch = nullptr;
  Gauge *ident_paused = nullptr, *iso_paused = nullptr;
  Gauge *ins_age = nullptr, *rudder_age = nullptr;
  std::array<Gauge*, 3> thread_age{};  // isolation, identification, publisher
  FollowedCounter samples, rejected;
  std::array<FollowedCounter, 3> dropped;  // input, identification, output
  std::array<FollowedCounter, 2> lost;     // ins, rudder

  Labels with(const char* key, const char* value) const {
    Labels l = vessel;
    l[key] = value;
    return l;
  }
  Gauge* gauge(const char* name, const char* help, const Labels& labels) {
    return &prometheus::BuildGauge().Name(name).Help(help).Register(*registry).Add(labels);
  }
  Counter* counter(const char* name, const char* help, const Labels& labels) {
    return &prometheus::BuildCounter().Name(name).Help(help).Register(*registry).Add(labels);
  }
};

SidecarMetrics::SidecarMetrics(const std::string& bind, std::uint32_t mmsi)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.vessel = {{"mmsi", std::to_string(mmsi)}};
  for (int i = 0; i < 3; ++i) {
    m.raises[i].counter =
        m.counter("usv_fdi_raises_total", "Faults raised by this run of the sidecar, per sensor",
                  m.with("sensor", sensor_name(i)));
  }
  for (int c = 0; c < 2; ++c) {
    m.statistic[c] = m.gauge("usv_fdi_statistic", "Windowed residual statistic J_N, per channel",
                             m.with("channel", sensor_name(c)));
    m.threshold[c] =
        m.gauge("usv_fdi_threshold", "Enter threshold on J_N, per channel (0 before arming)",
                m.with("channel", sensor_name(c)));
    m.confidence[c] = m.gauge("usv_fdi_isolation_confidence", "Isolation confidence C_a, C_g",
                              m.with("sensor", sensor_name(c)));
  }
  m.converged = m.gauge("usv_fdi_converged", "1 while the estimate of A has converged", m.vessel);
  m.armed = m.gauge("usv_fdi_armed", "1 while model-based detection is armed", m.vessel);
  m.mismatch = m.gauge("usv_fdi_model_mismatch",
                       "1 while the residuals contradict the model on both channels", m.vessel);
  m.ident_paused = m.gauge("usv_fdi_identification_paused",
                           "PauseReason bits of identification (0: identifying)", m.vessel);
  m.iso_paused =
      m.gauge("usv_fdi_isolation_paused", "PauseReason bits of isolation (0: detecting)", m.vessel);
  const char* age_help = "Wall-clock seconds since the last sample of the input (+Inf: none yet)";
  m.ins_age = m.gauge("usv_fdi_input_age_seconds", age_help, m.with("input", "ins"));
  m.rudder_age = m.gauge("usv_fdi_input_age_seconds", age_help, m.with("input", "rudder"));
  // No sample yet: +Inf, so that an alert on the age (usv_fdi_input_age_seconds > 5) fires
  // for a sidecar that never heard its INS (NaN would compare false).
  m.ins_age->Set(std::numeric_limits<double>::infinity());
  m.rudder_age->Set(std::numeric_limits<double>::infinity());
  const char* threads[3] = {"isolation", "identification", "publisher"};
  for (int i = 0; i < 3; ++i) {
    m.thread_age[i] =
        m.gauge("usv_fdi_thread_age_seconds",
                "Wall-clock seconds since the pipeline thread last went round its loop",
                m.with("thread", threads[i]));
  }
  m.samples.counter = m.counter("usv_fdi_samples_total", "Samples assembled", m.vessel);
  m.rejected.counter =
      m.counter("usv_fdi_rejected_samples_total", "Samples refused for their time stamp", m.vessel);
  const char* queues[3] = {"input", "identification", "output"};
  for (int i = 0; i < 3; ++i) {
    m.dropped[i].counter =
        m.counter("usv_fdi_dropped_samples_total", "Samples or events dropped by a full queue",
                  m.with("queue", queues[i]));
  }
  const char* inputs[2] = {"ins", "rudder"};
  for (int i = 0; i < 2; ++i) {
    m.lost[i].counter = m.counter("usv_fdi_lost_samples_total",
                                  "Samples lost before they reached the sidecar (sequence gaps)",
                                  m.with("input", inputs[i]));
  }
  try {
    m.exposer = std::make_unique<prometheus::Exposer>(bind);
  } catch (const std::exception& e) {
    throw std::runtime_error("metrics: cannot listen on '" + bind + "': " + e.what());
  }
  m.exposer->RegisterCollectable(m.registry);
}

SidecarMetrics::~SidecarMetrics() = default;

std::vector<int> SidecarMetrics::ports() const { return impl_->exposer->GetListeningPorts(); }

void SidecarMetrics::update(const pipeline::PipelineStatus& st,
                            const pipeline::PipelineLiveness& live) {
  Impl& m = *impl_;
  for (std::size_t i = 0; i < 3; ++i) m.raises[i].follow(st.raises[i]);
  const IsolatorStatus& iso = st.isolation;
  for (int c = 0; c < 2; ++c) {
    m.statistic[c]->Set(iso.J(c));
    m.threshold[c]->Set(iso.thresholds(c));
  }
  m.confidence[0]->Set(iso.c_a);
  m.confidence[1]->Set(iso.c_g);
  m.converged->Set(st.estimate.converged ? 1.0 : 0.0);
  m.armed->Set(iso.armed ? 1.0 : 0.0);
  m.mismatch->Set(iso.model_mismatch ? 1.0 : 0.0);
  m.ident_paused->Set(st.identification_paused);
  m.iso_paused->Set(st.isolation_paused);
  const auto age = [](double a) { return a < 0 ? std::numeric_limits<double>::infinity() : a; };
  m.ins_age->Set(age(live.ins_age));
  m.rudder_age->Set(age(live.rudder_age));
  m.thread_age[0]->Set(live.isolation);
  m.thread_age[1]->Set(live.identification);
  m.thread_age[2]->Set(live.publisher);
  m.samples.follow(st.samples);
  m.rejected.follow(st.rejected);
  m.dropped[0].follow(st.dropped_inputs);
  m.dropped[1].follow(st.dropped_ident);
  m.dropped[2].follow(st.dropped_output);
  m.lost[0].follow(st.lost_ins);
  m.lost[1].follow(st.lost_rudder);
}

}  // namespace usvfdi::metrics
