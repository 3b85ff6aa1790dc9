#include "sim_publish.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "commands.hpp"
#include "dds_options.hpp"

namespace usvfdi::app {

namespace dds = usv_fdi::dds;
using Clock = std::chrono::steady_clock;

int publish_simulation(const std::vector<std::pair<std::uint32_t, SimConfig>>& vessels,
                       const dds::DdsConfig& cfg, const PublishOptions& opt) {
  block_stop_signals();
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
  auto& ins =
      ctx->create_writer(dds::TopicId::kIns, opt.reliable ? dds::profiles::kInsWriterReliable
                                                          : dds::profiles::kInsWriterBestEffort);
  auto& rud = ctx->create_writer(
      dds::TopicId::kRudder,
      opt.reliable ? dds::profiles::kRudderWriterReliable : dds::profiles::kRudderWriterBestEffort);
  // Bounded wait for a sidecar, so the first seconds of the voyage are not lost.
  const auto wait_end = Clock::now() + std::chrono::duration<double>(opt.wait_readers);
  eprosima::fastdds::dds::PublicationMatchedStatus mi, mr;
  while (Clock::now() < wait_end) {
    ins.get_publication_matched_status(mi);
    rud.get_publication_matched_status(mr);
    if (mi.current_count > 0 && mr.current_count > 0) break;
    if (wait_for_stop_signal(0.05) != 0) return kExitOk;
  }
  if (mi.current_count == 0) spdlog::warn("no INS reader matched; publishing anyway");
  spdlog::info("publishing {} vessel(s) at {:g} Hz, {:g}x real time", vessels.size(),
               vessels.front().second.rate_hz, opt.speed);
  const auto t0 = Clock::now();
  std::uint64_t seq = 0;
  std::vector<SimRow> rows(sims.size());
  for (bool more = true; more;) {
    for (std::size_t i = 0; i < sims.size() && more; ++i) more = sims[i]->next(&rows[i]);
    if (!more) break;
    const double t = rows.front().t;
    std::this_thread::sleep_until(t0 + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(t / opt.speed)));
    ++seq;
    for (std::size_t i = 0; i < sims.size(); ++i) {
      const SimRow& r = rows[i];
      fdi::InsSample s;
      s.mmsi(vessels[i].first);
      s.seq(seq);
      s.stamp(r.t);
      s.v(r.v);
      s.r(r.r);
      s.v_valid(!std::isnan(r.v));  // a missing value is sent as invalid
      s.r_valid(!std::isnan(r.r));
      fdi::RudderSample d;
      d.mmsi(vessels[i].first);
      d.seq(seq);
      d.stamp(r.t);
      d.delta(r.delta);
      d.valid(std::isfinite(r.delta));
      try {
        dds::write(rud, d);
        dds::write(ins, s);
      } catch (const std::exception& e) {
        spdlog::warn("{}", e.what());
      }
    }
    if (wait_for_stop_signal(0.0) != 0) break;
  }
  spdlog::info("published {} samples per vessel", seq);
  ins.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(opt.linger));
  std::this_thread::sleep_for(std::chrono::duration<double>(opt.linger));
  return kExitOk;
}

}  // namespace usvfdi::app
