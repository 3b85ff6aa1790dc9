// usv-fdi emulate: a fleet of N vessels at the DDS level, without N sidecars, so that the shore
// side (monitor, dashboard) can be measured at fleet scale.
//
// The vessels are spread over P participants (one DdsContext each, with the shipped FaultEvent
// and FdiStatus writer profiles; each writer carries its vessels as instances). Every vessel
// publishes an FdiStatus at --status-rate, on its own phase of the period; fault events come at
// --event-rate per second over the fleet (a random vessel's accelerometer or gyro toggles
// between raised and cleared-unacknowledged, sequence +1 each time), and every --burst-every s
// --burst vessels raise their gyro fault at the same instant. Every sample's stamp is the wall
// clock at its write, so a reader on the same host can time its delivery. Paced to real time on
// a 10 ms tick; how far it fell behind is reported when it stops.
#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "dds_options.hpp"
#include "monitor_model.hpp"
#include "usv_fdi/dds/dds_context.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::app {
namespace {

namespace fdds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

struct EmulateArgs {
  DdsCli dds;
  int vessels = 100;
  int participants = 0;  ///< 0: min(vessels, 10)
  std::uint32_t first_mmsi = 990000001;
  double status_rate = 1.0;
  double event_rate = 2.0;
  int burst = 0;
  double burst_every = 30.0;
  double duration = 0.0;
  unsigned seed = 1;
};

/// One emulated vessel: its participant and the sequences of its two fault instances.
struct Vessel {
  std::uint32_t mmsi = 0;
  int participant = 0;
  std::uint64_t sequence[2] = {0, 0};
  bool raised[2] = {false, false};
  std::uint64_t samples = 0;
};

struct Participant {
  std::unique_ptr<dds::DdsContext> ctx;
  fdds::DataWriter* events = nullptr;
  fdds::DataWriter* status = nullptr;
};

class Fleet {
 public:
  Fleet(const EmulateArgs& a, const dds::DdsConfig& cfg) : a_(a), rng_(a.seed) {
    const int p = a.participants > 0 ? a.participants : std::min(a.vessels, 10);
    for (int i = 0; i < p; ++i) {
      Participant x;
      x.ctx = std::make_unique<dds::DdsContext>(cfg);
      x.events = &x.ctx->create_writer(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventWriter);
      x.status = &x.ctx->create_writer(dds::TopicId::kStatus, dds::profiles::kStatusWriter);
      parts_.push_back(std::move(x));
    }
    for (int i = 0; i < a.vessels; ++i) {
      Vessel v;
      v.mmsi = a.first_mmsi + static_cast<std::uint32_t>(i);
      v.participant = i % p;
      vessels_.push_back(v);
    }
  }

  int participants() const { return static_cast<int>(parts_.size()); }

  void status(Vessel& v) {
    fdi::FdiStatus s;
    s.mmsi(v.mmsi);
    s.stamp(wall_now());
    s.converged(true);
    s.armed(true);
    s.ins_healthy(!v.raised[0]);
    s.rudder_healthy(true);
    s.samples(v.samples += 10);
    s.incarnation(1);
    // Residual statistics as a sidecar's: healthy near 1, a raised channel's above its threshold.
    std::array<double, 2> j{};
    for (std::size_t c = 0; c < 2; ++c) {
      const double wave = 1.2 + 0.4 * std::sin(0.3 * static_cast<double>(v.samples) + c);
      j[c] = v.raised[c] ? 4.0 * wave + 5.0 : wave;
    }
    s.j_peak(j);
    s.j_raise({6.0, 6.0});
    s.j_leave({3.0, 3.0});
    s.c_a(v.raised[0] ? 0.97 : 0.05);
    s.c_g(v.raised[1] ? 0.98 : 0.04);
    s.message("emulated");
    dds::write(*parts_[static_cast<std::size_t>(v.participant)].status, s);
    ++statuses_;
  }

  void event(Vessel& v, int sensor, bool raise) {
    v.raised[sensor] = raise;
    fdi::FaultEvent e;
    e.mmsi(v.mmsi);
    e.sensor(static_cast<std::uint8_t>(sensor));
    e.state(static_cast<std::uint8_t>(raise ? FaultState::kRaised
                                            : FaultState::kClearedUnacknowledged));
    e.kind(static_cast<std::uint8_t>(FaultKind::kBias));
    e.c_a(sensor == 0 ? 0.97 : 0.05);
    e.c_g(sensor == 1 ? 0.97 : 0.05);
    e.statistic(raise ? 12.0 : 0.5);
    e.threshold(1.2);
    const double now = wall_now();
    e.onset_time(now);
    e.detection_time(now);
    e.stamp(now);
    e.sequence(++v.sequence[sensor]);
    e.incarnation(1);
    e.message("emulated");
    dds::write(*parts_[static_cast<std::size_t>(v.participant)].events, e);
    ++events_;
  }

  /// Runs until the duration has passed or a stop signal came.
  void run() {
    const double tick = 0.01;
    const double period = 1.0 / a_.status_rate;
    const auto t0 = Clock::now();
    std::uniform_int_distribution<std::size_t> any(0, vessels_.size() - 1);
    std::uniform_int_distribution<int> sensor(0, 1);
    double owed_events = 0.0;
    double next_burst = a_.burst_every;
    std::size_t next_status = 0;  // statuses written in all, in vessel order, period after period
    for (std::uint64_t k = 1;; ++k) {
      const double t = static_cast<double>(k) * tick;
      std::this_thread::sleep_until(
          t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t)));
      lag_ = std::max(lag_, std::chrono::duration<double>(Clock::now() - t0).count() - t);
      // Statuses due by t: vessel i's phase is i / N of the period.
      const auto due = static_cast<std::size_t>(std::floor(t / period * vessels_.size()));
      for (; next_status < due; ++next_status) status(vessels_[next_status % vessels_.size()]);
      owed_events += a_.event_rate * tick;
      for (; owed_events >= 1.0; owed_events -= 1.0) {
        Vessel& v = vessels_[any(rng_)];
        const int s = sensor(rng_);
        event(v, s, !v.raised[s]);
      }
      if (a_.burst > 0 && t >= next_burst) {
        next_burst += a_.burst_every;
        std::vector<std::size_t> order(vessels_.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::shuffle(order.begin(), order.end(), rng_);
        const auto n = std::min(order.size(), static_cast<std::size_t>(a_.burst));
        for (std::size_t i = 0; i < n; ++i) event(vessels_[order[i]], 1, true);
        ++bursts_;
      }
      if ((a_.duration > 0 && t >= a_.duration) || wait_for_stop_signal(0.0) != 0) break;
    }
    elapsed_ = std::chrono::duration<double>(Clock::now() - t0).count();
  }

  std::string summary() const {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "%llu statuses, %llu fault events (%d bursts) in %.1f s; fell behind real "
                  "time by at most %.3f s",
                  static_cast<unsigned long long>(statuses_),
                  static_cast<unsigned long long>(events_), bursts_, elapsed_, lag_);
    return buf;
  }

 private:
  const EmulateArgs& a_;
  std::mt19937 rng_;
  std::vector<Participant> parts_;
  std::vector<Vessel> vessels_;
  std::uint64_t statuses_ = 0, events_ = 0;
  int bursts_ = 0;
  double lag_ = 0.0, elapsed_ = 0.0;
};

int run_emulate(const EmulateArgs& a) {
  if (static_cast<std::uint64_t>(a.first_mmsi) + static_cast<std::uint64_t>(a.vessels) - 1 >
      999999999u) {
    spdlog::error("--first-mmsi {} + --vessels {} goes past MMSI 999999999", a.first_mmsi,
                  a.vessels);
    return kExitUsage;
  }
  block_stop_signals();
  route_fastdds_log_to_spdlog();
  dds::DdsConfig cfg;
  try {
    cfg = make_dds_config(a.dds);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  std::unique_ptr<Fleet> fleet;
  try {
    fleet = std::make_unique<Fleet>(a, cfg);
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  spdlog::info(
      "emulating {} vessels (MMSI {}..{}) on {} participants, status {:g} Hz, {:g} fault "
      "events/s, bursts of {} every {:g} s: running",
      a.vessels, a.first_mmsi, a.first_mmsi + static_cast<std::uint32_t>(a.vessels) - 1,
      fleet->participants(), a.status_rate, a.event_rate, a.burst, a.burst_every);
  fleet->run();
  spdlog::info("emulation stopped: {}", fleet->summary());
  return kExitOk;
}

}  // namespace

void register_emulate_command(CommandRegistry& registry) {
  static EmulateArgs args;
  CLI::App* sub = registry.add(
      "emulate",
      "a fleet of N vessels at the DDS level (FdiStatus and FaultEvents, bursts of raises) to "
      "measure the shore side without N sidecars",
      [] { return run_emulate(args); });
  add_dds_options(sub, &args.dds);
  sub->add_option("--vessels", args.vessels, "number of vessels")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  sub->add_option("--participants", args.participants,
                  "DDS participants the vessels are spread over (0: min(vessels, 10))")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  sub->add_option("--first-mmsi", args.first_mmsi, "MMSI of the first vessel (then +1 each)")
      ->check(CLI::Range(1u, 999999999u))
      ->capture_default_str();
  sub->add_option("--status-rate", args.status_rate, "FdiStatus per vessel per second")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  sub->add_option("--event-rate", args.event_rate, "fault events per second over the fleet")
      ->check(CLI::Range(0.0, 100000.0))
      ->capture_default_str();
  sub->add_option("--burst", args.burst, "vessels that raise at the same instant in a burst")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  sub->add_option("--burst-every", args.burst_every, "seconds between bursts")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--duration", args.duration, "stop after this many seconds (0: on a signal)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--seed", args.seed, "random seed of the events")->capture_default_str();
}

}  // namespace usvfdi::app
