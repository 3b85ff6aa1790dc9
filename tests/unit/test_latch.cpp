// The latch state machine of fault events (include/usv_fdi/core/latch.hpp), after IEC 62923
// bridge alert management:
//   normal -> raised (active, unacknowledged)
//   raised --ack--> active-acknowledged --condition clears--> acknowledged (= normal)
//   raised --condition clears--> cleared-unacknowledged --ack--> acknowledged
//   cleared-unacknowledged --condition returns--> raised
// Every transition, the three kinds of refused acknowledgement, kind refinement, restore(),
// and properties over seeded random detection / acknowledgement sequences checked against
// an independent reference model of the header's table.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "usv_fdi/core/latch.hpp"

namespace usvfdi {
namespace {

Mat2 some_A(double x = 1.0) {
  Mat2 A;
  A << -0.883 * x, -0.438, -1.55, -1.16;
  return A;
}

Detection raise(Sensor sensor, FaultKind kind, double t) {
  Detection d;
  d.sensor = sensor;
  d.active = true;
  d.kind = kind;
  d.c_a = sensor == Sensor::kAccelerometer ? 0.97 : 0.05;
  d.c_g = sensor == Sensor::kGyro ? 0.96 : 0.04;
  d.statistic = 12.5;
  d.threshold = 6.0;
  d.onset_time = t - 0.3;
  d.detection_time = t;
  d.message = "raise at " + std::to_string(t);
  return d;
}

Detection clear(Sensor sensor, double t) {
  Detection d;
  d.sensor = sensor;
  d.active = false;
  d.kind = FaultKind::kUnknown;
  d.c_a = 0.5;
  d.c_g = 0.5;
  d.statistic = 1.25;
  d.threshold = 3.0;
  d.detection_time = t;
  d.message = "clear at " + std::to_string(t);
  return d;
}

Detection refine(Sensor sensor, FaultKind kind, double t) {
  Detection d = raise(sensor, kind, t);
  d.update = true;
  d.c_a = 0.11;  // a refinement carries the kind; the latched confidences stay
  d.c_g = 0.22;
  d.message = "refined at " + std::to_string(t);
  return d;
}

void expect_same(const FaultEvent& a, const FaultEvent& b) {
  EXPECT_EQ(a.sensor, b.sensor);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.c_a, b.c_a);
  EXPECT_EQ(a.c_g, b.c_g);
  EXPECT_EQ(a.statistic, b.statistic);
  EXPECT_EQ(a.threshold, b.threshold);
  EXPECT_TRUE(a.t == b.t || (std::isnan(a.t) && std::isnan(b.t)));
  EXPECT_EQ(a.A, b.A);
  EXPECT_EQ(a.message, b.message);
}

/// Drives a latch to the wanted state through its public interface; returns the events.
std::vector<FaultEvent> drive_to(FaultLatch* latch, FaultState want) {
  std::vector<FaultEvent> evs;
  FaultEvent ev;
  const Sensor s = latch->current().sensor;
  if (want == FaultState::kNormal) return evs;
  EXPECT_TRUE(latch->on_detection(raise(s, FaultKind::kBias, 10.0), some_A(), &ev));
  evs.push_back(ev);
  if (want == FaultState::kRaised) return evs;
  if (want == FaultState::kActiveAcknowledged || want == FaultState::kAcknowledged) {
    EXPECT_EQ(latch->acknowledge(ev.sequence, 11.0, "op", &ev), AckResult::kAccepted);
    evs.push_back(ev);
    if (want == FaultState::kAcknowledged) {
      EXPECT_TRUE(latch->on_detection(clear(s, 12.0), some_A(), &ev));
      evs.push_back(ev);
    }
    return evs;
  }
  EXPECT_TRUE(latch->on_detection(clear(s, 12.0), some_A(), &ev));  // cleared-unacknowledged
  evs.push_back(ev);
  return evs;
}

const FaultState kAllStates[] = {FaultState::kNormal, FaultState::kRaised,
                                 FaultState::kActiveAcknowledged,
                                 FaultState::kClearedUnacknowledged, FaultState::kAcknowledged};

// ---------------------------------------------------------------------------------------
// Single transitions

TEST(Latch, StartsNormalWithSequenceZeroAndItsSensor) {
  const FaultLatch latch(Sensor::kGyro);
  EXPECT_EQ(latch.state(), FaultState::kNormal);
  EXPECT_FALSE(latch.latched());
  EXPECT_EQ(latch.current().sequence, 0u);
  EXPECT_EQ(latch.current().sensor, Sensor::kGyro);
  EXPECT_EQ(latch.current().kind, FaultKind::kUnknown);
}

TEST(Latch, RaiseCarriesEverythingTheDetectionKnew) {
  // GIVEN a normal latch of the accelerometer
  FaultLatch latch(Sensor::kAccelerometer);
  // WHEN a bias is detected
  const Detection d = raise(Sensor::kAccelerometer, FaultKind::kBias, 61.2);
  FaultEvent ev;
  ASSERT_TRUE(latch.on_detection(d, some_A(), &ev));
  // THEN one raised event with sequence 1 carries the detection and the A in force
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.sensor, Sensor::kAccelerometer);
  EXPECT_EQ(ev.kind, FaultKind::kBias);
  EXPECT_EQ(ev.sequence, 1u);
  EXPECT_EQ(ev.c_a, d.c_a);
  EXPECT_EQ(ev.c_g, d.c_g);
  EXPECT_EQ(ev.statistic, d.statistic);
  EXPECT_EQ(ev.threshold, d.threshold);
  EXPECT_EQ(ev.onset_time, d.onset_time);
  EXPECT_EQ(ev.detection_time, 61.2);
  EXPECT_EQ(ev.t, 61.2);
  EXPECT_EQ(ev.A, some_A());
  EXPECT_EQ(ev.message, d.message);
  // AND the latch holds exactly what it published
  expect_same(latch.current(), ev);
  EXPECT_TRUE(latch.latched());
}

TEST(Latch, NoChangeOfConditionPublishesNothing) {
  for (const FaultState s : kAllStates) {
    SCOPED_TRACE(to_string(s));
    FaultLatch latch(Sensor::kGyro);
    drive_to(&latch, s);
    ASSERT_EQ(latch.state(), s);
    const FaultEvent before = latch.current();
    FaultEvent ev;
    ev.sequence = 999;  // must stay untouched
    const bool active = s == FaultState::kRaised || s == FaultState::kActiveAcknowledged;
    // GIVEN a condition that did not change (active stays active, clear stays clear)
    const Detection same =
        active ? raise(Sensor::kGyro, before.kind, 50.0) : clear(Sensor::kGyro, 50.0);
    // THEN no event, nothing in the latch moves, and the output is not written
    EXPECT_FALSE(latch.on_detection(same, some_A(2.0), &ev));
    expect_same(latch.current(), before);
    EXPECT_EQ(ev.sequence, 999u);
  }
}

TEST(Latch, ClearOfARaisedFaultStaysLatchedUntilAcknowledged) {
  FaultLatch latch(Sensor::kGyro);
  const auto evs = drive_to(&latch, FaultState::kRaised);
  const FaultEvent raised = evs.back();
  // WHEN the condition clears before anyone acknowledged
  FaultEvent ev;
  ASSERT_TRUE(latch.on_detection(clear(Sensor::kGyro, 30.0), some_A(1.5), &ev));
  // THEN the event is rectified-unacknowledged: still latched, next sequence
  EXPECT_EQ(ev.state, FaultState::kClearedUnacknowledged);
  EXPECT_TRUE(latch.latched());
  EXPECT_EQ(ev.sequence, raised.sequence + 1);
  EXPECT_EQ(ev.t, 30.0);
  // AND what was learned at the raise (kind, confidences, onset, detection) is kept
  EXPECT_EQ(ev.kind, raised.kind);
  EXPECT_EQ(ev.c_a, raised.c_a);
  EXPECT_EQ(ev.c_g, raised.c_g);
  EXPECT_EQ(ev.onset_time, raised.onset_time);
  EXPECT_EQ(ev.detection_time, raised.detection_time);
  // AND the statistic, threshold, A and message are those of the clear
  EXPECT_EQ(ev.statistic, 1.25);
  EXPECT_EQ(ev.threshold, 3.0);
  EXPECT_EQ(ev.A, some_A(1.5));
  EXPECT_EQ(ev.message, "clear at " + std::to_string(30.0));
  // AND more clears change nothing
  EXPECT_FALSE(latch.on_detection(clear(Sensor::kGyro, 31.0), some_A(), &ev));
  EXPECT_EQ(latch.state(), FaultState::kClearedUnacknowledged);
}

TEST(Latch, AcknowledgingTheRaisedEventMakesItActiveAcknowledged) {
  FaultLatch latch(Sensor::kAccelerometer);
  const FaultEvent raised = drive_to(&latch, FaultState::kRaised).back();
  FaultEvent ev;
  ASSERT_EQ(latch.acknowledge(raised.sequence, 15.5, "bridge", &ev), AckResult::kAccepted);
  EXPECT_EQ(ev.state, FaultState::kActiveAcknowledged);
  EXPECT_TRUE(latch.latched());
  EXPECT_EQ(ev.sequence, raised.sequence + 1);
  EXPECT_EQ(ev.t, 15.5);
  EXPECT_EQ(ev.message, "acknowledged by bridge");
  EXPECT_EQ(ev.kind, raised.kind);
  EXPECT_EQ(ev.onset_time, raised.onset_time);
  EXPECT_EQ(ev.detection_time, raised.detection_time);
  expect_same(latch.current(), ev);
  // AND while the condition persists nothing else happens
  EXPECT_FALSE(
      latch.on_detection(raise(Sensor::kAccelerometer, FaultKind::kBias, 16.0), some_A(), &ev));
  // AND when it clears the event goes to acknowledged (= normal) on its own
  ASSERT_TRUE(latch.on_detection(clear(Sensor::kAccelerometer, 20.0), some_A(), &ev));
  EXPECT_EQ(ev.state, FaultState::kAcknowledged);
  EXPECT_FALSE(latch.latched());
  EXPECT_EQ(ev.sequence, raised.sequence + 2);
  EXPECT_EQ(ev.t, 20.0);
}

TEST(Latch, AcknowledgingTheClearedEventEndsIt) {
  FaultLatch latch(Sensor::kGyro);
  const FaultEvent cleared = drive_to(&latch, FaultState::kClearedUnacknowledged).back();
  ASSERT_EQ(cleared.state, FaultState::kClearedUnacknowledged);
  FaultEvent ev;
  ASSERT_EQ(latch.acknowledge(cleared.sequence, 40.0, "shore", &ev), AckResult::kAccepted);
  EXPECT_EQ(ev.state, FaultState::kAcknowledged);
  EXPECT_FALSE(latch.latched());
  EXPECT_EQ(ev.sequence, cleared.sequence + 1);
  EXPECT_EQ(ev.t, 40.0);
  EXPECT_EQ(ev.message, "acknowledged by shore");
  EXPECT_EQ(ev.kind, cleared.kind);
  // AND a second acknowledgement of the same (now stale) sequence is refused
  FaultEvent none;
  none.sequence = 777;
  EXPECT_EQ(latch.acknowledge(cleared.sequence, 41.0, "shore", &none), AckResult::kStaleSequence);
  // AND one of the current sequence finds nothing to acknowledge
  EXPECT_EQ(latch.acknowledge(ev.sequence, 41.0, "shore", &none), AckResult::kNothingToAck);
  EXPECT_EQ(none.sequence, 777u);
  EXPECT_EQ(latch.state(), FaultState::kAcknowledged);
}

TEST(Latch, AConditionReturningBeforeTheAckRaisesAgain) {
  FaultLatch latch(Sensor::kGyro);
  const FaultEvent cleared = drive_to(&latch, FaultState::kClearedUnacknowledged).back();
  FaultEvent ev;
  // WHEN the condition returns (another kind this time) before anyone acknowledged
  Detection again = raise(Sensor::kGyro, FaultKind::kDrift, 70.0);
  again.onset_time = 69.0;
  ASSERT_TRUE(latch.on_detection(again, some_A(3.0), &ev));
  // THEN it is raised again with the new occurrence's data and the next sequence
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.sequence, cleared.sequence + 1);
  EXPECT_EQ(ev.kind, FaultKind::kDrift);
  EXPECT_EQ(ev.onset_time, 69.0);
  EXPECT_EQ(ev.detection_time, 70.0);
  EXPECT_EQ(ev.A, some_A(3.0));
  // AND the acknowledgement meant for the cleared event is now stale: it cannot silence it
  EXPECT_EQ(latch.acknowledge(cleared.sequence, 71.0, "late", &ev), AckResult::kStaleSequence);
  EXPECT_EQ(latch.state(), FaultState::kRaised);
}

TEST(Latch, ANewFaultAfterAcknowledgedIsANewRaiseContinuingTheSequence) {
  FaultLatch latch(Sensor::kAccelerometer);
  const FaultEvent done = drive_to(&latch, FaultState::kAcknowledged).back();
  ASSERT_EQ(done.state, FaultState::kAcknowledged);
  FaultEvent ev;
  ASSERT_TRUE(
      latch.on_detection(raise(Sensor::kAccelerometer, FaultKind::kStuck, 90.0), some_A(), &ev));
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.kind, FaultKind::kStuck);
  EXPECT_EQ(ev.sequence, done.sequence + 1);
  EXPECT_EQ(ev.detection_time, 90.0);
}

TEST(Latch, AcknowledgementsThatDoNotApplyAreRefusedAndChangeNothing) {
  for (const FaultState s : kAllStates) {
    SCOPED_TRACE(to_string(s));
    FaultLatch latch(Sensor::kGyro);
    drive_to(&latch, s);
    const FaultEvent before = latch.current();
    FaultEvent out;
    out.sequence = 4242;
    // an unknown (never published) sequence
    EXPECT_EQ(latch.acknowledge(before.sequence + 1, 99.0, "x", &out), AckResult::kUnknownSequence);
    EXPECT_EQ(latch.acknowledge(before.sequence + 1000, 99.0, "x", &out),
              AckResult::kUnknownSequence);
    // a stale sequence (every older one)
    for (std::uint64_t q = 0; q < before.sequence; ++q) {
      EXPECT_EQ(latch.acknowledge(q, 99.0, "x", &out), AckResult::kStaleSequence) << q;
    }
    // the current sequence of a state that awaits no acknowledgement
    if (s == FaultState::kNormal || s == FaultState::kActiveAcknowledged ||
        s == FaultState::kAcknowledged) {
      EXPECT_EQ(latch.acknowledge(before.sequence, 99.0, "x", &out), AckResult::kNothingToAck);
    }
    expect_same(latch.current(), before);
    EXPECT_EQ(out.sequence, 4242u);
  }
}

TEST(Latch, AckResultsHaveReadableNames) {
  EXPECT_STREQ(to_string(AckResult::kAccepted), "accepted");
  EXPECT_STREQ(to_string(AckResult::kStaleSequence), "stale sequence");
  EXPECT_STREQ(to_string(AckResult::kUnknownSequence), "unknown sequence");
  EXPECT_STREQ(to_string(AckResult::kNothingToAck), "nothing to acknowledge");
}

// ---------------------------------------------------------------------------------------
// Kind refinement

TEST(Latch, KindRefinementOfARaisedFaultIsPublishedWithTheNextSequence) {
  FaultLatch latch(Sensor::kGyro);
  FaultEvent ev;
  Detection d = raise(Sensor::kGyro, FaultKind::kUnknown, 20.0);
  ASSERT_TRUE(latch.on_detection(d, some_A(), &ev));
  const FaultEvent raised = ev;
  // WHEN isolation names the kind two seconds later
  ASSERT_TRUE(latch.on_detection(refine(Sensor::kGyro, FaultKind::kDrift, 22.0), some_A(1.1), &ev));
  // THEN an update: same state, new kind, next sequence, time and A of the refinement
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.kind, FaultKind::kDrift);
  EXPECT_EQ(ev.sequence, raised.sequence + 1);
  EXPECT_EQ(ev.t, 22.0);
  EXPECT_EQ(ev.A, some_A(1.1));
  EXPECT_EQ(ev.message, "refined at " + std::to_string(22.0));
  // AND onset, detection time and the confidences of the raise are kept
  EXPECT_EQ(ev.onset_time, raised.onset_time);
  EXPECT_EQ(ev.detection_time, raised.detection_time);
  EXPECT_EQ(ev.c_a, raised.c_a);
  EXPECT_EQ(ev.c_g, raised.c_g);
  expect_same(latch.current(), ev);
  // AND the same kind again is no news
  EXPECT_FALSE(latch.on_detection(refine(Sensor::kGyro, FaultKind::kDrift, 23.0), some_A(), &ev));
  // AND an acknowledgement of the pre-refinement event is stale: the operator must see the
  //   refined event before it can be acknowledged
  FaultEvent ack;
  EXPECT_EQ(latch.acknowledge(raised.sequence, 24.0, "op", &ack), AckResult::kStaleSequence);
  ASSERT_EQ(latch.acknowledge(latch.current().sequence, 24.0, "op", &ack), AckResult::kAccepted);
  EXPECT_EQ(ack.state, FaultState::kActiveAcknowledged);
  EXPECT_EQ(ack.kind, FaultKind::kDrift);
}

TEST(Latch, KindRefinementWhileAcknowledgedKeepsTheAcknowledgement) {
  FaultLatch latch(Sensor::kAccelerometer);
  const FaultEvent acked = drive_to(&latch, FaultState::kActiveAcknowledged).back();
  FaultEvent ev;
  ASSERT_TRUE(
      latch.on_detection(refine(Sensor::kAccelerometer, FaultKind::kScale, 30.0), some_A(), &ev));
  EXPECT_EQ(ev.state, FaultState::kActiveAcknowledged);
  EXPECT_EQ(ev.kind, FaultKind::kScale);
  EXPECT_EQ(ev.sequence, acked.sequence + 1);
}

TEST(Latch, ADifferentKindWithoutTheUpdateFlagIsNotARefinement) {
  FaultLatch latch(Sensor::kGyro);
  const FaultEvent raised = drive_to(&latch, FaultState::kRaised).back();
  FaultEvent ev;
  EXPECT_FALSE(latch.on_detection(raise(Sensor::kGyro, FaultKind::kNoise, 30.0), some_A(), &ev));
  expect_same(latch.current(), raised);
}

TEST(Latch, ARefinementOfAClearedConditionDoesNotRewriteTheClearedEvent) {
  // A late refinement arriving after the clear carries active = true: it is the condition
  // returning, so the event is raised again (never a silent edit of the cleared event).
  FaultLatch latch(Sensor::kGyro);
  const FaultEvent cleared = drive_to(&latch, FaultState::kClearedUnacknowledged).back();
  FaultEvent ev;
  ASSERT_TRUE(latch.on_detection(refine(Sensor::kGyro, FaultKind::kSpikes, 33.0), some_A(), &ev));
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.sequence, cleared.sequence + 1);
  // AND in the acknowledged (final) state a refinement is a new raise, too
  FaultLatch done(Sensor::kGyro);
  const FaultEvent last = drive_to(&done, FaultState::kAcknowledged).back();
  ASSERT_TRUE(done.on_detection(refine(Sensor::kGyro, FaultKind::kSpikes, 33.0), some_A(), &ev));
  EXPECT_EQ(ev.state, FaultState::kRaised);
  EXPECT_EQ(ev.sequence, last.sequence + 1);
}

// ---------------------------------------------------------------------------------------
// restore()

TEST(Latch, RestoreContinuesTheSequenceOfThePersistedEvent) {
  for (const FaultState s : kAllStates) {
    SCOPED_TRACE(to_string(s));
    // GIVEN an event persisted before a restart, with sequence 41
    FaultEvent saved;
    saved.sensor = Sensor::kGyro;
    saved.state = s;
    saved.kind = FaultKind::kBias;
    saved.sequence = 41;
    saved.onset_time = 5.0;
    saved.detection_time = 6.0;
    saved.t = 7.0;
    FaultLatch latch(Sensor::kGyro);
    // WHEN it is restored
    latch.restore(saved);
    // THEN the latch is in that state
    EXPECT_EQ(latch.state(), s);
    EXPECT_EQ(latch.current().sequence, 41u);
    EXPECT_EQ(latch.latched(), s == FaultState::kRaised || s == FaultState::kActiveAcknowledged ||
                                   s == FaultState::kClearedUnacknowledged);
    // AND an acknowledgement of an older sequence is stale, of a newer one unknown
    FaultEvent ev;
    EXPECT_EQ(latch.acknowledge(40, 8.0, "op", &ev), AckResult::kStaleSequence);
    EXPECT_EQ(latch.acknowledge(42, 8.0, "op", &ev), AckResult::kUnknownSequence);
    // AND the next event (whatever moves it) has sequence 42
    bool moved = false;
    if (s == FaultState::kRaised || s == FaultState::kClearedUnacknowledged) {
      moved = latch.acknowledge(41, 8.0, "op", &ev) == AckResult::kAccepted;
    } else if (s == FaultState::kActiveAcknowledged) {
      moved = latch.on_detection(clear(Sensor::kGyro, 8.0), some_A(), &ev);
    } else {
      moved = latch.on_detection(raise(Sensor::kGyro, FaultKind::kDrift, 8.0), some_A(), &ev);
    }
    ASSERT_TRUE(moved);
    EXPECT_EQ(ev.sequence, 42u);
    EXPECT_EQ(latch.current().sequence, 42u);
  }
}

TEST(Latch, ARestoredRaisedEventIsNotLostByAClearAfterTheRestart) {
  // GIVEN a raised, unacknowledged event restored after a restart
  FaultEvent saved;
  saved.sensor = Sensor::kAccelerometer;
  saved.state = FaultState::kRaised;
  saved.kind = FaultKind::kDrift;
  saved.sequence = 7;
  FaultLatch latch(Sensor::kAccelerometer);
  latch.restore(saved);
  // WHEN the fresh engine sees a healthy sensor
  FaultEvent ev;
  ASSERT_TRUE(latch.on_detection(clear(Sensor::kAccelerometer, 1.0), some_A(), &ev));
  // THEN the event is cleared-unacknowledged, not forgotten, with the kind of the saved raise
  EXPECT_EQ(ev.state, FaultState::kClearedUnacknowledged);
  EXPECT_EQ(ev.kind, FaultKind::kDrift);
  EXPECT_EQ(ev.sequence, 8u);
  EXPECT_TRUE(latch.latched());
}

// ---------------------------------------------------------------------------------------
// Properties over random sequences

/// The reference model: the table of latch.hpp, written independently of latch.cpp.
struct Model {
  FaultState state = FaultState::kNormal;
  std::uint64_t seq = 0;
  FaultKind kind = FaultKind::kUnknown;

  /// Returns true when an event is due.
  bool detect(bool active, bool update, FaultKind k) {
    using S = FaultState;
    if (active) {
      switch (state) {
        case S::kNormal:
        case S::kAcknowledged:
        case S::kClearedUnacknowledged:
          state = S::kRaised;
          kind = k;
          ++seq;
          return true;
        case S::kRaised:
        case S::kActiveAcknowledged:
          if (update && k != kind) {
            kind = k;
            ++seq;
            return true;
          }
          return false;
      }
    } else {
      if (state == S::kRaised) {
        state = S::kClearedUnacknowledged;
        ++seq;
        return true;
      }
      if (state == S::kActiveAcknowledged) {
        state = S::kAcknowledged;
        ++seq;
        return true;
      }
    }
    return false;
  }
  AckResult ack(std::uint64_t q) {
    if (q > seq) return AckResult::kUnknownSequence;
    if (q < seq) return AckResult::kStaleSequence;
    if (state == FaultState::kRaised) {
      state = FaultState::kActiveAcknowledged;
    } else if (state == FaultState::kClearedUnacknowledged) {
      state = FaultState::kAcknowledged;
    } else {
      return AckResult::kNothingToAck;
    }
    ++seq;
    return AckResult::kAccepted;
  }
};

bool is_latched(FaultState s) {
  return s == FaultState::kRaised || s == FaultState::kActiveAcknowledged ||
         s == FaultState::kClearedUnacknowledged;
}

TEST(LatchProperty, RandomDetectionAndAckSequencesFollowTheTable) {
  std::mt19937_64 rng(0x1A7C4);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::uniform_int_distribution<int> kind_of(0, 8);
  std::uint64_t events_total = 0, accepted_total = 0;
  std::set<std::pair<int, int>> transitions_seen;
  for (int run = 0; run < 400; ++run) {
    const Sensor sensor = static_cast<Sensor>(run % 3);
    FaultLatch latch(sensor);
    Model model;
    std::vector<std::uint64_t> published;  // sequence numbers of every event, in order
    bool ever_raised = false;
    double t = 0.0;
    // Detections come in bursts (a condition tends to persist), acknowledgements at random.
    bool condition = false;
    for (int step = 0; step < 300; ++step) {
      t += 0.1;
      const FaultState before = latch.state();
      const std::uint64_t seq_before = latch.current().sequence;
      const FaultKind kind_before = latch.current().kind;
      FaultEvent ev;
      ev.sequence = 0xDEAD;
      const double p = u01(rng);
      bool changed = false;
      if (p < 0.6) {
        if (u01(rng) < 0.25) condition = !condition;
        const bool update = condition && u01(rng) < 0.3;
        const FaultKind k = static_cast<FaultKind>(kind_of(rng));
        Detection d = condition ? raise(sensor, k, t) : clear(sensor, t);
        d.update = update;
        const bool want = model.detect(condition, update, k);
        changed = latch.on_detection(d, some_A(1.0 + 0.01 * step), &ev);
        ASSERT_EQ(changed, want) << "run " << run << " step " << step;
        if (!changed) {
          ASSERT_EQ(ev.sequence, 0xDEADu) << "an unchanged latch wrote an event";
        }
        // A clear never names a kind: the kind of the raise is kept.
        if (!condition) {
          ASSERT_EQ(latch.current().kind, kind_before);
        }
      } else {
        // acknowledgement of the current, a stale, an unknown or a random sequence
        std::uint64_t q = seq_before;
        const double w = u01(rng);
        if (w < 0.15 && seq_before > 0) {
          q = seq_before - 1 -
              static_cast<std::uint64_t>(u01(rng) * static_cast<double>(seq_before));
        } else if (w < 0.3) {
          q = seq_before + 1 + static_cast<std::uint64_t>(u01(rng) * 5);
        }
        const AckResult want = model.ack(q);
        const AckResult got = latch.acknowledge(q, t, "op", &ev);
        ASSERT_EQ(got, want) << "run " << run << " step " << step << " q " << q;
        changed = got == AckResult::kAccepted;
        if (changed) {
          ++accepted_total;
          // only the acknowledgement of the sequence in force moves an event on
          ASSERT_EQ(q, seq_before);
          ASSERT_TRUE(before == FaultState::kRaised ||
                      before == FaultState::kClearedUnacknowledged);
        } else {
          ASSERT_EQ(ev.sequence, 0xDEADu) << "a refused ack wrote an event";
        }
      }
      const FaultEvent& now = latch.current();
      // The latch agrees with the reference model.
      ASSERT_EQ(now.state, model.state) << "run " << run << " step " << step;
      ASSERT_EQ(now.sequence, model.seq);
      if (is_latched(model.state)) {
        ASSERT_EQ(now.kind, model.kind);
      }
      if (changed) {
        ++events_total;
        // The event published is the latch's state, with the next sequence.
        ASSERT_EQ(ev.sequence, seq_before + 1);
        ASSERT_EQ(ev.state, now.state);
        ASSERT_EQ(ev.sensor, sensor);
        ASSERT_EQ(ev.t, t);
        if (!published.empty()) {
          ASSERT_GT(ev.sequence, published.back()) << "sequence must increase strictly";
        }
        published.push_back(ev.sequence);
        transitions_seen.insert({static_cast<int>(before), static_cast<int>(now.state)});
      } else {
        // No event, no change at all: nothing moves silently.
        ASSERT_EQ(now.state, before);
        ASSERT_EQ(now.sequence, seq_before);
        ASSERT_EQ(now.kind, kind_before);
      }
      if (now.state == FaultState::kRaised) ever_raised = true;
      // Never lost: once raised, the latch never returns to normal; it leaves the latched
      // states only through an acknowledgement (of the raise or of the clear).
      if (ever_raised) {
        ASSERT_NE(now.state, FaultState::kNormal);
      }
      if (is_latched(before) && !is_latched(now.state)) {
        ASSERT_EQ(now.state, FaultState::kAcknowledged);
        const bool via_ack_of_clear = before == FaultState::kClearedUnacknowledged;
        const bool acked_then_cleared = before == FaultState::kActiveAcknowledged;
        ASSERT_TRUE(via_ack_of_clear || acked_then_cleared);
      }
      // Never silently downgraded: a raised event leaves kRaised only to
      // cleared-unacknowledged (its condition cleared) or active-acknowledged (an ack).
      if (before == FaultState::kRaised && now.state != FaultState::kRaised) {
        ASSERT_TRUE(now.state == FaultState::kClearedUnacknowledged ||
                    now.state == FaultState::kActiveAcknowledged);
      }
    }
    // Every published sequence is 1, 2, 3, ... with no gap.
    for (std::size_t i = 0; i < published.size(); ++i) ASSERT_EQ(published[i], i + 1);
  }
  // The random walk exercised every edge of the table (so the properties are not vacuous).
  using S = FaultState;
  const std::set<std::pair<S, S>> edges = {
      {S::kNormal, S::kRaised},
      {S::kRaised, S::kRaised},  // refinement
      {S::kRaised, S::kActiveAcknowledged},
      {S::kRaised, S::kClearedUnacknowledged},
      {S::kActiveAcknowledged, S::kActiveAcknowledged},  // refinement
      {S::kActiveAcknowledged, S::kAcknowledged},
      {S::kClearedUnacknowledged, S::kAcknowledged},
      {S::kClearedUnacknowledged, S::kRaised},
      {S::kAcknowledged, S::kRaised},
  };
  for (const auto& e : edges) {
    EXPECT_EQ(transitions_seen.count({static_cast<int>(e.first), static_cast<int>(e.second)}), 1u)
        << to_string(e.first) << " -> " << to_string(e.second);
  }
  EXPECT_EQ(transitions_seen.size(), edges.size());
  EXPECT_GT(events_total, 10000u);
  EXPECT_GT(accepted_total, 1000u);
}

TEST(LatchProperty, EveryRaiseIsSeenByAnOperatorWhoOnlyAcksWhatHeReceived) {
  // GIVEN an operator who acknowledges only sequences he has received, and late (a random
  // number of steps after receiving them), and a condition that flickers at random
  std::mt19937_64 rng(0x0A11);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int run = 0; run < 200; ++run) {
    FaultLatch latch(Sensor::kAccelerometer);
    std::vector<FaultEvent> received;
    std::vector<std::pair<int, std::uint64_t>> pending;  // (due step, sequence)
    int raises = 0, raises_acknowledged = 0;
    bool condition = false;
    std::uint64_t raise_seq = 0;
    bool raise_open = false;  // a raise not yet acknowledged (as raised or as cleared)
    for (int step = 0; step < 400; ++step) {
      const double t = 0.1 * step;
      FaultEvent ev;
      if (u01(rng) < 0.1) condition = !condition;
      const Detection d = condition ? raise(Sensor::kAccelerometer, FaultKind::kBias, t)
                                    : clear(Sensor::kAccelerometer, t);
      if (latch.on_detection(d, some_A(), &ev)) {
        received.push_back(ev);
        pending.push_back({step + 1 + static_cast<int>(u01(rng) * 20), ev.sequence});
        if (ev.state == FaultState::kRaised) {
          // a raise while the previous one is still unacknowledged is only possible from
          // cleared-unacknowledged: the operator still gets both events
          ++raises;
          raise_open = true;
          raise_seq = ev.sequence;
        }
      }
      for (auto it = pending.begin(); it != pending.end();) {
        if (it->first > step) {
          ++it;
          continue;
        }
        const AckResult r = latch.acknowledge(it->second, t, "op", &ev);
        if (r == AckResult::kAccepted) {
          received.push_back(ev);
          if (raise_open && it->second >= raise_seq) {
            raise_open = false;
            ++raises_acknowledged;
          }
        } else {
          // a refused ack is always for a sequence the operator has received
          EXPECT_NE(r, AckResult::kUnknownSequence);
        }
        it = pending.erase(it);
      }
    }
    // THEN every event the operator received has a distinct, increasing sequence
    for (std::size_t i = 1; i < received.size(); ++i) {
      ASSERT_EQ(received[i].sequence, received[i - 1].sequence + 1) << "run " << run;
    }
    // AND the latch is still latched exactly when a raise has not been acknowledged yet
    // and the condition has not been acknowledged away
    if (raise_open) {
      EXPECT_TRUE(latch.latched()) << "run " << run;
    }
    EXPECT_LE(raises_acknowledged, raises);
    EXPECT_GT(raises, 0);
  }
}

}  // namespace
}  // namespace usvfdi
