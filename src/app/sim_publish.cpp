#include "sim_publish.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>

#include "commands.hpp"
#include "dds_options.hpp"

namespace usvfdi::app {

using Clock = std::chrono::steady_clock;

namespace {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::Duration_t;
using eprosima::fastrtps::types::ReturnCode_t;

/// With RELIABLE writers, wait for the readers' acknowledgements every this many samples
/// (half the writers' 256-deep history).
constexpr std::uint64_t kAckEvery = 128;

Clock::duration wall_duration(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

struct Writers {
  fdds::DataWriter* ins = nullptr;
  fdds::DataWriter* rudder = nullptr;
  fdds::DataWriter* speed = nullptr;  ///< only when a vessel has a speed
};

/// The INS and rudder writers (and the speed writer, with the rudder's QoS, if `speed`);
/// false (logged) when Fast DDS refuses one.
bool create_writers(dds::DdsContext& ctx, bool reliable, bool speed, Writers* w) {
  try {
    w->ins = &ctx.create_writer(dds::TopicId::kIns, reliable ? dds::profiles::kInsWriterReliable
                                                             : dds::profiles::kInsWriterBestEffort);
    const char* rudder_profile =
        reliable ? dds::profiles::kRudderWriterReliable : dds::profiles::kRudderWriterBestEffort;
    w->rudder = &ctx.create_writer(dds::TopicId::kRudder, rudder_profile);
    if (speed) w->speed = &ctx.create_writer(dds::TopicId::kSpeed, rudder_profile);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  return true;
}

/// Bounded wait (until wait_end) for the sidecars, so that the first seconds of the voyage are
/// not lost. False: a stop signal came.
bool wait_for_readers(const Writers& w, const PublishOptions& opt, std::uint32_t domain,
                      Clock::time_point wait_end) {
  fdds::PublicationMatchedStatus mi, mr, ms;
  const auto matched = [&] {
    w.ins->get_publication_matched_status(mi);
    w.rudder->get_publication_matched_status(mr);
    if (w.speed != nullptr) w.speed->get_publication_matched_status(ms);
    return mi.current_count >= opt.min_readers && mr.current_count >= opt.min_readers &&
           (w.speed == nullptr || ms.current_count >= opt.min_readers);
  };
  for (;;) {
    if (matched() || Clock::now() >= wait_end) break;
    if (wait_for_stop_signal(0.05) != 0) return false;
  }
  if (!matched()) {
    spdlog::warn(
        "{} INS / {} rudder{} reader(s) matched within {:g} s (domain {}, {} wanted); publishing "
        "anyway",
        mi.current_count, mr.current_count,
        w.speed == nullptr ? std::string() : " / " + std::to_string(ms.current_count) + " speed",
        opt.wait_readers, domain, opt.min_readers);
  }
  return true;
}

/// The voyage's schedule. A deterministic stream, not a race with the wall clock: with
/// RELIABLE writers the voyage waits for the readers' acknowledgements every kAckEvery samples,
/// so no sample is ever overwritten before a slow reader has it; and when the process falls
/// behind its schedule (a starved machine) it shifts the schedule instead of bursting to catch
/// up. Both are counted and reported at the end.
class Pacing {
 public:
  explicit Pacing(double speed) : speed_(speed), t0_(Clock::now()) {}

  /// Sleeps until data time t is due, or shifts the schedule when more than kLate behind.
  void wait_until_due(double t) {
    const auto due = t0_ + wall_duration(t / speed_);
    const auto now = Clock::now();
    if (now > due + kLate) {
      t0_ += now - due;
      ++behind_;
      behind_s_ += std::chrono::duration<double>(now - due).count();
    } else {
      std::this_thread::sleep_until(due);
    }
  }
  /// Data time t is due now.
  void restart_at(double t) { t0_ = Clock::now() - wall_duration(t / speed_); }
  /// Waits (at most 10 s) until the readers have acknowledged everything written.
  void flow_control(const Writers& w) {
    const auto w0 = Clock::now();
    const Duration_t bound(10.0);
    const bool ok = w.ins->wait_for_acknowledgments(bound) == ReturnCode_t::RETCODE_OK &&
                    w.rudder->wait_for_acknowledgments(bound) == ReturnCode_t::RETCODE_OK &&
                    (w.speed == nullptr ||
                     w.speed->wait_for_acknowledgments(bound) == ReturnCode_t::RETCODE_OK);
    if (!ok) ++ack_waits_failed_;
    ack_wait_max_ =
        std::max(ack_wait_max_, std::chrono::duration<double>(Clock::now() - w0).count());
  }
  /// Whether the machine kept up: a test that fails can say if it was starved.
  void log() const {
    spdlog::info(
        "pacing: fell behind the schedule {} time(s), {:.2f} s in all (shifted, not caught up); "
        "longest wait for the readers' acknowledgements {:.3f} s, {} wait(s) timed out{}",
        behind_, behind_s_, ack_wait_max_, ack_waits_failed_,
        behind_ > 0 || ack_waits_failed_ > 0 ? " (a busy machine)" : "");
  }

 private:
  static constexpr std::chrono::milliseconds kLate{250};
  double speed_;
  Clock::time_point t0_;
  int behind_ = 0;             ///< times the schedule was shifted
  double behind_s_ = 0.0;      ///< by how much in all [s of wall time]
  int ack_waits_failed_ = 0;   ///< flow-control waits that timed out
  double ack_wait_max_ = 0.0;  ///< the longest flow-control wait [s]
};

/// Writes one sample to DDS, counting failures in *failed (the first one logged).
template <typename Sample>
void write_counted(fdds::DataWriter* w, const Sample& s, std::uint64_t* failed) {
  try {
    dds::write(*w, s);
  } catch (const std::exception& e) {
    if ((*failed)++ == 0) spdlog::warn("{} (further failures only counted)", e.what());
  }
}

void write_speed(const Writers& w, const PublishedVessels& vessels, const std::vector<double>& u,
                 const std::vector<SimRow>& rows, std::uint64_t seq, std::uint64_t* failed) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (w.speed == nullptr || std::isnan(u[i])) continue;
    fdi::SpeedSample d;
    d.mmsi(vessels[i].first);
    d.seq(seq);
    d.stamp(rows[i].t);
    d.u(u[i]);
    d.valid(true);
    write_counted(w.speed, d, failed);
  }
}

void write_rudder(const Writers& w, const PublishedVessels& vessels,
                  const std::vector<SimRow>& rows, std::uint64_t seq, std::uint64_t* failed) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SimRow& r = rows[i];
    fdi::RudderSample d;
    d.mmsi(vessels[i].first);
    d.seq(seq);
    d.stamp(r.t);
    d.delta(r.delta);
    d.valid(std::isfinite(r.delta));
    write_counted(w.rudder, d, failed);
  }
}

void write_ins(const Writers& w, const PublishedVessels& vessels, const std::vector<SimRow>& rows,
               std::uint64_t seq, std::uint64_t* failed) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SimRow& r = rows[i];
    fdi::InsSample s;
    s.mmsi(vessels[i].first);
    s.seq(seq);
    s.stamp(r.t);
    // A missing value (stale fault) is sent as invalid; +Inf (invalid fault) as it is.
    s.v(std::isnan(r.v) ? 0.0 : r.v);
    s.r(std::isnan(r.r) ? 0.0 : r.r);
    s.v_valid(!std::isnan(r.v));
    s.r_valid(!std::isnan(r.r));
    write_counted(w.ins, s, failed);
  }
}

/// Handshake: the writers' match is one-sided; a reader acknowledges the first rudder sample
/// only once it has matched this writer too. So the voyage starts when the matched sidecars
/// listen (a rudder sample alone starts no INS timeout there). Bounded by what is left of
/// --wait-readers, at least 1 s.
void await_first_rudder_ack(const Writers& w, Clock::time_point wait_end) {
  const double left = std::max(1.0, std::chrono::duration<double>(wait_end - Clock::now()).count());
  if (w.rudder->wait_for_acknowledgments(Duration_t(left)) != ReturnCode_t::RETCODE_OK) {
    spdlog::warn("the first rudder sample was not acknowledged within {:g} s", left);
  }
  // The first speed sample too, written just before it (a speed reader that matched this
  // writer later than the rudder's would otherwise lose it).
  if (w.speed != nullptr &&
      w.speed->wait_for_acknowledgments(Duration_t(left)) != ReturnCode_t::RETCODE_OK) {
    spdlog::warn("the first speed sample was not acknowledged within {:g} s", left);
  }
}

/// What a voyage published.
struct Published {
  std::uint64_t seq = 0;     ///< samples per vessel
  std::uint64_t failed = 0;  ///< writes that failed
  bool stopped = false;      ///< by a signal
};

/// Publishes every vessel's samples in lockstep, paced, until one ends or a stop signal comes.
Published publish_voyage(const PublishedVessels& vessels, const Writers& w,
                         const PublishOptions& opt, Clock::time_point wait_end) {
  Pacing pacing(opt.speed);
  Published out;
  std::vector<SimRow> rows(vessels.size());
  std::vector<double> u(vessels.size(), kNaN);
  for (bool more = true; more && !out.stopped;) {
    for (std::size_t i = 0; i < vessels.size() && more; ++i) {
      more = vessels[i].second->next(&rows[i], &u[i]);
    }
    if (!more) break;
    const double t = rows.front().t;
    pacing.wait_until_due(t);
    const std::uint64_t seq = ++out.seq;
    if (opt.reliable && seq > 1 && seq % kAckEvery == 0) pacing.flow_control(w);
    // Speed and rudder first: the sidecar pairs an INS sample with the rudder angle at its
    // stamp and releases it as soon as a rudder sample at or after that stamp has arrived.
    write_speed(w, vessels, u, rows, seq, &out.failed);
    write_rudder(w, vessels, rows, seq, &out.failed);
    if (seq == 1 && opt.reliable) {
      await_first_rudder_ack(w, wait_end);
      pacing.restart_at(t);
    }
    write_ins(w, vessels, rows, seq, &out.failed);
    if (seq % 1000 == 0) spdlog::debug("t = {:.2f} s", t);
    out.stopped = wait_for_stop_signal(0.0) != 0;
  }
  spdlog::info("published {} samples per vessel{}{}", out.seq,
               out.stopped ? " (stopped by a signal)" : "",
               out.failed ? ", " + std::to_string(out.failed) + " writes failed" : std::string());
  pacing.log();
  return out;
}

/// Reliable writers: let the readers acknowledge the tail; then linger (bounded).
void linger(const Writers& w, const PublishOptions& opt) {
  const Duration_t linger(opt.linger);
  if (opt.reliable) {
    w.ins->wait_for_acknowledgments(linger);
    w.rudder->wait_for_acknowledgments(linger);
    if (w.speed != nullptr) w.speed->wait_for_acknowledgments(linger);
  }
  (void)wait_for_stop_signal(opt.linger);
}

/// The classic simulator: no speed (its models are linear at their design speed).
class SimulatorSource : public RowSource {
 public:
  explicit SimulatorSource(const SimConfig& c) : sim_(c) {}
  bool next(SimRow* row, double* u) override {
    *u = kNaN;
    return sim_.next(row);
  }
  bool has_speed() const override { return false; }

 private:
  Simulator sim_;
};

}  // namespace

int publish_rows(PublishedVessels vessels, double rate_hz, const dds::DdsConfig& cfg,
                 const PublishOptions& opt) {
  block_stop_signals();  // before Fast DDS starts its threads
  route_fastdds_log_to_spdlog();
  if (vessels.empty()) return kExitUsage;
  std::unique_ptr<dds::DdsContext> ctx;
  try {
    ctx = std::make_unique<dds::DdsContext>(cfg);
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  const bool speed = std::any_of(vessels.begin(), vessels.end(),
                                 [](const auto& v) { return v.second->has_speed(); });
  Writers w;
  if (!create_writers(*ctx, opt.reliable, speed, &w)) return kExitFailure;
  const auto wait_end = Clock::now() + wall_duration(opt.wait_readers);
  if (!wait_for_readers(w, opt, cfg.domain_id, wait_end)) return kExitOk;
  spdlog::info("publishing {} vessel(s) at {:g} Hz, {:g}x real time, {} writers{}", vessels.size(),
               rate_hz, opt.speed, opt.reliable ? "RELIABLE" : "BEST_EFFORT",
               speed ? ", with the surge speed" : "");
  const Published p = publish_voyage(vessels, w, opt, wait_end);
  if (!p.stopped) linger(w, opt);
  return kExitOk;
}

int publish_simulation(const std::vector<std::pair<std::uint32_t, SimConfig>>& vessels,
                       const dds::DdsConfig& cfg, const PublishOptions& opt) {
  if (vessels.empty()) return kExitUsage;
  PublishedVessels sources;
  try {
    for (const auto& v : vessels) {
      sources.emplace_back(v.first, std::make_unique<SimulatorSource>(v.second));
    }
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  return publish_rows(std::move(sources), vessels.front().second.rate_hz, cfg, opt);
}

}  // namespace usvfdi::app
