// Benchmark of the status uplink (issue 13, section 5: a frugal uplink), not a test.
//
//   usv-fdi-bench-uplink [--hulls otter,container,...] [--hours H] [--rate HZ] [--seed S]
//                        [--config config/default.yaml] [--tolerance T] [--theta T]
//                        [--decay L] [--heartbeat S] [--excitation-weight W]
//
// For each hull and two voyages of the proving ground's simulator (every manoeuvre, sea state
// 3, wind, current, MEMS-grade sensors; "healthy", and "faults": the standard fault set from
// 600 s on, one fault every 90 s), the engine (config/default.yaml, only B from the hull's
// linearisation, the surge speed given) runs over the voyage in source time; every second of
// it the sidecar's status is made as the sidecar makes it (pipeline::PipelineStatus ->
// dds_service::to_dds, the transport's counters zero) and offered, side by side, to three
// uplinks: periodic (every status, today's sidecar before this change), static event
// triggering (theta = infinity) and dynamic event triggering (the default). Every fault event
// the engine issues is acknowledged at once (so that latches cycle) and counted for all three:
// events are always sent.
//
// Reported per voyage and uplink: statuses sent per hour and why; bytes per hour of DDS
// payload (the CDR serialisation of each sample, FdiStatusPubSubType / FaultEventPubSubType)
// and on the wire (payload plus the RTPS and UDP/IPv4 framing of one DATA message per sample,
// the piggybacked HEARTBEAT and the reader's ACKNACK, constants below); what the shore knows:
// the worst and 99th-percentile relative deviation of its last A-hat from the sidecar's, the
// evaluations at which the state it shows differed from the sidecar's (detector and input
// state, flags, pause reasons, the message word for word: compared field by field, not with the
// uplink's own rule), and the longest time without a status (evaluations a second apart give or
// take 50 ms, like the sidecar's wall clock; the silent-vessel verdict comes silent_after after
// the last status heard, so a vessel that stops is flagged no later than before).
// Exit code 0 when it completed (the 50 % target is reported, not enforced), 1 on error.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "runner.hpp"
#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/dds/types.hpp"
#include "usv_fdi/dds_service/convert.hpp"
#include "usv_fdi/dds_service/status_uplink.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/voyage.hpp"

using namespace usvfdi;
using dds_service::StatusUplink;
using dds_service::UplinkOptions;
using dds_service::UplinkReason;

namespace {

constexpr std::uint32_t kMmsi = 257000001;

// One RTPS DATA message with a keyed sample, as Fast DDS 2.9 sends it to one reader over
// UDPv4: IPv4 (20) + UDP (8) headers; RTPS header (20); INFO_TS (12); DATA submessage header
// and fixed part (4 + 20); inline QoS with the key hash (4 + 16) and the sentinel (4); the
// serialised payload padded to 4; a piggybacked HEARTBEAT (4 + 28). The reader answers with an
// ACKNACK: IPv4 + UDP (28), RTPS header (20), INFO_DST (16), ACKNACK (4 + 24 + 4).
constexpr std::size_t kDataFraming = 28 + 20 + 12 + 24 + 24 + 32;
constexpr std::size_t kAckNack = 28 + 20 + 16 + 32;

std::size_t padded(std::size_t n) { return (n + 3) / 4 * 4; }

template <typename PubSub, typename T>
std::size_t payload_size(const T& sample) {
  PubSub type;
  return type.getSerializedSizeProvider(const_cast<T*>(&sample))();
}

struct Tally {
  std::string name;
  UplinkOptions opt;
  std::unique_ptr<StatusUplink> uplink;
  fdi::FdiStatus shore;
  bool have = false;
  double last_sent = 0.0, longest_gap = 0.0;
  std::size_t sent = 0, payload = 0, wire = 0;
  std::size_t discrete_differs = 0;
  std::size_t by_a = 0;  ///< continuous sends mostly for A-hat
  std::vector<double> a_dev;
};

/// What the shore shows as the vessel's state, compared field by field (not with the uplink's
/// own rule): detector and input state, flags, pause reasons and the message word for word.
bool same_state(const fdi::FdiStatus& a, const fdi::FdiStatus& b) {
  return a.converged() == b.converged() && a.armed() == b.armed() &&
         a.ins_healthy() == b.ins_healthy() && a.rudder_healthy() == b.rudder_healthy() &&
         a.input_flags() == b.input_flags() &&
         a.identification_paused() == b.identification_paused() &&
         a.isolation_paused() == b.isolation_paused() && a.message() == b.message();
}

double a_deviation(const fdi::FdiStatus& shore, const fdi::FdiStatus& s) {
  double num = 0.0, den = 0.0;
  for (int i = 0; i < 4; ++i) {
    num += (s.a()[i] - shore.a()[i]) * (s.a()[i] - shore.a()[i]);
    den += shore.a()[i] * shore.a()[i];
  }
  return den > 0.0 ? std::sqrt(num / den) : 0.0;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
}

sim::VoyageConfig voyage(const sim::Hull& hull, bool faults, double hours, double rate,
                         std::uint64_t seed) {
  sim::VoyageConfig c = bench::voyage_config(hull, "voyage/sea3/mems");
  c.rate_hz = rate;
  c.duration = hours * 3600.0;
  c.seed = seed;
  if (faults) c.faults = sim::standard_faults(c, 600.0, 30.0, 60.0);
  return c;
}

void run(const std::string& hull_name, bool faults, const EngineConfig& base, double hours,
         double rate, std::uint64_t seed, const UplinkOptions& event) {
  const auto hull = sim::voyage_hull(hull_name);
  if (!hull) throw std::invalid_argument("no hull named '" + hull_name + "'");
  sim::Voyage v(hull, voyage(*hull, faults, hours, rate, seed));
  EngineConfig cfg = base;
  cfg.B = v.linearisation().B;
  FdiEngine engine(cfg);

  std::vector<Tally> tallies(3);
  tallies[0].name = "periodic";
  tallies[0].opt.event = false;
  tallies[1].name = "event, static";
  tallies[1].opt = event;
  tallies[1].opt.theta = 1e12;
  tallies[2].name = "event, dynamic";
  tallies[2].opt = event;
  for (Tally& t : tallies) t.uplink = std::make_unique<StatusUplink>(t.opt);

  std::size_t events = 0, event_payload = 0;
  std::vector<FaultEvent> out;
  sim::VoyageRow row;
  double next_tick = 1.0, last_u = kNaN, t_end = 0.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::uint64_t samples = 0;
  const auto count_event = [&](const FaultEvent& e) {
    ++events;
    event_payload += payload_size<fdi::FaultEventPubSubType>(dds_service::to_dds(e, kMmsi));
  };
  while (v.next(&row)) {
    out.clear();
    const Sample s{row.t, row.v, row.r, row.delta, row.u_true};
    if (engine.process(s, &out)) ++samples;
    last_u = row.u_true;
    t_end = row.t;
    for (const FaultEvent& e : out) {
      count_event(e);
      FaultEvent ack;
      if ((e.state == FaultState::kRaised || e.state == FaultState::kClearedUnacknowledged) &&
          engine.acknowledge(e.sensor, e.sequence, row.t, "bench", &ack) == AckResult::kAccepted) {
        count_event(ack);
      }
    }
    if (row.t < next_tick) continue;
    // The evaluation instant: the sidecar's wall clock, a second apart give or take 50 ms.
    const double tick = next_tick + jitter(rng);
    next_tick += 1.0;
    // The status the sidecar's publisher makes every second (PipelineStatus, pipeline.cpp).
    pipeline::PipelineStatus ps;
    ps.stamp = row.t;
    ps.surge_speed = last_u;
    ps.estimate = engine.estimate();
    ps.isolation = engine.isolation_status();
    ps.samples = samples;
    ps.rudder_missing = !ps.isolation.input.delta_ok;
    std::uint32_t f = 0;
    if (!ps.isolation.input.delta_ok) f |= pipeline::kInputRudderMissing;
    if (!ps.isolation.input.v_ok) f |= pipeline::kInputAccelUnusable;
    if (!ps.isolation.input.r_ok) f |= pipeline::kInputGyroUnusable;
    ps.input_flags = f;
    const fdi::FdiStatus d = dds_service::to_dds(ps, kMmsi, cfg.isolation);
    for (Tally& t : tallies) {
      const UplinkReason why = t.uplink->offer(d, tick);
      if (why == UplinkReason::kContinuous && t.have) {
        // Which value moved: A-hat, or the others (excitation, sigmas, speed).
        const double ea = a_deviation(t.shore, d), e = t.uplink->deviation(t.shore, d);
        if (ea * ea >= 0.5 * e * e) ++t.by_a;
      }
      if (why != UplinkReason::kNone) {
        if (t.have) t.longest_gap = std::max(t.longest_gap, tick - t.last_sent);
        t.shore = d;
        t.have = true;
        t.last_sent = tick;
        ++t.sent;
        const std::size_t p = payload_size<fdi::FdiStatusPubSubType>(d);
        t.payload += p;
        t.wire += kDataFraming + padded(p) + kAckNack;
      }
      if (!same_state(t.shore, d)) ++t.discrete_differs;
      t.a_dev.push_back(a_deviation(t.shore, d));
    }
  }
  const double h = t_end / 3600.0;
  std::printf(
      "\n%s, %s voyage (%.2f h at %g Hz, seed %llu): %zu fault events (%.0f B/h payload, "
      "sent by every uplink)\n",
      hull_name.c_str(), faults ? "faults" : "healthy", h, rate,
      static_cast<unsigned long long>(seed), events, event_payload / h);
  std::printf(
      "| uplink | statuses/h | first / discrete / continuous (of which A-hat) / heartbeat | status "
      "payload "
      "B/h | status wire B/h | vs periodic (payload, wire) | status+events wire B/h | "
      "A-hat deviation p99 / max | state differs | longest gap [s] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  const Tally& per = tallies[0];
  for (const Tally& t : tallies) {
    const auto& u = *t.uplink;
    const double ev_wire = static_cast<double>(events) * (kDataFraming + kAckNack) + event_payload;
    std::printf(
        "| %s | %.0f | %llu / %llu / %llu (%zu) / %llu | %.0f | %.0f | %+.1f %%, %+.1f %% | %.0f "
        "| %.4f / %.4f | %zu | %.1f |\n",
        t.name.c_str(), t.sent / h, static_cast<unsigned long long>(u.sent(UplinkReason::kFirst)),
        static_cast<unsigned long long>(u.sent(UplinkReason::kDiscrete)),
        static_cast<unsigned long long>(u.sent(UplinkReason::kContinuous)), t.by_a,
        static_cast<unsigned long long>(u.sent(UplinkReason::kHeartbeat)), t.payload / h,
        t.wire / h, 100.0 * (static_cast<double>(t.payload) / per.payload - 1.0),
        100.0 * (static_cast<double>(t.wire) / per.wire - 1.0), (t.wire + ev_wire) / h,
        quantile(t.a_dev, 0.99), quantile(t.a_dev, 1.0), t.discrete_differs, t.longest_gap);
  }
  std::fflush(stdout);
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"usv-fdi status uplink benchmark (issue 13, section 5)"};
  std::string hulls = "otter,container,kvlcc2";
  std::string config = std::string(USV_FDI_SOURCE_DIR) + "/config/default.yaml";
  double hours = 1.0, rate = 10.0;
  std::uint64_t seed = 1;
  app.add_option("--hulls", hulls, "comma-separated hulls of the voyage simulator");
  app.add_option("--hours", hours, "length of each voyage [h]")->check(CLI::PositiveNumber);
  app.add_option("--rate", rate, "sample rate [Hz]")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "voyage seed");
  app.add_option("--config", config, "engine configuration (B comes from each hull)");
  UplinkOptions d;
  app.add_option("--tolerance", d.tolerance, "event mode: sigma");
  app.add_option("--theta", d.theta, "event mode: theta");
  app.add_option("--decay", d.decay, "event mode: lambda");
  app.add_option("--heartbeat", d.heartbeat, "event mode: heartbeat [s]");
  app.add_option("--excitation-weight", d.excitation_weight, "event mode: excitation's weight");
  CLI11_PARSE(app, argc, argv);
  try {
    const EngineConfig base = io::load_engine_config(config);
    std::printf(
        "status uplink benchmark: statuses evaluated every 1 s of voyage; event mode "
        "tolerance %g, theta %g, decay %g (bound %.4f), heartbeat %g s\n",
        d.tolerance, d.theta, d.decay, StatusUplink(d).bound(), d.heartbeat);
    for (const std::string& h : split(hulls)) {
      run(h, false, base, hours, rate, seed, d);
      run(h, true, base, hours, rate, seed, d);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "usv-fdi-bench-uplink: %s\n", e.what());
    return 1;
  }
  return 0;
}
