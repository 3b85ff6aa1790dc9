// Voyage simulator: determinism, autopilot and manoeuvres, speed changes, waves, sensors
// and faults, each checked against the configuration that produced it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kDeg = M_PI / 180.0;

std::shared_ptr<const Hull> hull(const std::string& name) {
  auto h = voyage_hull(name);
  if (!h) throw std::runtime_error("no hull " + name);
  return h;
}

VoyageConfig base(const Hull& h, const std::string& scenario, double duration, double rate = 10) {
  VoyageConfig c;
  c.rate_hz = rate;
  c.duration = duration;
  c.legs = scenario_legs(scenario, h);
  sensor_preset("ideal", 5e-3, 5e-4, &c.sensors);
  return c;
}

double mean(const std::vector<double>& x) {
  return std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

double variance(const std::vector<double>& x) {
  const double m = mean(x);
  double s = 0;
  for (const double v : x) s += (v - m) * (v - m);
  return s / static_cast<double>(x.size() - 1);
}

/// Autocorrelation of x at lag k (normalised by the lag-0 value).
double autocorr(const std::vector<double>& x, std::size_t k) {
  const double m = mean(x);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    den += (x[i] - m) * (x[i] - m);
    if (i + k < x.size()) num += (x[i] - m) * (x[i + k] - m);
  }
  return num / den;
}

bool same_row(const VoyageRow& a, const VoyageRow& b) {
  const auto eq = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return eq(a.t, b.t) && eq(a.v, b.v) && eq(a.r, b.r) && eq(a.delta, b.delta) && eq(a.psi, b.psi) &&
         eq(a.u_true, b.u_true) && a.fault_a == b.fault_a && a.fault_g == b.fault_g &&
         a.duplicate == b.duplicate;
}

/// Index ranges [first, last) of the rows of each leg of kind m.
std::vector<std::pair<std::size_t, std::size_t>> legs_of(const std::vector<VoyageRow>& rows,
                                                         Manoeuvre m) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].manoeuvre != m) continue;
    if (out.empty() || out.back().second != i) out.emplace_back(i, i);
    out.back().second = i + 1;
  }
  return out;
}

// ------------------------------------------------------------------------ determinism

TEST(Voyage, SameSeedGivesTheSameRowsAndAnotherSeedDoesNot) {
  // GIVEN a voyage with waves, current, wind, MEMS sensors and the standard faults
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "voyage", 400);
  sensor_preset("mems", 5e-3, 5e-4, &c.sensors);
  c.environment.sea = sea_state(4);
  c.environment.current = 0.2;
  c.environment.current_sigma = 0.05;
  c.environment.wind = 1.0 * kDeg;
  c.environment.wind_sigma = 0.5 * kDeg;
  c.faults = standard_faults(c, 60, 10, 10);
  // WHEN it runs twice with seed 7 and once with seed 8
  c.seed = 7;
  const auto a = run_voyage(h, c), b = run_voyage(h, c);
  c.seed = 8;
  const auto d = run_voyage(h, c);
  // THEN the same seed gives the same rows bit for bit, another seed other rows
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(same_row(a[i], b[i])) << "row " << i;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < std::min(a.size(), d.size()); ++i) differ += !same_row(a[i], d[i]);
  EXPECT_GT(differ, a.size() / 2);
}

TEST(Voyage, SwitchingOnOneProcessLeavesTheOthersStreamsAlone) {
  // GIVEN the same voyage without and with a current
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 200);
  c.environment.sea = sea_state(3);
  const auto calm = run_voyage(h, c);
  c.environment.current = 0.5;
  const auto current = run_voyage(h, c);
  // THEN the wave motion and the sensor noise are the same draws
  ASSERT_EQ(calm.size(), current.size());
  for (std::size_t i = 0; i < calm.size(); ++i) {
    ASSERT_EQ(calm[i].r_wave, current[i].r_wave);
    ASSERT_NEAR(calm[i].r - calm[i].r_true, current[i].r - current[i].r_true, 1e-15);
  }
}

// ----------------------------------------------------------------- autopilot, manoeuvres

TEST(Voyage, AutopilotHoldsTheCourseOnTheMeasuredHeading) {
  for (const std::string name : {"mariner-linear", "otter"}) {
    // GIVEN a noisy straight passage with a wind and a current
    const auto h = hull(name);
    VoyageConfig c = base(*h, "hold", 30 * leg_period(*h));
    c.environment.current = 0.3;
    c.environment.wind = 2.0 * kDeg;
    c.sensors.compass_sigma = 0.2 * kDeg;
    const auto rows = run_voyage(h, c);
    // THEN after settling the heading stays within 1 deg of the course (the integral action
    // takes out the steady yaw moment of wind and current)
    double worst = 0;
    for (const VoyageRow& w : rows) {
      if (w.t_true > 15 * leg_period(*h)) worst = std::max(worst, std::abs(w.psi));
    }
    EXPECT_LT(worst, 1.0 * kDeg) << name;
  }
}

TEST(Voyage, CourseChangesReachEachNewCourse) {
  for (const std::string name : {"mariner-linear", "otter"}) {
    // GIVEN the course scenario (+10, -10, -10, +10 deg)
    const auto h = hull(name);
    VoyageConfig c = base(*h, "course", 5 * leg_period(*h));
    const auto rows = run_voyage(h, c);
    const auto legs = legs_of(rows, Manoeuvre::kCourse);
    ASSERT_EQ(legs.size(), 1u);  // one run of consecutive course legs
    // THEN at the end of each leg the heading is within 1.5 deg of its reference
    const double p = leg_period(*h);
    const double want[] = {10 * kDeg, 0.0, -10 * kDeg, 0.0};
    for (int j = 0; j < 4; ++j) {
      const double t_end = (j + 2) * p - 1.0;
      const auto it = std::find_if(rows.begin(), rows.end(),
                                   [&](const VoyageRow& w) { return w.t_true >= t_end; });
      ASSERT_NE(it, rows.end());
      EXPECT_NEAR(it->psi, want[j], 1.5 * kDeg) << name << " leg " << j;
    }
  }
}

TEST(Voyage, ZigzagsSwitchTheRudderAtTheHeadingAndOvershoot) {
  for (const double angle : {10.0, 20.0}) {
    for (const std::string name : {"mariner-linear", "otter"}) {
      // GIVEN a zigzag angle/angle
      const auto h = hull(name);
      const std::string sc = angle == 10.0 ? "zigzag10" : "zigzag20";
      VoyageConfig c = base(*h, sc, 11 * leg_period(*h));
      const auto rows = run_voyage(h, c);
      const auto legs = legs_of(rows, Manoeuvre::kZigzag);
      ASSERT_EQ(legs.size(), 1u);
      // THEN the rudder is +-angle, switched at least 4 times, each time after the heading
      // passed +-angle off the base course, and the heading overshoots it
      int switches = 0;
      double max_dev = 0;
      const double base_psi = rows[legs[0].first].psi_meas;
      for (std::size_t i = legs[0].first + 1; i < legs[0].second; ++i) {
        EXPECT_NEAR(std::abs(rows[i].delta_cmd), angle * kDeg, 1e-12);
        max_dev = std::max(max_dev, std::abs(rows[i].psi - base_psi));
        if (rows[i].delta_cmd != rows[i - 1].delta_cmd) {
          ++switches;
          EXPECT_GE(std::abs(rows[i].psi_meas - base_psi), angle * kDeg - 1e-9);
        }
      }
      EXPECT_GE(switches, 4) << name << " " << sc;
      EXPECT_GT(max_dev, angle * kDeg) << name << " " << sc;
    }
  }
}

TEST(Voyage, TurningCirclesTurnFullCirclesAndResumeTheCourse) {
  for (const std::string name : {"mariner-linear", "otter"}) {
    const auto h = hull(name);
    VoyageConfig c = base(*h, "turn", 2000 + 12 * leg_period(*h));
    const auto rows = run_voyage(h, c);
    const auto legs = legs_of(rows, Manoeuvre::kTurn);
    ASSERT_GE(legs.size(), 2u) << name;
    // on a linear hull with the rudder of a circle of diameter 4 L
    const double r_ss = h->nominal_speed() / (2 * h->limits().length);
    double r_max = 0;
    for (std::size_t i = legs[0].first; i < legs[0].second; ++i) {
      r_max = std::max(r_max, std::abs(rows[i].r_lf));
      EXPECT_NEAR(std::abs(rows[i].delta_cmd), turning_rudder(*h), 1e-12);
    }
    EXPECT_NEAR(r_max, r_ss, 0.15 * r_ss) << name;
    // THEN each turn ends after 360 deg (starboard first, then port)
    for (int j = 0; j < 2; ++j) {
      const double turned = rows[legs[j].second - 1].psi_meas - rows[legs[j].first].psi_meas;
      EXPECT_NEAR(std::abs(turned), 2 * M_PI, 10 * kDeg) << name << " turn " << j;
      EXPECT_EQ(turned > 0, j == 0) << name;
      // and the autopilot takes her back onto the course (mod 360) within the next leg
      // (the hold leg of 2 leg periods after the turn)
      const std::size_t end =
          legs[j].second + static_cast<std::size_t>(2 * leg_period(*h) * c.rate_hz) - 2;
      ASSERT_LT(end, rows.size());
      EXPECT_EQ(rows[end].manoeuvre, Manoeuvre::kHold);
      EXPECT_NEAR(std::remainder(rows[end].psi, 2 * M_PI), 0.0, 2 * kDeg) << name << " turn " << j;
    }
  }
}

TEST(Voyage, ZigzagsAndTurningCirclesTakeASideStarboardByDefault) {
  // GIVEN every scenario's legs by default, to starboard and to port
  const auto h = hull("mariner-linear");
  for (const std::string& sc : scenario_names()) {
    const auto def = scenario_legs(sc, *h);
    const auto stb = scenario_legs(sc, *h, Side::kStarboard);
    const auto port = scenario_legs(sc, *h, Side::kPort);
    ASSERT_EQ(def.size(), stb.size()) << sc;
    ASSERT_EQ(port.size(), stb.size()) << sc;
    for (std::size_t i = 0; i < stb.size(); ++i) {
      // THEN the default is starboard, bit for bit
      EXPECT_EQ(def[i].kind, stb[i].kind) << sc << " " << i;
      EXPECT_EQ(def[i].duration, stb[i].duration) << sc << " " << i;
      EXPECT_EQ(def[i].heading, stb[i].heading) << sc << " " << i;
      EXPECT_EQ(def[i].rudder, stb[i].rudder) << sc << " " << i;
      EXPECT_EQ(def[i].throttle, stb[i].throttle) << sc << " " << i;
      // and port mirrors the zigzags' and turns' rudder (and the turns' heading) only
      const bool zig = stb[i].kind == Manoeuvre::kZigzag, turn = stb[i].kind == Manoeuvre::kTurn;
      EXPECT_EQ(port[i].kind, stb[i].kind) << sc << " " << i;
      EXPECT_EQ(port[i].duration, stb[i].duration) << sc << " " << i;
      EXPECT_EQ(port[i].throttle, stb[i].throttle) << sc << " " << i;
      EXPECT_EQ(port[i].rudder, zig || turn ? -stb[i].rudder : stb[i].rudder) << sc << " " << i;
      EXPECT_EQ(port[i].heading, turn ? -stb[i].heading : stb[i].heading) << sc << " " << i;
    }
  }
  // GIVEN a zigzag and the turns to port first, on a ship and on the Otter
  for (const std::string name : {"mariner-linear", "otter"}) {
    const auto hl = hull(name);
    for (const std::string sc : {"zigzag10", "turn"}) {
      VoyageConfig c = base(*hl, sc, 4 * leg_period(*hl));
      const auto stb_rows = run_voyage(hl, c);
      c.legs = scenario_legs(sc, *hl, Side::kPort);
      const auto port_rows = run_voyage(hl, c);
      const Manoeuvre m = sc == "turn" ? Manoeuvre::kTurn : Manoeuvre::kZigzag;
      const auto legs = legs_of(port_rows, m);
      ASSERT_FALSE(legs.empty()) << name << " " << sc;
      const std::size_t i0 = legs[0].first;
      // THEN the first rudder command is the starboard one mirrored, and the heading first
      // leaves the base course to port
      EXPECT_NE(port_rows[i0].delta_cmd, 0.0) << name << " " << sc;
      EXPECT_EQ(port_rows[i0].delta_cmd, -stb_rows[i0].delta_cmd) << name << " " << sc;
      const double base_psi = port_rows[i0].psi_meas;
      double first_dev = 0.0;
      for (std::size_t i = i0; i < legs[0].second && first_dev == 0.0; ++i) {
        const double dev = port_rows[i].psi - base_psi;
        if (std::abs(dev) > 5 * kDeg) first_dev = dev;
      }
      EXPECT_LT(first_dev, 0.0) << name << " " << sc;
    }
  }
}

TEST(Voyage, SpeedChangesChangeTheSurgeSpeed) {
  for (const std::string name : {"mariner-linear", "otter"}) {
    // GIVEN throttle steps 0.7, 1.0, 1.3, 1.0, each held for 3 leg periods
    const auto h = hull(name);
    const double p = leg_period(*h), u0 = h->nominal_speed();
    VoyageConfig c = base(*h, "speed", 13 * p);
    const auto rows = run_voyage(h, c);
    // THEN u follows each step: at the end of each 3-period block it is near throttle * U0
    const double want[] = {0.7, 1.0, 1.3, 1.0};
    for (int j = 0; j < 4; ++j) {
      const double t_end = (1 + 3 * (j + 1)) * p - 1.0;
      const auto it = std::find_if(rows.begin(), rows.end(),
                                   [&](const VoyageRow& w) { return w.t_true >= t_end; });
      ASSERT_NE(it, rows.end());
      EXPECT_NEAR(it->u_true / u0, want[j], 0.05) << name << " step " << j;
      EXPECT_DOUBLE_EQ(it->throttle, want[j]);
    }
  }
}

TEST(Voyage, SlowPassageRunsAtHalfSpeed) {
  const auto h = hull("otter");
  const double p = leg_period(*h);
  VoyageConfig c = base(*h, "slow", 5.5 * p);
  const auto rows = run_voyage(h, c);
  EXPECT_NEAR(rows.back().u_true / h->nominal_speed(), 0.5, 0.03);
}

TEST(Voyage, TheAutopilotFeedsBackTheMeasuredYawRate) {
  // GIVEN the same voyage with and without a gyro bias of 10 sigma from 100 s
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "course", 200);
  const auto healthy = run_voyage(h, c);
  c.faults.push_back(sigma_fault(c, Sensor::kGyro, FaultKind::kBias, 100, 200, 10));
  const auto faulty = run_voyage(h, c);
  // THEN the rudder command is the same before the fault and differs after it
  ASSERT_EQ(healthy.size(), faulty.size());
  double before = 0, after = 0;
  for (std::size_t i = 0; i < healthy.size(); ++i) {
    const double d = std::abs(healthy[i].delta_cmd - faulty[i].delta_cmd);
    (healthy[i].t_true < 100 ? before : after) =
        std::max(d, healthy[i].t_true < 100 ? before : after);
  }
  EXPECT_EQ(before, 0.0);
  EXPECT_GT(after, 0.1 * kDeg);
}

TEST(Voyage, RudderIsSaturatedAndRateLimited) {
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "turn", 600);
  const auto rows = run_voyage(h, c);
  const HullLimits l = h->limits();
  for (std::size_t i = 1; i < rows.size(); ++i) {
    EXPECT_LE(std::abs(rows[i].delta_true), l.max_rudder + 1e-12);
    EXPECT_LE(std::abs(rows[i].delta_true - rows[i - 1].delta_true),
              l.max_rudder_rate / c.rate_hz + 1e-12);
  }
}

/// A voyage of one turning leg from t = 0 with rudder `rudder` (a step of the command at
/// t = 0; the leg turns by at most 360 deg, far more than the run lasts), calm water, no sensor
/// noise, sampled at 20 samples per servo time constant for `duration` [s].
std::vector<VoyageRow> rudder_step(const std::shared_ptr<const Hull>& h, double rudder,
                                   double duration) {
  VoyageConfig c;
  c.rate_hz = 20.0 / h->limits().rudder_time_constant;
  c.duration = duration;
  sensor_preset("ideal", 0, 0, &c.sensors);
  Leg turn;
  turn.kind = Manoeuvre::kTurn;
  turn.duration = 10 * duration;
  turn.heading = 2 * M_PI;
  turn.rudder = rudder;
  c.legs = {turn};
  return run_voyage(h, c);
}

TEST(Voyage, RudderFollowsAStepOfTheCommandThroughTheServoLag) {
  for (const std::string& name : voyage_hull_names()) {
    // GIVEN a step of the rudder command small enough that the servo is not rate-limited
    // (initial rate X / T = half the rate limit)
    const auto h = hull(name);
    const HullLimits l = h->limits();
    const double T = l.rudder_time_constant;
    const double X = std::min(0.5 * l.max_rudder_rate * T, 0.5 * l.max_rudder);
    const auto rows = rudder_step(h, X, 5 * T);
    ASSERT_GE(rows.size(), 100u) << name;
    // THEN the rudder is the first-order lag of the step, X (1 - exp(-t / T)): 63.2 % of it
    // after one time constant, 95 % after three; on the side of the command, never beyond it
    for (const VoyageRow& w : rows) {
      ASSERT_NEAR(std::abs(w.delta_cmd), X, 1e-12) << name << " t=" << w.t_true;
      EXPECT_GE(w.delta_true * w.delta_cmd, 0.0) << name << " t=" << w.t_true;
      EXPECT_NEAR(std::abs(w.delta_true), X * -std::expm1(-w.t_true / T), 1e-6 * X)
          << name << " t=" << w.t_true;
    }
    EXPECT_NEAR(std::abs(rows[20].delta_true) / X, 0.632, 0.001) << name;  // t = T
    EXPECT_NEAR(std::abs(rows[60].delta_true) / X, 0.950, 0.001) << name;  // t = 3 T
  }
}

TEST(Voyage, RudderStepBeyondTheLimitIsRateLimitedThenLagsIntoTheSaturation) {
  for (const std::string& name : voyage_hull_names()) {
    // GIVEN a command of twice the rudder limit M
    const auto h = hull(name);
    const HullLimits l = h->limits();
    const double M = l.max_rudder, rate = l.max_rudder_rate, T = l.rudder_time_constant;
    // THEN the command is saturated at M; the rudder moves at the rate limit until the lag's
    // rate (M - delta) / T falls below it (delta = M - rate T, at t1), then lags into M:
    // delta = rate t before t1, M - rate T exp(-(t - t1) / T) after; it never exceeds M
    const double t1 = std::max(0.0, (M - rate * T) / rate);
    const auto expected = [&](double t) {
      if (t1 == 0.0) return M * -std::expm1(-t / T);
      return t <= t1 ? rate * t : M - rate * T * std::exp(-(t - t1) / T);
    };
    const auto rows = rudder_step(h, 2 * M, t1 + 6 * T);
    for (const VoyageRow& w : rows) {
      ASSERT_NEAR(std::abs(w.delta_cmd), M, 1e-12) << name << " t=" << w.t_true;
      EXPECT_LE(std::abs(w.delta_true), M) << name << " t=" << w.t_true;
      EXPECT_NEAR(std::abs(w.delta_true), expected(w.t_true), 1e-5 * M)
          << name << " t=" << w.t_true;
    }
    EXPECT_NEAR(std::abs(rows.back().delta_true), M, 0.01 * rate * T) << name;
  }
}

TEST(Voyage, DitherAddsASineToTheRudderCommand) {
  // (the Mariner: her heading loop is far slower than a 10 s dither)
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 1000);
  sensor_preset("ideal", 0, 0, &c.sensors);
  const auto plain = run_voyage(h, c);
  c.autopilot.dither = 0.5 * kDeg;
  c.autopilot.dither_period = 10;
  const auto dithered = run_voyage(h, c);
  // THEN the command carries a sine of the dither period (the autopilot answers the yaw it
  // makes, so less than the dither itself), and without dither nothing moves
  double corr = 0;
  for (const VoyageRow& w : dithered) corr += w.delta_cmd * std::sin(2 * M_PI * w.t_true / 10);
  const double amp = 2 * corr / static_cast<double>(dithered.size());
  EXPECT_GT(amp, 0.4 * kDeg);
  EXPECT_LT(amp, 0.55 * kDeg);
  for (const VoyageRow& w : plain) EXPECT_LT(std::abs(w.delta_cmd), 1e-9);
}

TEST(Voyage, EveryZooHullHoldsItsCoursesAndFollowsTheThrottle) {
  for (const std::string& name : voyage_hull_names()) {
    // GIVEN the hull under course changes and under throttle steps
    const auto h = hull(name);
    const double p = leg_period(*h);
    VoyageConfig c = base(*h, "course", 5 * p, 5.0);
    const auto rows = run_voyage(h, c);
    // THEN every sample is finite and each course is reached within 1.5 deg by the leg's end
    for (const VoyageRow& w : rows)
      ASSERT_TRUE(std::isfinite(w.psi + w.u_true + w.v + w.r)) << name;
    for (int j = 0; j < 4; ++j) {
      const auto it = std::find_if(rows.begin(), rows.end(), [&](const VoyageRow& w) {
        return w.t_true >= (j + 2) * p - 1.0;
      });
      ASSERT_NE(it, rows.end());
      EXPECT_NEAR(it->psi, it->psi_ref, 1.5 * kDeg) << name << " leg " << j;
    }
    // AND the surge speed goes down with -30 % throttle and up with +30 %
    c = base(*h, "speed", 13 * p, 5.0);
    const auto sp = run_voyage(h, c);
    double u_end[4] = {0, 0, 0, 0};
    for (int j = 0; j < 4; ++j) {
      const double t_end = (1 + 3 * (j + 1)) * p - 1.0;
      const auto it =
          std::find_if(sp.begin(), sp.end(), [&](const VoyageRow& w) { return w.t_true >= t_end; });
      ASSERT_NE(it, sp.end());
      u_end[j] = it->u_true;
    }
    const double u0 = h->nominal_speed();
    EXPECT_LT(u_end[0], 0.9 * u0) << name;
    EXPECT_NEAR(u_end[1], u0, 0.05 * u0) << name;
    EXPECT_GT(u_end[2], 1.1 * u0) << name;
    EXPECT_NEAR(u_end[3], u0, 0.05 * u0) << name;
  }
}

// ---------------------------------------------------------------------------- waves

TEST(Voyage, WaveMotionHasTheSpectrumsPeakPeriodAndVariance) {
  for (const int code : {3, 4, 5}) {
    // GIVEN a straight passage in sea state code
    const auto h = hull("mariner-linear");
    VoyageConfig c = base(*h, "hold", 7200);
    const SeaState sea = sea_state(code);
    c.environment.sea = sea;
    const auto rows = run_voyage(h, c);
    std::vector<double> rw;
    for (const VoyageRow& w : rows) rw.push_back(w.r_wave);
    // THEN the autocorrelation of the wave yaw rate peaks again after one peak period
    // (2 pi / w_d = Tp / sqrt(1 - lambda^2)), an FFT-free estimate of the peak period
    const std::size_t lo = static_cast<std::size_t>(0.5 * sea.tp * c.rate_hz);
    const std::size_t hi = static_cast<std::size_t>(1.5 * sea.tp * c.rate_hz);
    std::size_t best = lo;
    for (std::size_t k = lo; k <= hi; ++k) {
      if (autocorr(rw, k) > autocorr(rw, best)) best = k;
    }
    const double period = static_cast<double>(best) / c.rate_hz;
    EXPECT_NEAR(period, sea.tp, 0.05 * sea.tp) << "sea state " << code;
    // and its std is the one the sea state gives
    double want = 0, sway = 0;
    (void)sway;
    EXPECT_GT(sea.hs, 0);
    const double tp = sea.tp, lw = 9.81 * tp * tp / (2 * M_PI), w0 = 2 * M_PI / tp;
    want = 0.3 * (M_PI * sea.hs / lw) * lw / (lw + h->limits().length) * w0;
    EXPECT_NEAR(std::sqrt(variance(rw)), want, 0.1 * want) << "sea state " << code;
    // and the measured yaw rate carries it
    EXPECT_NEAR(rows[100].r_true, rows[100].r_lf + rows[100].r_wave, 1e-15);
  }
}

TEST(Voyage, HigherSeaStatesMoveTheHullMore) {
  const auto h = hull("otter");
  double last = 0;
  for (const int code : {3, 4, 5}) {
    VoyageConfig c = base(*h, "hold", 600);
    c.environment.sea = sea_state(code);
    const auto rows = run_voyage(h, c);
    std::vector<double> rw;
    for (const VoyageRow& w : rows) rw.push_back(w.r_wave);
    EXPECT_GT(variance(rw), last) << code;
    last = variance(rw);
  }
  EXPECT_THROW(sea_state(2), std::invalid_argument);
}

TEST(Voyage, WindIsASlowlyVaryingSwayForceAndYawMoment) {
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 2000);
  c.environment.wind = 1 * kDeg;
  c.environment.wind_sigma = 0.5 * kDeg;
  const auto rows = run_voyage(h, c);
  std::vector<double> dr, dv;
  for (const VoyageRow& w : rows) {
    dr.push_back(w.dist_r);
    dv.push_back(w.dist_v);
  }
  const Linearisation lin = linearise(*h, h->nominal_speed());
  // the rudder's split of force and moment, gusts of 0.5 deg around 1 deg
  EXPECT_NEAR(dv[500] / dr[500], lin.B(0) / lin.B(1), 1e-9);
  EXPECT_NEAR(mean(dr) / lin.B(1), 1 * kDeg, 0.3 * kDeg);
  EXPECT_NEAR(std::sqrt(variance(dr)) / std::abs(lin.B(1)), 0.5 * kDeg, 0.2 * kDeg);
  // slowly varying: a second apart they are almost the same value
  EXPECT_GT(autocorr(dr, 10), 0.95);
}

TEST(Voyage, ACurrentMovesTheHullOverGroundWithoutTurningIt) {
  // GIVEN a noise-free straight passage in a beam current of 0.5 m/s
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 600);
  sensor_preset("ideal", 0, 0, &c.sensors);
  c.environment.current = 0.5;
  c.environment.current_direction_rw = 0;
  const auto rows = run_voyage(h, c);
  // THEN the INS reads the current in the sway velocity, and the hull needs no rudder
  for (const VoyageRow& w : rows) {
    EXPECT_NEAR(w.v_true, 0.5, 1e-9);
    EXPECT_NEAR(w.v_current, 0.5, 1e-12);
    EXPECT_NEAR(w.delta_true, 0.0, 1e-9);
  }
  // AND in a turning circle the current's body component turns with her
  c = base(*h, "turn", 3000);
  c.environment.current = 0.5;
  const auto turn = run_voyage(h, c);
  double lo = 1, hi = -1;
  for (const VoyageRow& w : turn) {
    lo = std::min(lo, w.v_current);
    hi = std::max(hi, w.v_current);
  }
  EXPECT_LT(lo, -0.4);
  EXPECT_GT(hi, 0.4);
}

// -------------------------------------------------------------------------- sensors

TEST(Voyage, QuantisationStepsAreAsSpecified) {
  // GIVEN ROT in 0.1 deg/min, the rudder in 0.1 deg, v to 3 significant digits
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "zigzag10", 300);
  std::string why;
  ASSERT_TRUE(apply_sensor_setting("rot=nmea", &c.sensors, &why)) << why;
  ASSERT_TRUE(apply_sensor_setting("rudder.step=0.1deg", &c.sensors, &why)) << why;
  ASSERT_TRUE(apply_sensor_setting("acc.digits=3", &c.sensors, &why)) << why;
  const auto rows = run_voyage(h, c);
  std::size_t distinct_r = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const VoyageRow& w = rows[i];
    // THEN every r is a whole number of 0.1 deg/min
    const double rot = w.r / kRotQuantum;
    EXPECT_NEAR(rot, std::round(rot), 1e-6) << w.r;
    const double rud = w.delta / kRudderQuantum;
    EXPECT_NEAR(rud, std::round(rud), 1e-6) << w.delta;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2e", w.v);
    EXPECT_EQ(std::strtod(buf, nullptr), w.v);
    // and within half a step of the unquantised reading
    EXPECT_LE(std::abs(w.delta - w.delta_true), 0.5 * kRudderQuantum + 1e-12);
    if (i > 0 && w.r != rows[i - 1].r) ++distinct_r;
  }
  EXPECT_GT(distinct_r, rows.size() / 4);  // a moving quantised channel still moves
  Quantiser q;
  q.digits = 3;
  EXPECT_EQ(q.apply(0.0123456), 0.0123);
  EXPECT_EQ(q.apply(-987.6), -988.0);
  q = Quantiser{};
  q.step = 0.25;
  EXPECT_EQ(q.apply(0.3), 0.25);
  EXPECT_TRUE(std::isnan(q.apply(kNaN)));
}

TEST(Voyage, GaussMarkovNoiseHasTheConfiguredVarianceAndCorrelationTime) {
  // GIVEN a gyro with GM noise only (sigma 3e-4 rad/s, tau 2 s) at 2 Hz
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 20000, 2.0);
  c.sensors.r = ChannelNoise{};
  c.sensors.r.gm_sigma = 3e-4;
  c.sensors.r.gm_tau = 2.0;
  const auto rows = run_voyage(h, c);
  std::vector<double> e;
  for (const VoyageRow& w : rows) e.push_back(w.r - w.r_true);
  // THEN its variance is sigma^2 and its lag-1 correlation exp(-dt / tau)
  EXPECT_NEAR(std::sqrt(variance(e)), 3e-4, 0.05 * 3e-4);
  const double tau = -0.5 / std::log(autocorr(e, 1));
  EXPECT_NEAR(tau, 2.0, 0.1 * 2.0);
  EXPECT_NEAR(autocorr(e, 4), std::exp(-2.0 / 2.0), 0.05);
}

TEST(Voyage, GyroBiasInstabilityIsARandomWalk) {
  const auto h = hull("mariner-linear");
  VoyageConfig c = base(*h, "hold", 5000, 10.0);
  c.sensors.r.bias_rw = 2e-5;
  const auto rows = run_voyage(h, c);
  std::vector<double> inc;
  for (std::size_t i = 1; i < rows.size(); ++i)
    inc.push_back(rows[i].gyro_bias - rows[i - 1].gyro_bias);
  EXPECT_NEAR(std::sqrt(variance(inc)), 2e-5 * std::sqrt(0.1), 0.03 * 2e-5 * std::sqrt(0.1));
  EXPECT_NEAR(autocorr(inc, 1), 0.0, 0.03);  // independent increments
}

TEST(Voyage, RudderSensorOffsetAndLag) {
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "zigzag10", 200);
  c.sensors.delta = ChannelNoise{};
  c.sensors.delta.bias = 0.5 * kDeg;
  c.sensors.delta.lag = 0.5;
  const auto rows = run_voyage(h, c);
  // THEN the reading follows delta_true through a first-order lag, plus the offset
  double lagged = rows[0].delta_true;
  const double a = -std::expm1(-0.1 / 0.5);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    lagged += (rows[i].delta_true - lagged) * a;
    ASSERT_NEAR(rows[i].delta, lagged + 0.5 * kDeg, 1e-12) << i;
  }
}

TEST(Voyage, DroppedAndDuplicatedSamplesAndJitterAppearAtTheirRates) {
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "course", 4000);
  c.sensors.drop = 0.05;
  c.sensors.duplicate = 0.03;
  c.sensors.jitter = 0.01;
  const auto rows = run_voyage(h, c);
  const double n = 4000 * 10 + 1;
  std::size_t dups = 0, emitted = 0;
  std::vector<double> jit;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].duplicate) {
      ++dups;
      ASSERT_GT(i, 0u);
      EXPECT_EQ(rows[i].t, rows[i - 1].t);
      EXPECT_EQ(rows[i].r, rows[i - 1].r);
      continue;
    }
    ++emitted;
    jit.push_back(rows[i].t - rows[i].t_true);
    EXPECT_LE(std::abs(rows[i].t - rows[i].t_true), 0.045 + 1e-12);
  }
  const double drop = 1.0 - emitted / n, dup = dups / static_cast<double>(emitted);
  EXPECT_NEAR(drop, 0.05, 3 * std::sqrt(0.05 * 0.95 / n));
  EXPECT_NEAR(dup, 0.03, 3 * std::sqrt(0.03 * 0.97 / emitted));
  EXPECT_NEAR(std::sqrt(variance(jit)), 0.01, 0.0005);
  EXPECT_NEAR(mean(jit), 0.0, 0.0003);
}

TEST(Voyage, SensorSettingsAreCheckedWithAClearReason) {
  SensorConfig s;
  std::string why;
  EXPECT_TRUE(apply_sensor_setting("gyro.gm=2.5e-4", &s, &why));
  EXPECT_EQ(s.r.gm_sigma, 2.5e-4);
  EXPECT_TRUE(apply_sensor_setting("rudder.bias=-0.5deg", &s, &why));
  EXPECT_NEAR(s.delta.bias, -0.5 * kDeg, 1e-15);
  EXPECT_FALSE(apply_sensor_setting("gyro.gm=oops", &s, &why));
  EXPECT_NE(why.find("not a number: 'oops'"), std::string::npos) << why;
  EXPECT_FALSE(apply_sensor_setting("compas=1", &s, &why));
  EXPECT_NE(why.find("'compas=1'"), std::string::npos) << why;
  EXPECT_FALSE(apply_sensor_setting("drop=1.5", &s, &why));
  EXPECT_FALSE(apply_sensor_setting("keel.white=1", &s, &why));
  EXPECT_NE(why.find("unknown channel 'keel'"), std::string::npos) << why;
  EXPECT_FALSE(sensor_preset("perfect", 1, 1, &s));
  EXPECT_THROW(scenario_legs("zigzag30", *hull("otter")), std::invalid_argument);
}

// --------------------------------------------------------------------------- faults

TEST(Voyage, StandardFaultsAppearWithTheirMagnitudeAndIntervalDuringManoeuvres) {
  // GIVEN the whole voyage of the Otter with the standard fault set in sigma units, white
  // noise only, so that the sensor error outside faults is the white noise
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "voyage", 2400);
  c.faults = standard_faults(c, 100, 20, 20);
  ASSERT_GE(c.faults.size(), 16u);
  const auto rows = run_voyage(h, c);
  std::vector<Manoeuvre> during;
  for (const FaultInjection& f : c.faults) {
    const bool acc = f.sensor == Sensor::kAccelerometer;
    const double sigma = acc ? 5e-3 : 5e-4;
    std::vector<double> err, truth, val;
    for (const VoyageRow& w : rows) {
      const bool in = w.t_true >= f.t_start && w.t_true < f.t_end;
      const FaultKind label = acc ? w.fault_a : w.fault_g;
      // THEN the fault columns mark exactly the interval
      if (in) {
        ASSERT_EQ(label, f.kind) << w.t_true;
      }
      if (!in) continue;
      during.push_back(w.manoeuvre);
      const double y = acc ? w.v : w.r, x = acc ? w.v_true : w.r_true;
      err.push_back(y - x);
      truth.push_back(x);
      val.push_back(y);
    }
    const std::string what = std::string(to_string(f.sensor)) + " " + to_string(f.kind);
    // and each kind has its magnitude in sigma
    switch (f.kind) {
      case FaultKind::kBias:
        EXPECT_NEAR(mean(err) / sigma, 10.0, 0.5) << what;
        break;
      case FaultKind::kDrift: {
        // the ramp reaches 10 sigma in 30 s: 20/3 sigma at the end of a 20 s interval
        EXPECT_NEAR(err.back() / sigma, 10.0 / 30.0 * (20.0 - 0.1), 3.5) << what;
        EXPECT_NEAR(err[err.size() / 2] / sigma, 10.0 / 30.0 * 10.0, 3.5) << what;
        break;
      }
      case FaultKind::kNoise:
        EXPECT_NEAR(std::sqrt(variance(err)) / sigma, 8.0, 0.8) << what;
        break;
      case FaultKind::kScale: {
        double num = 0, den = 0;
        for (std::size_t i = 0; i < err.size(); ++i) {
          num += (err[i]) * truth[i];
          den += truth[i] * truth[i];
        }
        EXPECT_NEAR(num / den, 0.5, 0.1) << what;
        break;
      }
      case FaultKind::kSpikes: {
        std::size_t spikes = 0;
        for (const double e : err) spikes += std::abs(e) > 15 * sigma;
        EXPECT_NEAR(spikes, 2.0 * 20, 20) << what;  // 2 per second, Poisson
        break;
      }
      case FaultKind::kStuck:
        for (const double y : val) EXPECT_EQ(y, val.front()) << what;
        break;
      case FaultKind::kStale:
        for (const double y : val) EXPECT_TRUE(std::isnan(y)) << what;
        break;
      case FaultKind::kInvalid:
        for (const double y : val) EXPECT_TRUE(std::isinf(y)) << what;
        break;
      case FaultKind::kUnknown:
        ADD_FAILURE();
        break;
    }
  }
  // and outside every interval of a sensor its column is empty
  for (const VoyageRow& w : rows) {
    FaultKind want_a = FaultKind::kUnknown, want_g = FaultKind::kUnknown;
    for (const FaultInjection& f : c.faults) {
      if (w.t_true < f.t_start || w.t_true >= f.t_end) continue;
      (f.sensor == Sensor::kAccelerometer ? want_a : want_g) = f.kind;
    }
    ASSERT_EQ(w.fault_a, want_a) << w.t_true;
    ASSERT_EQ(w.fault_g, want_g) << w.t_true;
  }
  // and the faults fall into zigzags, turns and speed changes, not only straight legs
  for (const Manoeuvre m : {Manoeuvre::kZigzag, Manoeuvre::kTurn, Manoeuvre::kSpeed}) {
    EXPECT_NE(std::find(during.begin(), during.end(), m), during.end()) << to_string(m);
  }
}

TEST(Voyage, FaultMagnitudesFollowTheChannelSigma) {
  VoyageConfig c;
  c.sensors.v.white = 0.01;
  c.sensors.r.white = 0.001;
  EXPECT_DOUBLE_EQ(sigma_fault(c, Sensor::kGyro, FaultKind::kBias, 0, 1, 10).magnitude, 0.01);
  EXPECT_DOUBLE_EQ(sigma_fault(c, Sensor::kAccelerometer, FaultKind::kScale, 0, 1, 0.5).magnitude,
                   0.5);
  c.sigma_v = 0.002;
  EXPECT_DOUBLE_EQ(sigma_fault(c, Sensor::kAccelerometer, FaultKind::kBias, 0, 1, 5).magnitude,
                   0.01);
}

// ------------------------------------------------------------------------- hulls, csv

TEST(LinearHull, AScalesWithSpeedAndBWithItsSquare) {
  const auto h = hull("mariner-linear");
  HullState x;
  x.u = h->nominal_speed();
  x.v = 0.1;
  x.r = 0.01;
  HullInput in;
  in.delta = 0.1;
  const HullRates f1 = h->rates(x, in, Disturbance{});
  HullState x0 = x;
  x0.v = 0;
  x0.r = 0;
  const HullRates b1 = h->rates(x0, in, Disturbance{});
  x.u *= 0.5;
  x0.u *= 0.5;
  const HullRates f2 = h->rates(x, in, Disturbance{});
  const HullRates b2 = h->rates(x0, in, Disturbance{});
  EXPECT_NEAR(b2.dr, 0.25 * b1.dr, 1e-15);
  EXPECT_NEAR(f2.dr - b2.dr, 0.5 * (f1.dr - b1.dr), 1e-15);
  const Linearisation lin = linearise(*h, h->nominal_speed());
  EXPECT_NEAR(lin.A(1, 1), -0.100362, 1e-9);
  EXPECT_NEAR(lin.B(1), -3.74282e-3, 1e-12);
  EXPECT_EQ(voyage_hull("titanic"), nullptr);
}

TEST(VoyageCsv, KeepsTheSimRowColumnsFirstAndTheSurgeSpeedAsU) {
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "hold", 1);
  const auto rows = run_voyage(h, c);
  std::ostringstream os;
  VoyageCsvWriter w(os);
  for (const VoyageRow& r : rows) w.write(r);
  std::istringstream is(os.str());
  std::string header, first;
  std::getline(is, header);
  std::getline(is, first);
  EXPECT_EQ(header.rfind("t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g,u,", 0),
            0u);
  std::vector<std::string> f;
  std::stringstream ss(first);
  for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
  EXPECT_EQ(std::strtod(f[11].c_str(), nullptr), rows[0].u_true);
  EXPECT_EQ(f[24], "hold");
}

TEST(VoyageCsv, AChannelOfThreeSignificantDigitsIsPrintedWithThem) {
  const auto h = hull("otter");
  VoyageConfig c = base(*h, "course", 20);
  c.sensors.v.quantiser.digits = 3;
  const auto rows = run_voyage(h, c);
  std::ostringstream os;
  VoyageCsvWriter w(os, c.sensors);
  for (const VoyageRow& r : rows) w.write(r);
  std::istringstream is(os.str());
  std::string line;
  std::getline(is, line);
  for (std::size_t i = 0; std::getline(is, line); ++i) {
    const std::string v =
        line.substr(line.find(',') + 1, line.find(',', line.find(',') + 1) - line.find(',') - 1);
    std::size_t digits = 0;
    bool leading = true;
    for (const char ch : v) {
      if (ch == 'e') break;
      if (ch < '0' || ch > '9') continue;
      if (ch != '0') leading = false;
      if (!leading) ++digits;
    }
    EXPECT_LE(digits, 3u) << v;
    EXPECT_EQ(std::strtod(v.c_str(), nullptr), rows[i].v) << v;  // the same double back
  }
}

}  // namespace
}  // namespace usvfdi::sim
