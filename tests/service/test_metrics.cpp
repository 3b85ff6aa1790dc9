// The sidecar's Prometheus endpoint (usv_fdi/metrics/metrics.hpp), served for real on a free
// loopback port and scraped over HTTP.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "support/http_get.hpp"
#include "usv_fdi/metrics/metrics.hpp"

namespace usvfdi::metrics {
namespace {

using testing_http::sample;

TEST(SidecarMetrics, AScrapeShowsTheLatestStatusAndCountersOnlyGrow) {
  SidecarMetrics m("127.0.0.1:0", 257000123);
  ASSERT_EQ(m.ports().size(), 1u);
  const int port = m.ports().front();
  ASSERT_GT(port, 0);
  const std::map<std::string, std::string> vessel = {{"mmsi", "257000123"}};
  const auto with = [&](const char* key, const char* value) {
    auto l = vessel;
    l[key] = value;
    return l;
  };

  // Before the first update: every series exists, at zero; no input yet (+Inf)
  std::string page = testing_http::get(port, "/metrics");
  ASSERT_FALSE(page.empty());
  EXPECT_EQ(sample(page, "usv_fdi_raises_total", with("sensor", "gyro")), 0.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_input_age_seconds", with("input", "ins")), HUGE_VAL) << page;

  pipeline::PipelineStatus st;
  st.raises = {1, 2, 0};
  st.samples = 5000;
  st.dropped_inputs = 3;
  st.lost_rudder = 7;
  st.estimate.converged = true;
  st.isolation.armed = true;
  st.isolation.J << 2.5, 17.0;
  st.isolation.thresholds << 6.0, 12.0;
  st.isolation.c_a = 0.1;
  st.isolation.c_g = 0.99;
  st.isolation_paused = 128;
  pipeline::PipelineLiveness live;
  live.ins_age = 0.25;
  live.rudder_age = -1.0;
  live.publisher = 0.05;
  m.update(st, live);
  page = testing_http::get(port, "/metrics");
  EXPECT_EQ(sample(page, "usv_fdi_raises_total", with("sensor", "accelerometer")), 1.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_raises_total", with("sensor", "gyro")), 2.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_statistic", with("channel", "gyro")), 17.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_threshold", with("channel", "accelerometer")), 6.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_isolation_confidence", with("sensor", "gyro")), 0.99) << page;
  EXPECT_EQ(sample(page, "usv_fdi_converged", vessel), 1.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_armed", vessel), 1.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_isolation_paused", vessel), 128.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_samples_total", vessel), 5000.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_dropped_samples_total", with("queue", "input")), 3.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_lost_samples_total", with("input", "rudder")), 7.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_input_age_seconds", with("input", "ins")), 0.25) << page;
  EXPECT_EQ(sample(page, "usv_fdi_input_age_seconds", with("input", "rudder")), HUGE_VAL) << page;
  EXPECT_EQ(sample(page, "usv_fdi_thread_age_seconds", with("thread", "publisher")), 0.05);

  // A later status with more samples and one more raise: counters follow; the gauges are the
  // latest values
  st.raises = {1, 3, 0};
  st.samples = 6000;
  st.estimate.converged = false;
  m.update(st, live);
  page = testing_http::get(port, "/metrics");
  EXPECT_EQ(sample(page, "usv_fdi_raises_total", with("sensor", "gyro")), 3.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_samples_total", vessel), 6000.0) << page;
  EXPECT_EQ(sample(page, "usv_fdi_converged", vessel), 0.0) << page;
}

TEST(SidecarMetrics, AnAddressItCannotListenOnIsNamed) {
  SidecarMetrics first("127.0.0.1:0", 1);
  const std::string taken = "127.0.0.1:" + std::to_string(first.ports().front());
  try {
    SidecarMetrics second(taken, 2);
    FAIL() << "a second endpoint listened on " << taken;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("metrics: cannot listen on '" + taken + "'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(SidecarMetrics("not-an-address", 3), std::runtime_error);
}

}  // namespace
}  // namespace usvfdi::metrics
