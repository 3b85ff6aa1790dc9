#include "metrics.hpp"

#include <prometheus/counter.h>
#include <prometheus/gauge.h>
#include <prometheus/registry.h>
#include <prometheus/text_serializer.h>

#include <algorithm>
#include <limits>
#include <set>

namespace usvfdi::app::dashboard {

namespace {

prometheus::Family<prometheus::Gauge>& gauge(prometheus::Registry& reg, const char* name,
                                             const char* help) {
  return prometheus::BuildGauge().Name(name).Help(help).Register(reg);
}

bool active(FaultState s) {
  return s == FaultState::kRaised || s == FaultState::kActiveAcknowledged;
}

bool unacknowledged(FaultState s) {
  return s == FaultState::kRaised || s == FaultState::kClearedUnacknowledged;
}

}  // namespace

std::string fleet_metrics(const BoardInput& in, const EventHistory& events,
                          const std::deque<AckOutcome>& acks) {
  prometheus::Registry reg;
  const std::set<std::uint32_t> mmsis = board_vessels(in);

  gauge(reg, "usv_fdi_fleet_vessels", "vessels on the board (heard, latched or on the roster)")
      .Add({})
      .Set(static_cast<double>(mmsis.size()));
  auto& silent = gauge(reg, "usv_fdi_fleet_silent", "1: silent or never heard; 0: heard lately");
  auto& heard = gauge(reg, "usv_fdi_fleet_heard_age_seconds",
                      "seconds since the vessel was last heard (+Inf: never)");
  for (const std::uint32_t m : mmsis) {
    const std::map<std::string, std::string> l{{"mmsi", std::to_string(m)}};
    const auto age = in.heard_age.find(m);
    const auto sil = in.silent.find(m);
    const bool never = age == in.heard_age.end() ||
                       std::find(in.roster_never_heard.begin(), in.roster_never_heard.end(), m) !=
                           in.roster_never_heard.end();
    silent.Add(l).Set(never || (sil != in.silent.end() && sil->second) ? 1.0 : 0.0);
    heard.Add(l).Set(age == in.heard_age.end() ? std::numeric_limits<double>::infinity()
                                               : age->second);
  }

  auto& act = gauge(reg, "usv_fdi_fleet_fault_active", "1 while the latched instance is active");
  auto& unack = gauge(reg, "usv_fdi_fleet_fault_unacknowledged",
                      "1 while the latched instance waits for an acknowledgement");
  for (const auto& [key, row] : in.rows) {
    const std::map<std::string, std::string> l{{"mmsi", std::to_string(row.mmsi)},
                                               {"sensor", to_string(row.ev.sensor)}};
    act.Add(l).Set(active(row.ev.state) ? 1.0 : 0.0);
    unack.Add(l).Set(unacknowledged(row.ev.state) ? 1.0 : 0.0);
  }
  auto& raises = prometheus::BuildCounter()
                     .Name("usv_fdi_fleet_raises_total")
                     .Help("fault raises this dashboard has seen")
                     .Register(reg);
  for (const auto& [key, n] : events.raises()) {
    raises
        .Add({{"mmsi", std::to_string(key.first)},
              {"sensor", to_string(static_cast<Sensor>(key.second))}})
        .Increment(static_cast<double>(n));
  }

  auto& conv = gauge(reg, "usv_fdi_fleet_converged", "1: the vessel's estimate of A converged");
  auto& armed = gauge(reg, "usv_fdi_fleet_armed", "1: the vessel's residual detection is armed");
  for (const auto& [m, v] : in.statuses) {
    const std::map<std::string, std::string> l{{"mmsi", std::to_string(m)}};
    conv.Add(l).Set(v.st.converged() ? 1.0 : 0.0);
    armed.Add(l).Set(v.st.armed() ? 1.0 : 0.0);
  }
  prometheus::BuildCounter()
      .Name("usv_fdi_fleet_writer_conflicts_total")
      .Help(
          "samples of another writer than an instance's owner (a second sidecar, a writer for "
          "another vessel, an owner change) reported since the start")
      .Register(reg)
      .Add({})
      .Increment(in.conflicts);

  auto& ack = gauge(reg, "usv_fdi_dashboard_acks",
                    "acknowledgements asked from this dashboard (the last 100 kept), by state");
  std::map<std::string, int> by_state{
      {"pending", 0}, {"accepted", 0}, {"refused", 0}, {"unconfirmed", 0}};
  for (const AckOutcome& a : acks) ++by_state[a.state];
  for (const auto& [state, n] : by_state) ack.Add({{"state", state}}).Set(n);

  return prometheus::TextSerializer().Serialize(reg.Collect());
}

}  // namespace usvfdi::app::dashboard
