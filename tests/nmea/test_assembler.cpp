// SampleAssembler: sentences at their own rates -> samples on a fixed time base, in SI units and
// the project's signs (include/usv_fdi/nmea/assembler.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "support.hpp"
#include "usv_fdi/nmea/assembler.hpp"

namespace usvfdi::nmea {
namespace {

constexpr double kDeg = kPi / 180.0;

Rot rot(double deg_per_min, Status st = Status::kValid) {
  Rot x;
  x.rate_deg_per_min = deg_per_min;
  x.status = st;
  return x;
}

Rsa rsa(double deg, Status st = Status::kValid) {
  Rsa x;
  x.starboard_deg = deg;
  x.starboard_status = st;
  return x;
}

Vbw vbw(double longitudinal_kn, double transverse_kn, Status st = Status::kValid) {
  Vbw x;
  x.water_longitudinal_kn = longitudinal_kn;
  x.water_transverse_kn = transverse_kn;
  x.water_status = st;
  return x;
}

Vtg vtg(double kn, PositioningMode mode = PositioningMode::kAutonomous) {
  Vtg x;
  x.speed_kn = kn;
  x.mode = mode;
  return x;
}

/// The configuration with hold_until_due (include/usv_fdi/nmea/assembler.hpp).
AssemblerConfig until_due() {
  AssemblerConfig c;
  c.hold_until_due = true;
  return c;
}

TEST(Assembler, UnitsAndSignsOfTheShippedVessels) {
  SampleAssembler a(AssemblerConfig{});     // 10 Hz, 1 s, delta > 0 to port (b2 < 0)
  ASSERT_TRUE(a.add(0.0, rot(60.0)));       // 60 deg/min, bow to starboard
  ASSERT_TRUE(a.add(0.0, rsa(10.0)));       // rudder: bow turns to starboard
  ASSERT_TRUE(a.add(0.0, vbw(5.0, -0.5)));  // 5 kn ahead, 0.5 kn to port
  a.advance(0.0);
  const auto s = a.take();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_DOUBLE_EQ(s[0].t, 0.0);
  EXPECT_NEAR(s[0].r, 1.0 * kDeg, 1e-15);              // r > 0: starboard
  EXPECT_NEAR(s[0].delta, -10.0 * kDeg, 1e-15);        // RSA > 0 -> delta < 0 (delta > 0 = port)
  EXPECT_NEAR(s[0].v, -0.5 * 1852.0 / 3600.0, 1e-15);  // v < 0: port
  EXPECT_NEAR(s[0].u, 5.0 * 1852.0 / 3600.0, 1e-15);
  EXPECT_DOUBLE_EQ(s[0].age_r, 0.0);

  AssemblerConfig starboard;
  starboard.rudder_sign = RudderSign::kPositiveToStarboard;  // container, kvlcc2
  SampleAssembler b(starboard);
  b.add(0.0, rsa(10.0));
  b.advance(0.0);
  EXPECT_NEAR(b.take().at(0).delta, 10.0 * kDeg, 1e-15);
}

TEST(Assembler, DifferentRatesOnOneGrid) {
  for (const bool until_due : {false, true}) {
    // Held until due, a value goes to the grid time nearest it: the look time is half a grid
    // period after the grid time.
    const double look = until_due ? 0.05 : 0.0;
    AssemblerConfig c;
    c.hold_until_due = until_due;
    SampleAssembler a(c);
    // ROT at 20 Hz, RSA at 5 Hz, VBW at 1 Hz over 2 s, starting between grid times.
    for (int i = 0; i <= 40; ++i) {
      const double t = 100.01 + 0.05 * i;
      a.add(t, rot(i));
      if (i % 4 == 0) a.add(t, rsa(0.5 * i));
      if (i % 20 == 0) a.add(t, vbw(4.0, 0.1 * i));
    }
    a.advance(102.05);
    const auto s = a.take();
    ASSERT_FALSE(s.empty());
    EXPECT_NEAR(s.front().t, until_due ? 100.0 : 100.1, 1e-9);  // the grid is k / rate
    for (std::size_t k = 1; k < s.size(); ++k) EXPECT_NEAR(s[k].t - s[k - 1].t, 0.1, 1e-9);
    EXPECT_NEAR(s.back().t, 102.0, 1e-9);
    for (const auto& x : s) {
      // The latest ROT at or before the look time: i = floor((t + look - 100.01) / 0.05).
      const int i = static_cast<int>(std::floor((x.t + look - 100.01) / 0.05 + 1e-9));
      EXPECT_NEAR(x.r, yaw_rate_from_rot(i), 1e-12) << x.t;
      EXPECT_NEAR(x.age_r, x.t - (100.01 + 0.05 * i), 1e-9);
      const int j = i - i % 4;
      EXPECT_NEAR(x.delta, delta_from_rsa(0.5 * j, RudderSign::kPositiveToPort), 1e-12) << x.t;
      EXPECT_FALSE(std::isnan(x.v)) << x.t;  // VBW at 1 Hz, held within max_age = 1 s
      EXPECT_LE(x.age_v, 1.0);
    }
  }
}

TEST(Assembler, SampleUsesOnlyInputsAtOrBeforeItsTime) {
  AssemblerConfig c;
  c.hold_until_due = false;  // the look time is the grid time
  SampleAssembler a(c);
  a.add(0.05, rot(1.0));
  a.add(0.15, rot(2.0));  // emits 0.1 before applying this
  a.add(0.2, rot(3.0));   // exactly on the grid: in the sample at 0.2
  a.advance(0.2);
  const auto s = a.take();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_NEAR(s[0].r, yaw_rate_from_rot(1.0), 1e-15);
  EXPECT_NEAR(s[1].r, yaw_rate_from_rot(3.0), 1e-15);
}

TEST(Assembler, OldValuesGoMissingAndTheSentenceIsReportedStale) {
  AssemblerConfig c;
  c.max_age_s = 0.5;
  for (const bool until_due : {false, true}) {
    c.hold_until_due = until_due;
    SampleAssembler a(c);
    for (int i = 0; i <= 30; ++i) {
      if (i <= 10) a.add(0.1 * i, rot(1.0));  // ROT until t = 1.0
      a.add(0.1 * i, rsa(2.0));               // RSA until t = 3.0
    }
    EXPECT_EQ(a.out_of_order(), 0u);
    a.advance(3.0);
    // Held up to max_age_s; held until due: missing once the next ROT (1.1) is due.
    const double last_held = until_due ? 1.0 : 1.5;
    for (const auto& x : a.take()) {
      EXPECT_EQ(std::isnan(x.r), x.t > last_held + 1e-9) << x.t << " until_due " << until_due;
      EXPECT_FALSE(std::isnan(x.delta)) << x.t;
    }
    // Stale (the sentence has stopped) only after max_age_s either way.
    const auto st = a.stale(3.0);
    ASSERT_EQ(st.size(), 3u);  // r stopped; v and u never received
    EXPECT_EQ(st[0].quantity, "v");
    EXPECT_TRUE(st[0].never_received);
    EXPECT_EQ(st[1].quantity, "r");
    EXPECT_EQ(st[1].sentence, "ROT");
    EXPECT_FALSE(st[1].never_received);
    EXPECT_NEAR(st[1].age_s, 2.0, 1e-9);
    EXPECT_EQ(st[2].sentence, "VBW/VTG");
    EXPECT_TRUE(a.stale(1.4).size() == 2u);  // ROT not yet stale at 1.4
  }
}

// The sentences of a grid-rate INS (TAG times on the grid, as the simulator sends them): a lost
// ROT is a gap in r at its grid time, not the previous value again; the zero-order hold (the
// old behaviour, hold_until_due false) repeats it.
TEST(Assembler, ALostSentenceIsAGapNotTheOldValueAgain) {
  for (const bool until_due : {false, true}) {
    AssemblerConfig c;
    c.hold_until_due = until_due;
    SampleAssembler a(c);
    for (int i = 0; i <= 40; ++i) {
      if (i != 25 && i != 31 && i != 32) a.add(0.1 * i, rot(i));  // lost: 2.5, 3.1, 3.2
      a.add(0.1 * i, rsa(i));
    }
    a.advance(4.0);
    const auto s = a.take();
    ASSERT_EQ(s.size(), 41u);
    for (int i = 0; i <= 40; ++i) {
      const bool lost = i == 25 || i == 31 || i == 32;
      EXPECT_NEAR(s[i].delta, delta_from_rsa(i, RudderSign::kPositiveToPort), 1e-15);
      if (!lost) {
        EXPECT_NEAR(s[i].r, yaw_rate_from_rot(i), 1e-15) << i;
        EXPECT_NEAR(s[i].age_r, 0.0, 1e-12);
      } else if (until_due) {
        EXPECT_TRUE(std::isnan(s[i].r)) << i;
        EXPECT_TRUE(std::isnan(s[i].age_r)) << i;
      } else {
        EXPECT_NEAR(s[i].r, yaw_rate_from_rot(i == 32 ? 30 : i - 1), 1e-15) << i;
      }
    }
    if (until_due) {
      EXPECT_NEAR(a.learned_period("ROT"), 0.1, 1e-12);
    }
  }
}

// Sentences sent at the grid rate whose times straddle the grid (the time base starts at the
// first one, so they lie on it; the sender's jitter puts them before or after): each value goes
// to the grid time nearest it, every sample has its own ROT, none twice; a lost ROT is a gap.
// Held up to max_age (the look time the grid time), the ROTs just after their grid time are
// repeats of the one before.
TEST(Assembler, JitterAroundTheGridGoesToTheNearestGridTime) {
  for (const double jitter : {0.0015, 0.02}) {
    for (const bool until_due : {false, true}) {
      AssemblerConfig c;
      c.hold_until_due = until_due;
      SampleAssembler a(c);
      for (int i = 0; i < 200; ++i) {
        if (i == 120) continue;  // lost
        a.add(0.1 * i + jitter * std::sin(1.7 * i), rot(i));
      }
      a.advance(0.1 * 199);
      const auto s = a.take();
      int repeats = 0;
      double previous = std::nan("");
      for (const auto& x : s) {
        const int i = static_cast<int>(std::lround(x.t / 0.1));
        repeats += x.r == previous;
        if (!std::isnan(x.r)) previous = x.r;
        if (!until_due) continue;
        if (i == 120) {
          EXPECT_TRUE(std::isnan(x.r)) << "jitter " << jitter;
        } else {
          EXPECT_NEAR(x.r, yaw_rate_from_rot(i), 1e-15) << x.t << " jitter " << jitter;
        }
      }
      if (until_due) {
        EXPECT_EQ(s.size(), 199u) << "jitter " << jitter;  // 120 lost: no sample there
        EXPECT_EQ(repeats, 0) << "jitter " << jitter;
        EXPECT_NEAR(a.learned_period("ROT"), 0.1, 4 * jitter);
      } else {
        EXPECT_GT(repeats, 20) << "jitter " << jitter;
      }
    }
  }
}

// Two senders of one sentence on the group (two talkers, a doubled datagram on the receive
// clock): the intervals alternate short and long, no period is learned, and the values are
// held up to max_age_s as before. A copy within 2 ms is the same arrival.
TEST(Assembler, TwoSendersOfOneSentenceTeachNoPeriod) {
  SampleAssembler a(until_due());
  SampleAssembler copies(until_due());
  for (int i = 0; i < 100; ++i) {
    a.add(0.1 * i, rsa(1.0));  // on the grid: every grid time has a sample
    a.add(0.1 * i + 0.01, rot(i));
    a.add(0.1 * i + 0.04, rot(i + 0.5));  // the second talker, 30 ms later
    copies.add(0.1 * i, rsa(1.0));
    copies.add(0.1 * i + 0.01, rot(i));
    copies.add(0.1 * i + 0.0105, rot(i + 0.25));  // a copy 0.5 ms later (not read)
  }
  a.advance(0.1 * 99);
  copies.advance(0.1 * 99);
  EXPECT_TRUE(std::isnan(a.learned_period("ROT")));
  const auto s = a.take();
  ASSERT_EQ(s.size(), 100u);
  for (const auto& x : s) EXPECT_FALSE(std::isnan(x.r)) << x.t;
  EXPECT_NEAR(copies.learned_period("ROT"), 0.1, 1e-9);
  const auto c = copies.take();
  ASSERT_EQ(c.size(), 100u);
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_NEAR(c[i].r, yaw_rate_from_rot(static_cast<double>(i)), 1e-15) << c[i].t;
  }
}

// A sentence faster than the grid (ROT at 20 Hz on a 10 Hz grid) with sentences lost: each
// sample has the latest ROT at or before its look time, never a gap.
TEST(Assembler, ASentenceFasterThanTheGridGivesItsLatestValueOverALoss) {
  SampleAssembler a(until_due());
  std::vector<double> times;
  for (int i = 0; i < 400; ++i) {
    if (i % 2 == 0) a.add(0.05 * i, rsa(1.0));  // on the grid: every grid time has a sample
    // Lost: every 10th ROT from the 2nd (the one nearest grid time x.1 or x.6: the one before
    // it, not yet in a sample, stands in) and two in a row before grid times x.3 and x.8 (no ROT
    // since the previous sample's: a gap).
    if (i % 10 == 2 || i % 10 == 5 || i % 10 == 6) continue;
    times.push_back(0.05 * i + 0.013);
    a.add(times.back(), rot(i));
  }
  a.advance(0.1 * 199);
  EXPECT_NEAR(a.learned_period("ROT"), 0.05, 1e-9);
  const auto s = a.take();
  ASSERT_EQ(s.size(), 200u);
  // Each sample has the latest ROT at or before its look time x.t + 0.05, unless the previous
  // sample had that one: then a gap (from 1 s on: the period is learned from 4 intervals).
  int used = -1, gaps = 0, stand_ins = 0;
  for (const auto& x : s) {
    int latest = -1;
    for (double t : times) {
      if (t <= x.t + 0.05) latest = static_cast<int>(std::lround((t - 0.013) / 0.05));
    }
    if (x.t < 1.0 - 1e-9) {
      used = latest;
      continue;
    }
    if (latest == used) {
      ++gaps;
      EXPECT_TRUE(std::isnan(x.r)) << x.t;
      continue;
    }
    ASSERT_FALSE(std::isnan(x.r)) << x.t;
    EXPECT_NEAR(x.r, yaw_rate_from_rot(latest), 1e-15) << x.t;
    stand_ins += 0.05 * latest + 0.013 < x.t;  // measured before its grid time: a stand-in
    used = latest;
  }
  EXPECT_EQ(gaps, 38);       // grid times x.3 and x.8 from 1 s
  EXPECT_EQ(stand_ins, 38);  // grid times x.1 and x.6, whose successor was due before the look
}

// A sentence that changes its rate (10 Hz, then 1 Hz from 5 s): learned again after three
// intervals off the old period, then held over the grid times between arrivals.
TEST(Assembler, ANewRateIsLearnedAgain) {
  AssemblerConfig c = until_due();
  c.max_age_s = 3.0;
  SampleAssembler b(c);
  for (int i = 0; i <= 200; ++i) {
    const double t = 0.1 * i;
    if (i <= 50 || i % 10 == 0) b.add(t, rot(i <= 50 ? 1.0 : 2.0));  // 1 Hz from 5 s
    b.add(t, rsa(1.0));
  }
  b.advance(20.0);
  EXPECT_NEAR(b.learned_period("ROT"), 1.0, 1e-9);
  const auto s = b.take();
  ASSERT_EQ(s.size(), 201u);
  int missing_after_9 = 0;
  for (const auto& x : s) missing_after_9 += x.t > 9.0 && std::isnan(x.r);
  // Learned again by 9 s (three intervals off the old period at 6, 7, 8 s, a fourth at 9 s),
  // then held over the grid times between the arrivals.
  EXPECT_EQ(missing_after_9, 0);
}

// The surge speed: where the water speed is withheld as a repetition (its VBW lost), u is
// missing, not the ground speed for one sample.
TEST(Assembler, AWithheldWaterSpeedIsNotReplacedByTheGroundSpeed) {
  SampleAssembler a(until_due());
  for (int i = 0; i <= 30; ++i) {
    if (i != 20) a.add(0.1 * i, vbw(8.0, 0.0));
    a.add(0.1 * i, vtg(10.0));
  }
  a.advance(3.0);
  for (const auto& x : a.take()) {
    if (std::lround(x.t / 0.1) == 20) {
      EXPECT_TRUE(std::isnan(x.u)) << x.t;
    } else {
      EXPECT_NEAR(x.u, speed_from_knots(8.0), 1e-12) << x.t;
    }
  }
}

// A sentence slower than the grid (VBW at 1 Hz on a 10 Hz grid) is held over the grid times
// between its arrivals, up to the next one's due time; a lost VBW leaves v missing until the
// next one comes.
TEST(Assembler, ASlowSentenceIsHeldUntilItsNextIsDue) {
  AssemblerConfig c = until_due();
  c.max_age_s = 3.0;
  SampleAssembler a(c);
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.1 * i;
    a.add(t, rot(1.0));
    if (i % 10 == 3 && i != 63) a.add(t, vbw(5.0, 0.1 * i));  // 1 Hz at x.3 s; 6.3 lost
  }
  a.advance(10.0);
  EXPECT_NEAR(a.learned_period("VBW"), 1.0, 1e-9);
  for (const auto& x : a.take()) {
    if (x.t < 0.3 - 1e-9) continue;
    const bool lost = x.t > 6.3 - 1e-9 && x.t < 7.3 - 1e-9;
    EXPECT_EQ(std::isnan(x.v), lost) << x.t;
    if (!lost) {
      EXPECT_LT(x.age_v, 1.0 - 1e-9) << x.t;
    }
  }
}

// A sentence whose intervals scatter (an irregular sender) has no period: it is held up to
// max_age_s as before.
TEST(Assembler, AnIrregularSentenceIsHeldUpToMaxAge) {
  SampleAssembler a(until_due());
  const double times[] = {0.0, 0.05, 0.4, 0.45, 0.9, 1.3, 1.32, 1.8, 2.0, 2.6, 2.65, 3.0};
  for (double t : times) a.add(t, rot(t * 10));
  a.advance(3.0);
  EXPECT_TRUE(std::isnan(a.learned_period("ROT")));
  for (const auto& x : a.take()) EXPECT_FALSE(std::isnan(x.r)) << x.t;
}

TEST(Assembler, StatusVInvalidatesWithoutRefreshingTheAge) {
  AssemblerConfig c;
  c.hold_until_due = false;  // the look time is the grid time
  SampleAssembler a(c);
  a.add(0.0, rot(5.0));
  a.add(0.25, rot(6.0, Status::kInvalid));
  a.advance(0.3);
  const auto s = a.take();
  ASSERT_EQ(s.size(), 3u);  // 0.0, 0.1, 0.2 valid; 0.3 has nothing fresh: not emitted
  EXPECT_FALSE(std::isnan(s[2].r));
  a.add(0.5, rot(7.0));
  a.advance(0.5);
  const auto later = a.take();
  ASSERT_EQ(later.size(), 1u);
  EXPECT_NEAR(later[0].t, 0.5, 1e-12);
  EXPECT_TRUE(a.stale(0.9).empty());  // ROT valid at 0.5; the others not yet max_age_s late
  // An empty field is invalid as well.
  Rot empty;
  empty.status = Status::kValid;
  a.add(0.6, empty);
  a.advance(0.6);
  EXPECT_TRUE(a.take().empty());
  // Stale counts from the last VALID value (0.5), not from the invalid one (0.6).
  ASSERT_FALSE(a.stale(1.55).empty());
  bool r_stale = false;
  for (const auto& x : a.stale(1.55))
    r_stale = r_stale || (x.quantity == "r" && std::fabs(x.age_s - 1.05) < 1e-9);
  EXPECT_TRUE(r_stale);
}

TEST(Assembler, SurgeFromVbwWaterElseVtg) {
  SampleAssembler a(AssemblerConfig{});
  a.add(0.0, vtg(10.0));
  a.advance(0.0);
  EXPECT_NEAR(a.take().at(0).u, speed_from_knots(10.0), 1e-12);  // VTG alone
  a.add(0.1, vbw(8.0, 0.0));
  a.add(0.1, vtg(10.0));
  a.advance(0.1);
  EXPECT_NEAR(a.take().at(0).u, speed_from_knots(8.0), 1e-12);  // VBW water first
  a.add(0.2, vbw(8.0, 0.0, Status::kInvalid));
  a.advance(0.2);
  auto s = a.take().at(0);
  EXPECT_NEAR(s.u, speed_from_knots(10.0), 1e-12);  // water invalid: VTG
  EXPECT_TRUE(std::isnan(s.v));
  a.add(0.3, vtg(10.0, PositioningMode::kNotValid));
  a.advance(0.3);
  EXPECT_TRUE(a.take().empty());  // nothing valid at 0.3
}

TEST(Assembler, PortRudderWhenOnlyItIsValid) {
  SampleAssembler a(AssemblerConfig{});
  Rsa twin;
  twin.starboard_deg = 3.0;
  twin.starboard_status = Status::kInvalid;
  twin.port_deg = 4.0;
  twin.port_status = Status::kValid;
  a.add(0.0, twin);
  a.advance(0.0);
  EXPECT_NEAR(a.take().at(0).delta, -4.0 * kDeg, 1e-15);
}

TEST(Assembler, RefusesTimesThatGoBackOrAreNotFinite) {
  SampleAssembler a(AssemblerConfig{});
  EXPECT_TRUE(a.add(1.0, rot(1.0)));
  EXPECT_FALSE(a.add(0.9, rot(2.0)));
  EXPECT_FALSE(a.add(std::nan(""), rot(2.0)));
  EXPECT_FALSE(a.add(HUGE_VAL, rot(2.0)));
  EXPECT_EQ(a.out_of_order(), 3u);
  a.advance(1.0);
  EXPECT_NEAR(a.take().at(0).r, yaw_rate_from_rot(1.0), 1e-15);
}

TEST(Assembler, NoFloodAfterALongSilence) {
  AssemblerConfig c;
  c.rate_hz = 50.0;
  SampleAssembler a(c);
  a.add(1.7e9, rot(1.0));
  a.add(1.7e9 + 3600.0, rot(2.0));
  a.advance(1.7e9 + 3600.0);
  const auto s = a.take();
  EXPECT_LE(s.size(), 52u + 1u);  // one second of held values, then the new one
  EXPECT_NEAR(s.back().r, yaw_rate_from_rot(2.0), 1e-15);
  EXPECT_NEAR(s.back().t, 1.7e9 + 3600.0, 1e-6);
}

TEST(Assembler, AddSentenceDispatchesAndReports) {
  SampleAssembler a(AssemblerConfig{});
  const auto used = a.add_sentence(0.0, parse_sentence("$HEROT,-12.4,A*31").value());
  EXPECT_EQ(used.use, InputUse::kUsed);
  EXPECT_EQ(a.add_sentence(0.0, test::sentence("AGRSA,5.2,A,,V")).use, InputUse::kUsed);
  EXPECT_EQ(a.add_sentence(0.0, test::sentence("IIVBW,7.5,-0.3,A,7.6,-0.2,A")).use,
            InputUse::kUsed);
  EXPECT_EQ(a.add_sentence(0.0, test::sentence("GPVTG,70.5,T,,M,10.2,N,18.9,K,A")).use,
            InputUse::kUsed);
  EXPECT_EQ(a.add_sentence(0.0, parse_sentence("$GPHDT,72.14,T*35").value()).use,
            InputUse::kNotAnInput);
  EXPECT_EQ(a.add_sentence(0.0, test::sentence("PROT,1,A")).use, InputUse::kNotAnInput);
  const auto refused = a.add_sentence(0.0, test::sentence("HEROT,20000,A"));
  EXPECT_EQ(refused.use, InputUse::kRefused);
  EXPECT_EQ(refused.rejection.reason, Reason::kOutOfRange);
  EXPECT_EQ(a.add_sentence(-1.0, test::sentence("HEROT,1,A")).use, InputUse::kOutOfOrder);
  // Read, but its status says the value is not valid (or the value fed is empty): kNotValid
  SampleAssembler b(AssemblerConfig{});
  EXPECT_EQ(b.add_sentence(0.0, test::sentence("HEROT,-12.4,V")).use, InputUse::kNotValid);
  EXPECT_EQ(b.add_sentence(0.0, test::sentence("AGRSA,5.2,V,,V")).use, InputUse::kNotValid);
  EXPECT_EQ(b.add_sentence(0.0, test::sentence("IIVBW,7.5,-0.3,V,7.6,-0.2,A")).use,
            InputUse::kNotValid);
  EXPECT_EQ(b.add_sentence(0.0, test::sentence("IIVBW,7.5,,A,,,V")).use, InputUse::kNotValid);
  EXPECT_EQ(b.add_sentence(0.0, test::sentence("GPVTG,70.5,T,,M,10.2,N,18.9,K,N")).use,
            InputUse::kNotValid);
  a.advance(0.0);
  const auto s = a.take();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(s[0].r, yaw_rate_from_rot(-12.4), 1e-15);  // the refused 20000 changed nothing
  EXPECT_NEAR(s[0].delta, delta_from_rsa(5.2, RudderSign::kPositiveToPort), 1e-15);
  EXPECT_NEAR(s[0].v, speed_from_knots(-0.3), 1e-15);
  EXPECT_NEAR(s[0].u, speed_from_knots(7.5), 1e-15);
}

TEST(Assembler, RefusesBadConfiguration) {
  AssemblerConfig c;
  c.rate_hz = 0.0;
  EXPECT_THROW(SampleAssembler{c}, std::invalid_argument);
  c.rate_hz = std::nan("");
  EXPECT_THROW(SampleAssembler{c}, std::invalid_argument);
  c = AssemblerConfig{};
  c.max_age_s = -1.0;
  EXPECT_THROW(SampleAssembler{c}, std::invalid_argument);
}

}  // namespace
}  // namespace usvfdi::nmea
