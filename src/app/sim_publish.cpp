#include "sim_publish.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "commands.hpp"
#include "dds_options.hpp"

namespace usvfdi::app {

using Clock = std::chrono::steady_clock;

int publish_simulation(const std::vector<std::pair<std::uint32_t, SimConfig>>& vessels,
                       const dds::DdsConfig& cfg, const PublishOptions& opt) {
  block_stop_signals();  // before Fast DDS starts its threads
  route_fastdds_log_to_spdlog();
  if (vessels.empty()) return kExitUsage;
  std::vector<std::unique_ptr<Simulator>> sims;
  try {
    for (const auto& v : vessels) sims.push_back(std::make_unique<Simulator>(v.second));
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  std::unique_ptr<dds::DdsContext> ctx;
  try {
    ctx = std::make_unique<dds::DdsContext>(cfg);
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  eprosima::fastdds::dds::DataWriter* ins = nullptr;
  eprosima::fastdds::dds::DataWriter* rud = nullptr;
  try {
    ins =
        &ctx->create_writer(dds::TopicId::kIns, opt.reliable ? dds::profiles::kInsWriterReliable
                                                             : dds::profiles::kInsWriterBestEffort);
    rud = &ctx->create_writer(dds::TopicId::kRudder, opt.reliable
                                                         ? dds::profiles::kRudderWriterReliable
                                                         : dds::profiles::kRudderWriterBestEffort);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  // Bounded wait for the sidecars, so that the first seconds of the voyage are not lost.
  const auto wait_end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(opt.wait_readers));
  eprosima::fastdds::dds::PublicationMatchedStatus mi, mr;
  for (;;) {
    ins->get_publication_matched_status(mi);
    rud->get_publication_matched_status(mr);
    if ((mi.current_count >= opt.min_readers && mr.current_count >= opt.min_readers) ||
        Clock::now() >= wait_end) {
      break;
    }
    if (wait_for_stop_signal(0.05) != 0) return kExitOk;
  }
  if (mi.current_count < opt.min_readers || mr.current_count < opt.min_readers) {
    spdlog::warn(
        "{} INS / {} rudder reader(s) matched within {:g} s (domain {}, {} wanted); publishing "
        "anyway",
        mi.current_count, mr.current_count, opt.wait_readers, cfg.domain_id, opt.min_readers);
  }
  spdlog::info("publishing {} vessel(s) at {:g} Hz, {:g}x real time, {} writers", vessels.size(),
               vessels.front().second.rate_hz, opt.speed,
               opt.reliable ? "RELIABLE" : "BEST_EFFORT");
  auto t0 = Clock::now();
  std::uint64_t seq = 0, failed = 0;
  // A deterministic stream, not a race with the wall clock: with RELIABLE writers the voyage
  // waits for the readers' acknowledgements every kAckEvery samples (half the writers' 256-deep
  // history), so no sample is ever overwritten before a slow reader has it; and when the process
  // falls behind its schedule (a starved machine) it shifts the schedule instead of bursting to
  // catch up. Both are counted and reported at the end.
  constexpr std::uint64_t kAckEvery = 128;
  const auto kLate = std::chrono::milliseconds(250);
  int behind = 0;             // times the schedule was shifted
  double behind_s = 0.0;      // by how much in all [s of wall time]
  int ack_waits_failed = 0;   // flow-control waits that timed out
  double ack_wait_max = 0.0;  // the longest flow-control wait [s]
  std::vector<SimRow> rows(sims.size());
  bool stopped = false;
  for (bool more = true; more && !stopped;) {
    for (std::size_t i = 0; i < sims.size() && more; ++i) more = sims[i]->next(&rows[i]);
    if (!more) break;
    const double t = rows.front().t;
    const auto due = t0 + std::chrono::duration_cast<Clock::duration>(
                              std::chrono::duration<double>(t / opt.speed));
    const auto now = Clock::now();
    if (now > due + kLate) {
      t0 += now - due;
      ++behind;
      behind_s += std::chrono::duration<double>(now - due).count();
    } else {
      std::this_thread::sleep_until(due);
    }
    ++seq;
    if (opt.reliable && seq > 1 && seq % kAckEvery == 0) {
      const auto w0 = Clock::now();
      const eprosima::fastrtps::Duration_t bound(10.0);
      const bool ok = ins->wait_for_acknowledgments(bound) ==
                          eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK &&
                      rud->wait_for_acknowledgments(bound) ==
                          eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
      if (!ok) ++ack_waits_failed;
      ack_wait_max =
          std::max(ack_wait_max, std::chrono::duration<double>(Clock::now() - w0).count());
    }
    // Rudder first: the sidecar pairs an INS sample with the rudder angle at its stamp and
    // releases it as soon as a rudder sample at or after that stamp has arrived.
    for (std::size_t i = 0; i < sims.size(); ++i) {
      const SimRow& r = rows[i];
      fdi::RudderSample d;
      d.mmsi(vessels[i].first);
      d.seq(seq);
      d.stamp(r.t);
      d.delta(r.delta);
      d.valid(std::isfinite(r.delta));
      try {
        dds::write(*rud, d);
      } catch (const std::exception& e) {
        if (failed++ == 0) spdlog::warn("{} (further failures only counted)", e.what());
      }
    }
    if (seq == 1 && opt.reliable) {
      // Handshake: the writers' match above is one-sided; a reader acknowledges the first
      // rudder sample only once it has matched this writer too. So the voyage starts when the
      // matched sidecars listen (a rudder sample alone starts no INS timeout there). Bounded
      // by what is left of --wait-readers, at least 1 s.
      const double left =
          std::max(1.0, std::chrono::duration<double>(wait_end - Clock::now()).count());
      if (rud->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(left)) !=
          eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
        spdlog::warn("the first rudder sample was not acknowledged within {:g} s", left);
      }
      t0 = Clock::now() - std::chrono::duration_cast<Clock::duration>(
                              std::chrono::duration<double>(t / opt.speed));
    }
    for (std::size_t i = 0; i < sims.size(); ++i) {
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
      try {
        dds::write(*ins, s);
      } catch (const std::exception& e) {
        if (failed++ == 0) spdlog::warn("{} (further failures only counted)", e.what());
      }
    }
    if (seq % 1000 == 0) spdlog::debug("t = {:.2f} s", t);
    stopped = wait_for_stop_signal(0.0) != 0;
  }
  spdlog::info("published {} samples per vessel{}{}", seq, stopped ? " (stopped by a signal)" : "",
               failed ? ", " + std::to_string(failed) + " writes failed" : std::string());
  // Whether the machine kept up: a test that fails can say if it was starved.
  spdlog::info(
      "pacing: fell behind the schedule {} time(s), {:.2f} s in all (shifted, not caught up); "
      "longest wait for the readers' acknowledgements {:.3f} s, {} wait(s) timed out{}",
      behind, behind_s, ack_wait_max, ack_waits_failed,
      behind > 0 || ack_waits_failed > 0 ? " (a busy machine)" : "");
  if (!stopped) {
    // Reliable writers: let the readers acknowledge the tail; then linger (bounded).
    const eprosima::fastrtps::Duration_t linger(opt.linger);
    if (opt.reliable) {
      ins->wait_for_acknowledgments(linger);
      rud->wait_for_acknowledgments(linger);
    }
    (void)wait_for_stop_signal(opt.linger);
  }
  return kExitOk;
}

}  // namespace usvfdi::app
