// The engine's wiring (include/usv_fdi/core/engine.hpp) and the isolation stage's input
// bookkeeping: what one stage hands the other, and what bad timestamps do to the channels.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "usv_fdi/core/engine.hpp"

namespace usvfdi {
namespace {

/// A healthy-looking sample: values that move (nothing stuck), rudder inside its range.
Sample moving(double t) {
  return Sample{t, 0.01 * std::sin(0.7 * t), 0.002 * std::cos(0.5 * t), 0.05 * std::sin(0.3 * t)};
}

TEST(IsolatorInputs, RepeatedTimestampsNeverMakeTheRudderMissing) {
  // GIVEN an isolator fed 10 Hz samples with a usable rudder angle
  Isolator iso(IsolationParams{}, Vec2(0.01, 0.002));
  std::vector<Detection> out;
  double t = 0.0;
  for (int k = 0; k < 20; ++k, t += 0.1) ASSERT_TRUE(iso.update(moving(t), &out));
  ASSERT_TRUE(iso.status().input.delta_ok);
  // WHEN three samples repeat the previous timestamp
  const double t_last = t - 0.1;
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(iso.update(moving(t_last), &out));
  EXPECT_EQ(iso.status().input.rejected_time, 3u);
  // THEN the timing errors raise the unknown sensor's invalid condition ...
  bool timing_raised = false;
  for (const Detection& d : out) {
    timing_raised = timing_raised ||
                    (d.sensor == Sensor::kUnknown && d.active && d.kind == FaultKind::kInvalid);
  }
  EXPECT_TRUE(timing_raised);
  // ... but the rudder channel stays usable on every later sample
  for (int k = 0; k < 40; ++k, t += 0.1) {
    ASSERT_TRUE(iso.update(moving(t), &out));
    EXPECT_TRUE(iso.status().input.delta_ok) << "t = " << t;
  }
}

}  // namespace
}  // namespace usvfdi
