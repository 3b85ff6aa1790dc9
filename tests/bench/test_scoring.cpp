// Scoring rules of the detection benchmark on hand-made event lists (docs/benchmark.md).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "scoring.hpp"

namespace usvfdi::bench {
namespace {

const Sensor kA = Sensor::kAccelerometer;
const Sensor kG = Sensor::kGyro;
const Sensor kU = Sensor::kUnknown;

Alarm raise(double t, Sensor s) { return Alarm{t, s, true, FaultKind::kBias}; }
Alarm clear(double t, Sensor s) { return Alarm{t, s, false, FaultKind::kBias}; }

TEST(BenchScoring, ARaiseInTheWindowDetectsWithItsDelayAndSensor) {
  const RunScore r =
      score_run({{kG, FaultKind::kBias, 100, 160}}, {raise(100.4, kG), clear(163, kG)}, 0, 300, 50);
  ASSERT_EQ(r.faults.size(), 1u);
  EXPECT_TRUE(r.faults[0].detected);
  EXPECT_TRUE(r.faults[0].isolated);
  EXPECT_NEAR(r.faults[0].delay, 0.4, 1e-12);
  EXPECT_TRUE(r.faults[0].recovered);
  EXPECT_NEAR(r.faults[0].recovery_delay, 3.0, 1e-12);
  EXPECT_TRUE(r.faults[0].armed_at_onset);
  EXPECT_EQ(r.false_alarms(), 0u);
  // Healthy: 300 s minus the window [100, 162).
  EXPECT_NEAR(r.healthy_time, 300 - 62, 1e-9);
  EXPECT_NEAR(r.healthy_armed_time, 250 - 62, 1e-9);
}

TEST(BenchScoring, AFaultIsHeldWhenItsSensorStaysRaisedToItsEnd) {
  // Raised at 100.4 and cleared after the end: held, shown for 59.6 of 60 s.
  const RunScore held =
      score_run({{kG, FaultKind::kBias, 100, 160}}, {raise(100.4, kG), clear(163, kG)}, 0, 300, 0);
  EXPECT_TRUE(held.faults[0].held);
  EXPECT_NEAR(held.faults[0].shown, 59.6 / 60.0, 1e-12);
  // Cleared at 103 while the bias lasts, raised again when it ends (its removal is a step
  // too): detected and isolated, but not held; shown for 3 s.
  const RunScore early = score_run(
      {{kA, FaultKind::kBias, 150, 180}},
      {raise(150.3, kA), clear(153.3, kA), raise(180.3, kA), clear(183.3, kA)}, 0, 300, 0);
  EXPECT_TRUE(early.faults[0].detected);
  EXPECT_TRUE(early.faults[0].isolated);
  EXPECT_FALSE(early.faults[0].held);
  EXPECT_NEAR(early.faults[0].shown, 3.0 / 30.0, 1e-12);
  // Cleared and raised again within the fault: not held, shown for both stretches.
  const RunScore gap =
      score_run({{kG, FaultKind::kDrift, 100, 160}},
                {raise(110, kG), clear(120, kG), raise(130, kG), clear(161, kG)}, 0, 300, 0);
  EXPECT_FALSE(gap.faults[0].held);
  EXPECT_NEAR(gap.faults[0].shown, 40.0 / 60.0, 1e-12);
  // The other sensor raised throughout: not held (not isolated), its sensor shown never.
  const RunScore other =
      score_run({{kG, FaultKind::kBias, 100, 160}}, {raise(100.2, kA), clear(161, kA)}, 0, 300, 0);
  EXPECT_FALSE(other.faults[0].held);
  EXPECT_EQ(other.faults[0].shown, 0.0);
  // Never detected: neither.
  const RunScore missed = score_run({{kG, FaultKind::kScale, 100, 160}}, {}, 0, 300, 0);
  EXPECT_FALSE(missed.faults[0].held);
  EXPECT_EQ(missed.faults[0].shown, 0.0);
}

TEST(BenchScoring, TheFirstRaiseDecidesTheIsolation) {
  const RunScore wrong =
      score_run({{kA, FaultKind::kStuck, 100, 160}}, {raise(101, kG), raise(102, kA)}, 0, 300, 0);
  EXPECT_TRUE(wrong.faults[0].detected);
  EXPECT_FALSE(wrong.faults[0].isolated);
  EXPECT_EQ(wrong.faults[0].raised_sensor, kG);
  EXPECT_EQ(wrong.false_alarms(), 0u);  // the second raise is inside the window too
  const RunScore unknown =
      score_run({{kA, FaultKind::kStuck, 100, 160}}, {raise(101, kU)}, 0, 300, 0);
  EXPECT_TRUE(unknown.faults[0].detected);
  EXPECT_FALSE(unknown.faults[0].isolated);
}

TEST(BenchScoring, ARaiseWithinTheGraceAfterTheEndStillDetects) {
  const RunScore late =
      score_run({{kA, FaultKind::kDrift, 100, 160}}, {raise(161.5, kA)}, 0, 300, 0);
  EXPECT_TRUE(late.faults[0].detected);
  EXPECT_NEAR(late.faults[0].delay, 61.5, 1e-12);
  const RunScore after =
      score_run({{kA, FaultKind::kDrift, 100, 160}}, {raise(162.5, kA)}, 0, 300, 0);
  EXPECT_FALSE(after.faults[0].detected);
  ASSERT_EQ(after.false_alarms(), 1u);
  EXPECT_EQ(after.false_alarm_times[0], 162.5);
  ScoreParams wide;
  wide.detect_grace = 5.0;
  EXPECT_TRUE(score_run({{kA, FaultKind::kDrift, 100, 160}}, {raise(162.5, kA)}, 0, 300, 0, wide)
                  .faults[0]
                  .detected);
}

TEST(BenchScoring, RaisesOutsideEveryWindowAreFalseAlarmsAndClearsAreNot) {
  const RunScore r = score_run(
      {{kG, FaultKind::kNoise, 100, 160}},
      {raise(10, kA), clear(12, kA), raise(99.9, kG), clear(200, kG), raise(250, kU)}, 0, 300, 0);
  ASSERT_EQ(r.false_alarms(), 3u);
  EXPECT_EQ(r.false_alarm_times[0], 10);
  EXPECT_EQ(r.false_alarm_times[1], 99.9);
  EXPECT_EQ(r.false_alarm_times[2], 250);
  ASSERT_EQ(r.false_alarm_events.size(), 3u);
  EXPECT_EQ(r.false_alarm_events[2].sensor, kU);
  // A condition already raised at the onset does not detect the fault: no new raise.
  EXPECT_FALSE(r.faults[0].detected);
}

TEST(BenchScoring, AHealthyRunIsAllHealthyTimeAndRaisesOutsideItAreIgnored) {
  const RunScore r = score_run({}, {raise(-5, kG), raise(5, kG), raise(3601, kA)}, 0, 3600, kNaN);
  EXPECT_EQ(r.false_alarms(), 1u);
  ASSERT_EQ(r.false_alarm_durations.size(), 1u);
  EXPECT_NEAR(r.false_alarm_durations[0], 3595.0, 1e-9);  // never cleared: to the run's end
  const RunScore d =
      score_run({}, {raise(5, kG), raise(6, kA), clear(8, kA), clear(12.5, kG)}, 0, 3600, kNaN);
  ASSERT_EQ(d.false_alarm_durations.size(), 2u);
  EXPECT_NEAR(d.false_alarm_durations[0], 7.5, 1e-9);  // to its own sensor's clear
  EXPECT_NEAR(d.false_alarm_durations[1], 2.0, 1e-9);
  EXPECT_NEAR(r.healthy_time, 3600, 1e-9);
  EXPECT_EQ(r.healthy_armed_time, 0.0);  // never armed
}

TEST(BenchScoring, RecoveryWaitsForEverySensorAndEndsAtTheNextOnset) {
  // Both sensors raised during the fault; the later clear decides.
  const RunScore both =
      score_run({{kG, FaultKind::kBias, 100, 160}},
                {raise(100.2, kG), raise(101, kA), clear(161, kG), clear(170, kA)}, 0, 300, 0);
  EXPECT_TRUE(both.faults[0].recovered);
  EXPECT_NEAR(both.faults[0].recovery_delay, 10.0, 1e-12);
  // Cleared before the end (a scale fault hiding while the course is held): recovery 0.
  const RunScore early =
      score_run({{kG, FaultKind::kScale, 100, 160}}, {raise(100.2, kG), clear(130, kG)}, 0, 300, 0);
  EXPECT_NEAR(early.faults[0].recovery_delay, 0.0, 1e-12);
  // Not cleared before the next fault's onset: not recovered; the second fault is scored
  // on its own window.
  const RunScore stay =
      score_run({{kG, FaultKind::kBias, 100, 160}, {kA, FaultKind::kBias, 200, 260}},
                {raise(100.2, kG), raise(200.1, kA), clear(210, kG), clear(262, kA)}, 0, 300, 0);
  EXPECT_FALSE(stay.faults[0].recovered);
  EXPECT_TRUE(stay.faults[1].detected);
  EXPECT_TRUE(stay.faults[1].isolated);
  EXPECT_NEAR(stay.faults[1].recovery_delay, 2.0, 1e-12);
  EXPECT_NEAR(stay.healthy_time, 300 - 62 - 62, 1e-9);
  // Never cleared before the run's end.
  EXPECT_FALSE(score_run({{kG, FaultKind::kBias, 100, 160}}, {raise(100.2, kG)}, 0, 300, 0)
                   .faults[0]
                   .recovered);
}

TEST(BenchScoring, ArmingAfterTheOnsetIsRecordedAndWindowsAreCutAtTheNextOnset) {
  const RunScore r = score_run({{kA, FaultKind::kBias, 200, 260}, {kG, FaultKind::kBias, 100, 199}},
                               {raise(199.5, kA)}, 0, 400, 150);
  // Sorted by onset: the gyro fault's window [100, 200) is cut at 200 (not 201).
  EXPECT_EQ(r.faults[0].fault.sensor, kG);
  EXPECT_FALSE(r.faults[0].armed_at_onset);
  EXPECT_TRUE(r.faults[0].detected);  // 199.5 is inside [100, 200)
  EXPECT_FALSE(r.faults[0].isolated);
  EXPECT_TRUE(r.faults[1].armed_at_onset);
  EXPECT_FALSE(r.faults[1].detected);
  EXPECT_NEAR(r.healthy_time, 400 - 100 - 62, 1e-9);
  EXPECT_NEAR(r.healthy_armed_time, (400 - 150) - 50 - 62, 1e-9);
}

TEST(BenchScoring, OnlyTheLiveSpansCountAsArmed) {
  // Live from 50 s, un-armed at 120 s (the estimate lost convergence), live again from 200 s.
  const std::vector<LiveSpan> live{{50, 120}, {200}};
  EXPECT_FALSE(live_at(live, 49.9));
  EXPECT_TRUE(live_at(live, 50));
  EXPECT_FALSE(live_at(live, 120));
  EXPECT_FALSE(live_at(live, 150));
  EXPECT_TRUE(live_at(live, 1e9));
  // Faults at 100 (live), 150 (un-armed) and 250 (live again).
  const RunScore r = score_run({{kG, FaultKind::kBias, 100, 110},
                                {kA, FaultKind::kBias, 150, 160},
                                {kG, FaultKind::kBias, 250, 260}},
                               {raise(100.4, kG), clear(111, kG)}, 0, 400, live);
  ASSERT_EQ(r.faults.size(), 3u);
  EXPECT_TRUE(r.faults[0].armed_at_onset);
  EXPECT_FALSE(r.faults[1].armed_at_onset);
  EXPECT_TRUE(r.faults[2].armed_at_onset);
  // Healthy: 400 s minus three windows of 12 s; while live: [50, 120) and [200, 400) minus
  // the windows in them ([100, 112) and [250, 262)).
  EXPECT_NEAR(r.healthy_time, 400 - 36, 1e-9);
  EXPECT_NEAR(r.healthy_armed_time, (70 - 12) + (200 - 12), 1e-9);
  // A detector live from 50 s to the end is the same as one armed at 50 s.
  const RunScore once = score_run({{kG, FaultKind::kBias, 150, 160}}, {}, 0, 400, 50);
  const RunScore span =
      score_run({{kG, FaultKind::kBias, 150, 160}}, {}, 0, 400, std::vector<LiveSpan>{{50}});
  EXPECT_EQ(once.faults[0].armed_at_onset, span.faults[0].armed_at_onset);
  EXPECT_NEAR(once.healthy_armed_time, span.healthy_armed_time, 1e-12);
}

TEST(BenchScoring, BadInputIsRefusedWithAReason) {
  EXPECT_THROW(score_run({{kG, FaultKind::kBias, 100, 100}}, {}, 0, 300, 0), std::invalid_argument);
  EXPECT_THROW(score_run({{kG, FaultKind::kBias, 100, 160}, {kA, FaultKind::kBias, 150, 200}}, {},
                         0, 300, 0),
               std::invalid_argument);
  EXPECT_THROW(score_run({}, {raise(5, kG), raise(4, kG)}, 0, 300, 0), std::invalid_argument);
  EXPECT_THROW(score_run({}, {}, 0, 300, std::vector<LiveSpan>{{50, 50}}), std::invalid_argument);
  EXPECT_THROW(score_run({}, {}, 0, 300, std::vector<LiveSpan>{{50, 120}, {100, 200}}),
               std::invalid_argument);
  try {
    score_run({{kG, FaultKind::kBias, 100, 160}, {kA, FaultKind::kBias, 150, 200}}, {}, 0, 300, 0);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("overlap"), std::string::npos) << e.what();
  }
}

TEST(BenchScoring, QuantilesInterpolateAndIgnoreNaN) {
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
  EXPECT_EQ(quantile({3, 1, 2}, 0.5), 2);
  EXPECT_NEAR(quantile({1, 2, 3, 4}, 0.5), 2.5, 1e-12);
  EXPECT_NEAR(quantile({0, 10}, 0.95), 9.5, 1e-12);
  EXPECT_EQ(quantile({kNaN, 7}, 0.5), 7);
  EXPECT_EQ(quantile({1, 5, 9}, 1.0), 9);
}

}  // namespace
}  // namespace usvfdi::bench
