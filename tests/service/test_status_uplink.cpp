// The status uplink (issue 13, section 5): which FdiStatus samples an event-triggered sidecar
// sends, against periodic sending.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "usv_fdi/dds_service/status_uplink.hpp"

using usvfdi::dds_service::StatusUplink;
using usvfdi::dds_service::UplinkOptions;
using usvfdi::dds_service::UplinkReason;

namespace {

fdi::FdiStatus healthy() {
  fdi::FdiStatus s;
  s.mmsi(257000001);
  s.a({-0.9, -0.6, -2.4, -1.2});
  s.converged(true);
  s.armed(true);
  s.excitation(0.5);
  s.sigma_v(0.01);
  s.sigma_r(0.0005);
  s.ins_healthy(true);
  s.rudder_healthy(true);
  s.surge_speed(7.0);
  s.speed_ratio(1.0);
  s.reference_speed(7.0);
  s.j_peak({1.2, 1.5});
  s.j_raise({6.0, 8.0});
  s.j_leave({3.0, 4.0});
  s.c_a(0.3);
  s.c_g(0.4);
  s.message("armed; ");
  return s;
}

}  // namespace

TEST(StatusUplink, PeriodicModeSendsEveryStatus) {
  UplinkOptions o;
  o.event = false;
  StatusUplink u(o);
  const fdi::FdiStatus s = healthy();
  for (int i = 0; i < 10; ++i) EXPECT_EQ(u.offer(s, i), UplinkReason::kPeriodic);
  EXPECT_EQ(u.sent_total(), 10u);
}

TEST(StatusUplink, AnUnchangedStatusGoesOnlyAsAHeartbeat) {
  StatusUplink u;  // heartbeat 3 s
  fdi::FdiStatus s = healthy();
  EXPECT_EQ(u.offer(s, 0.0), UplinkReason::kFirst);
  int sent = 0;
  for (int i = 1; i <= 60; ++i) {
    s.stamp(i);
    s.samples(10 * i);  // always moving: not news
    const UplinkReason r = u.offer(s, i);
    if (r != UplinkReason::kNone) {
      EXPECT_EQ(r, UplinkReason::kHeartbeat) << "at " << i;
      EXPECT_EQ(i % 3, 0) << "at " << i;
      ++sent;
    }
  }
  EXPECT_EQ(sent, 20);
}

TEST(StatusUplink, EveryDiscreteChangeIsSentAtOnce) {
  struct Change {
    const char* name;
    void (*apply)(fdi::FdiStatus*);
  };
  const Change changes[] = {
      {"armed", [](fdi::FdiStatus* s) { s->armed(false); }},
      {"converged", [](fdi::FdiStatus* s) { s->converged(false); }},
      {"ins_healthy", [](fdi::FdiStatus* s) { s->ins_healthy(false); }},
      {"rudder_healthy", [](fdi::FdiStatus* s) { s->rudder_healthy(false); }},
      {"input_flags", [](fdi::FdiStatus* s) { s->input_flags(1u << 9); }},
      {"isolation_paused", [](fdi::FdiStatus* s) { s->isolation_paused(2); }},
      {"lost", [](fdi::FdiStatus* s) { s->lost_ins(1); }},
      {"acks", [](fdi::FdiStatus* s) { s->acks_refused(1); }},
      {"message", [](fdi::FdiStatus* s) { s->message("model mismatch, not a sensor fault"); }},
      {"a value became or stopped being finite", [](fdi::FdiStatus* s) { s->surge_speed(NAN); }},
      {"a value became or stopped being finite", [](fdi::FdiStatus* s) { s->sigma_v(INFINITY); }},
      {"incarnation", [](fdi::FdiStatus* s) { s->incarnation(2); }},
      {"model_mismatch", [](fdi::FdiStatus* s) { s->model_mismatch(true); }},
      {"residual above its leave threshold",
       [](fdi::FdiStatus* s) {
         s->j_peak({1.2, 4.5});
       }},
      {"residual above its leave threshold",
       [](fdi::FdiStatus* s) {
         s->j_peak({3.5, 1.5});
       }},
  };
  for (const Change& c : changes) {
    StatusUplink u;
    fdi::FdiStatus s = healthy();
    ASSERT_EQ(u.offer(s, 0.0), UplinkReason::kFirst);
    ASSERT_EQ(u.offer(s, 1.0), UplinkReason::kNone);
    c.apply(&s);
    EXPECT_EQ(u.offer(s, 2.0), UplinkReason::kDiscrete) << c.name;
    EXPECT_EQ(u.last_change(), c.name);
    EXPECT_EQ(u.offer(s, 3.0), UplinkReason::kNone) << c.name << ": sent once";
  }
}

TEST(StatusUplink, AResidualsLevelBelowItsLeaveThresholdIsNoNews) {
  StatusUplink u;
  fdi::FdiStatus s = healthy();
  ASSERT_EQ(u.offer(s, 0.0), UplinkReason::kFirst);
  // J_N wanders under the leave threshold, the confidences move: nothing is sent before the
  // heartbeat (3 s)
  for (int i = 1; i < 20; ++i) {
    s.j_peak({0.5 + 0.1 * i, 3.9 - 0.1 * i});
    s.c_a(0.05 * i);
    EXPECT_EQ(u.offer(s, 0.1 * i), UplinkReason::kNone) << i;
  }
  // NaN (none computed) is below every threshold
  s.j_peak({NAN, NAN});
  EXPECT_EQ(u.offer(s, 2.0), UplinkReason::kNone);
}

TEST(StatusUplink, AMovingEstimateIsSentWhenItLeavesTheTolerance) {
  StatusUplink u;  // tolerance 8 %, bound 11.3 %
  fdi::FdiStatus s = healthy();
  u.offer(s, 0.0);
  // 1 % of A-hat: below the tolerance, and the budget a quiet status builds lets it stand.
  auto a = s.a();
  for (double& x : a) x *= 1.01;
  s.a(a);
  EXPECT_EQ(u.offer(s, 1.0), UplinkReason::kNone);
  // 15 %: past the bound, sent at once.
  for (double& x : a) x *= 1.15;
  s.a(a);
  EXPECT_EQ(u.offer(s, 2.0), UplinkReason::kContinuous);
  // The surge speed: 1 m/s of 7 is news too.
  s.surge_speed(6.0);
  EXPECT_EQ(u.offer(s, 3.0), UplinkReason::kContinuous);
}

TEST(StatusUplink, TheHeartbeatGoesAtTheEvaluationNearestItsTime) {
  // Evaluations about a second apart, a little early or late each time (the sidecar's wall
  // clock): statuses are never more than heartbeat + half an interval apart.
  StatusUplink u;  // heartbeat 3 s
  const fdi::FdiStatus s = healthy();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  double last = 0.0, longest = 0.0;
  u.offer(s, 0.0);
  for (int i = 1; i <= 600; ++i) {
    const double now = i + jitter(rng);
    if (u.offer(s, now) != UplinkReason::kNone) {
      longest = std::max(longest, now - last);
      last = now;
    }
  }
  EXPECT_LE(longest, 3.0 + 0.5 * 1.1);
  EXPECT_GE(u.sent_total(), 600u / 3);
}

TEST(StatusUplink, ASteadyLossIsSentWhenItStartsAndThenWithTheHeartbeat) {
  // A link that loses samples every period: the counter and the count in the message grow
  // every status, the period's flag stays set. Only the start is urgent.
  StatusUplink u;
  fdi::FdiStatus s = healthy();
  ASSERT_EQ(u.offer(s, 0.0), UplinkReason::kFirst);
  int urgent = 0, sent = 0;
  for (int i = 1; i <= 30; ++i) {
    s.lost_ins(5 * i);
    s.input_flags(1u << 9);  // samples lost this period
    s.message(("armed; " + std::to_string(5 * i) + " samples lost; ").c_str());
    const UplinkReason r = u.offer(s, i);
    if (r == UplinkReason::kDiscrete) ++urgent;
    if (r != UplinkReason::kNone) ++sent;
  }
  EXPECT_EQ(urgent, 1);
  EXPECT_EQ(sent, 10);
  // When the losses stop, the flag clears: news.
  s.input_flags(0);
  EXPECT_EQ(u.offer(s, 31.0), UplinkReason::kDiscrete);
  // A counter that goes back (a restart) is news too.
  s.lost_ins(0);
  EXPECT_EQ(u.offer(s, 32.0), UplinkReason::kDiscrete);
}

TEST(StatusUplink, AnInfiniteValueIsNewsBothWaysAndKeepsTheRuleWorking) {
  StatusUplink u;
  fdi::FdiStatus s = healthy();
  u.offer(s, 0.0);
  s.excitation(INFINITY);
  EXPECT_EQ(u.offer(s, 1.0), UplinkReason::kDiscrete);
  // While the copy holds an infinity, A-hat's moves are still seen.
  auto a = s.a();
  for (double& x : a) x *= 1.5;
  s.a(a);
  EXPECT_EQ(u.offer(s, 2.0), UplinkReason::kContinuous);
  s.excitation(0.5);
  EXPECT_EQ(u.offer(s, 3.0), UplinkReason::kDiscrete);
}

TEST(StatusUplink, TheShoreCopyStaysWithinTheBoundAndSendsFewerThanPeriodic) {
  // A random walk of A-hat (3 % per element and status) for an hour at 1 Hz: at every evaluation
  // the last sent A-hat is within bound() of the current one, and far fewer statuses go out.
  StatusUplink u;
  fdi::FdiStatus s = healthy();
  fdi::FdiStatus shore;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> step(0.0, 0.03);
  double worst = 0.0;
  for (int i = 0; i < 3600; ++i) {
    auto a = s.a();
    for (double& x : a) x *= 1.0 + step(rng);
    s.a(a);
    if (u.offer(s, i) != UplinkReason::kNone) shore = s;
    worst = std::max(worst, u.deviation(shore, s));
  }
  EXPECT_LE(worst, u.bound());
  EXPECT_GT(worst, 0.5 * u.options().tolerance);  // the tolerance was used, not wasted
  EXPECT_LT(u.sent_total(), 3600u / 2);
  std::printf("random walk: %llu of 3600 statuses sent, worst deviation %.4f (bound %.4f)\n",
              static_cast<unsigned long long>(u.sent_total()), worst, u.bound());
}

TEST(StatusUplink, BadOptionsAreRefusedByName) {
  UplinkOptions o;
  o.heartbeat = 0;
  EXPECT_THROW(StatusUplink{o}, std::invalid_argument);
  o = UplinkOptions{};
  o.decay = 1.0;
  EXPECT_THROW(StatusUplink{o}, std::invalid_argument);
  o = UplinkOptions{};
  o.tolerance = -1;
  EXPECT_THROW(StatusUplink{o}, std::invalid_argument);
}
