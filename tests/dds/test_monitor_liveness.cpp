// The monitor's "last heard" logic (src/app/vessel_liveness.hpp) on a clock the test drives:
// ages, the silent threshold (strictly longer than --silent-after), each change reported once,
// per vessel, and "heard again" with the length of the silence.
#include <gtest/gtest.h>

#include <cmath>

#include "vessel_liveness.hpp"

namespace usvfdi::app {
namespace {

TEST(VesselLiveness, AVesselNeverHeardHasNoAgeAndIsNotSilent) {
  VesselLiveness live(2.0);
  EXPECT_TRUE(std::isnan(live.age(257000001, 100.0)));
  EXPECT_FALSE(live.silent(257000001));
  EXPECT_TRUE(live.evaluate(1000.0).empty());
  EXPECT_TRUE(live.vessels().empty());
}

TEST(VesselLiveness, GoesSilentOnceAfterTheThresholdAndIsHeardAgainOnce) {
  VesselLiveness live(2.0);
  VesselLiveness::Change c;
  // GIVEN a vessel heard at t = 10 s (its first sample is not a change)
  EXPECT_FALSE(live.heard(7, 10.0, &c));
  EXPECT_DOUBLE_EQ(live.age(7, 11.5), 1.5);
  // THEN it is not silent at exactly the threshold, silent just after it, reported once
  EXPECT_TRUE(live.evaluate(12.0).empty());
  EXPECT_FALSE(live.silent(7));
  const auto went = live.evaluate(12.25);
  ASSERT_EQ(went.size(), 1u);
  EXPECT_EQ(went[0].mmsi, 7u);
  EXPECT_TRUE(went[0].silent);
  EXPECT_DOUBLE_EQ(went[0].age, 2.25);
  EXPECT_TRUE(live.silent(7));
  EXPECT_TRUE(live.evaluate(13.0).empty());
  EXPECT_TRUE(live.evaluate(60.0).empty());
  EXPECT_DOUBLE_EQ(live.age(7, 60.0), 50.0);
  // WHEN it is heard again THEN that is one change, with the length of the silence
  ASSERT_TRUE(live.heard(7, 70.0, &c));
  EXPECT_EQ(c.mmsi, 7u);
  EXPECT_FALSE(c.silent);
  EXPECT_DOUBLE_EQ(c.gap, 60.0);
  EXPECT_DOUBLE_EQ(c.age, 0.0);
  EXPECT_FALSE(live.silent(7));
  EXPECT_FALSE(live.heard(7, 70.5, &c));
  // AND it can go silent again
  EXPECT_TRUE(live.evaluate(72.0).empty());
  ASSERT_EQ(live.evaluate(72.6).size(), 1u);
}

TEST(VesselLiveness, EachVesselHasItsOwnAge) {
  VesselLiveness live(3.0);
  VesselLiveness::Change c;
  live.heard(2, 0.0, &c);
  live.heard(1, 0.0, &c);
  for (double t = 1.0; t <= 10.0; t += 1.0) {
    live.heard(1, t, &c);  // vessel 1 keeps talking, vessel 2 does not
    const auto changes = live.evaluate(t + 0.5);
    if (t + 0.5 > 3.0 && !live.silent(2)) ADD_FAILURE() << "vessel 2 not silent at " << t;
    for (const auto& ch : changes) EXPECT_EQ(ch.mmsi, 2u) << "at " << t;
  }
  EXPECT_FALSE(live.silent(1));
  EXPECT_TRUE(live.silent(2));
  EXPECT_EQ(live.vessels(), (std::vector<std::uint32_t>{1, 2}));
}

TEST(VesselLiveness, ASampleReceivedOutOfClockOrderNeverMakesAVesselOlder) {
  VesselLiveness live(2.0);
  VesselLiveness::Change c;
  live.heard(5, 10.0, &c);
  live.heard(5, 9.0, &c);
  EXPECT_DOUBLE_EQ(live.age(5, 11.0), 1.0);
}

}  // namespace
}  // namespace usvfdi::app
