// The vessel simulator (include/usv_fdi/core/simulator.hpp): determinism per seed, the
// heading autopilot on a course-unstable vessel, rudder saturation and rate limit, noise
// statistics, the documented shape of every injected fault kind inside (and only inside)
// its window, and the paper's scenario.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"

namespace usvfdi {
namespace {

constexpr double kDeg = M_PI / 180.0;

bool same_double(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || a == b;  // bit-level enough for our values
}

bool same_row(const SimRow& a, const SimRow& b) {
  return same_double(a.t, b.t) && same_double(a.v, b.v) && same_double(a.r, b.r) &&
         same_double(a.delta, b.delta) && a.v_true == b.v_true && a.r_true == b.r_true &&
         a.delta_true == b.delta_true && a.psi == b.psi && a.psi_ref == b.psi_ref &&
         a.fault_a == b.fault_a && a.fault_g == b.fault_g;
}

struct Stats {
  double mean = 0.0, std = 0.0, lag1 = 0.0;
  std::size_t n = 0;
};

Stats stats(const std::vector<double>& x) {
  Stats s;
  s.n = x.size();
  for (double v : x) s.mean += v;
  s.mean /= static_cast<double>(x.size());
  double ss = 0.0, c1 = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    ss += (x[i] - s.mean) * (x[i] - s.mean);
    if (i > 0) c1 += (x[i] - s.mean) * (x[i - 1] - s.mean);
  }
  s.std = std::sqrt(ss / static_cast<double>(x.size() - 1));
  s.lag1 = c1 / ss;
  return s;
}

/// The Mariner with a positive a4: course-unstable (det A < 0, one eigenvalue > 0).
VesselModel unstable_mariner() {
  VesselModel m = mariner();
  m.name = "unstable mariner";
  m.A(1, 1) = +0.02;
  return m;
}

double channel(const SimRow& row, Sensor s) { return s == Sensor::kAccelerometer ? row.v : row.r; }
double channel_true(const SimRow& row, Sensor s) {
  return s == Sensor::kAccelerometer ? row.v_true : row.r_true;
}
FaultKind flag(const SimRow& row, Sensor s) {
  return s == Sensor::kAccelerometer ? row.fault_a : row.fault_g;
}
Sensor other(Sensor s) {
  return s == Sensor::kAccelerometer ? Sensor::kGyro : Sensor::kAccelerometer;
}

// ---------------------------------------------------------------------------------------
// Timing, determinism, configuration

TEST(Simulator, SamplesAreEquallySpacedOverTheWholeDuration) {
  SimConfig c;
  c.vessel = otter();
  c.rate_hz = 20.0;
  c.duration = 30.0;
  const auto rows = simulate(c);
  ASSERT_EQ(rows.size(), 601u);  // t = 0, 0.05, ..., 30 inclusive
  for (std::size_t k = 0; k < rows.size(); ++k) {
    ASSERT_NEAR(rows[k].t, static_cast<double>(k) / 20.0, 1e-12) << k;
  }
  // AND the step-wise interface gives the same rows and then stops
  Simulator sim(c);
  SimRow row;
  for (const SimRow& want : rows) {
    ASSERT_TRUE(sim.next(&row));
    ASSERT_TRUE(same_row(row, want)) << row.t;
  }
  EXPECT_FALSE(sim.next(&row));
  EXPECT_FALSE(sim.next(&row));
}

TEST(Simulator, SameSeedSameDataDifferentSeedDifferentNoise) {
  // GIVEN a configuration with every random element: sensor noise, rudder noise, waves,
  //   a noise fault and a spikes fault
  for (const Steering steering : {Steering::kAutopilot, Steering::kSine}) {
    SimConfig c;
    c.vessel = otter();
    c.rate_hz = 50.0;
    c.duration = 60.0;
    c.seed = 12345;
    c.sigma_delta = 1e-3;
    c.disturbance = 1e-3;
    c.steering = steering;
    c.faults = {{Sensor::kGyro, FaultKind::kNoise, 10.0, 20.0, 5e-3, 2.0},
                {Sensor::kAccelerometer, FaultKind::kSpikes, 15.0, 40.0, 0.2, 3.0}};
    // WHEN it runs twice with one seed and once with another
    const auto a = simulate(c), b = simulate(c);
    c.seed = 12346;
    const auto d = simulate(c);
    // THEN the same seed reproduces every value bit for bit
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) ASSERT_TRUE(same_row(a[k], b[k])) << a[k].t;
    // AND another seed gives other noise on every channel
    ASSERT_EQ(a.size(), d.size());
    std::size_t differ_v = 0, differ_r = 0, differ_d = 0;
    for (std::size_t k = 1; k < a.size(); ++k) {
      differ_v += a[k].v != d[k].v;
      differ_r += a[k].r != d[k].r;
      differ_d += a[k].delta != d[k].delta;
    }
    EXPECT_GT(differ_v, a.size() * 9 / 10);
    EXPECT_GT(differ_r, a.size() * 9 / 10);
    EXPECT_GT(differ_d, a.size() * 9 / 10);
  }
}

TEST(Simulator, RefusesBadConfigurationsWithAReason) {
  const auto expect_refused = [](SimConfig c, const std::string& what) {
    try {
      Simulator sim(c);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("sim: ", 0), 0u) << e.what();
    }
  };
  SimConfig ok;
  ok.vessel = otter();
  EXPECT_NO_THROW(Simulator{ok});
  SimConfig c = ok;
  c.rate_hz = 0.0;
  expect_refused(c, "rate_hz");
  c = ok;
  c.rate_hz = std::numeric_limits<double>::quiet_NaN();
  expect_refused(c, "rate_hz");
  c = ok;
  c.duration = -1.0;
  expect_refused(c, "duration");
  c = ok;
  c.substeps = 0;
  expect_refused(c, "substeps");
  c = ok;
  c.vessel.B(1) = 0.0;
  expect_refused(c, "b2");
  c = ok;
  c.vessel.A(0, 1) = std::numeric_limits<double>::infinity();
  expect_refused(c, "finite A");
  c = ok;
  c.vessel.max_rudder_rate = 0.0;
  expect_refused(c, "rudder limits");
  c = ok;
  c.faults = {{Sensor::kUnknown, FaultKind::kBias, 1.0, 2.0, 1.0, 2.0}};
  expect_refused(c, "accelerometer or the gyro");
  c = ok;
  c.faults = {{Sensor::kGyro, FaultKind::kBias, 2.0, 2.0, 1.0, 2.0}};
  expect_refused(c, "end after it starts");
}

// ---------------------------------------------------------------------------------------
// Autopilot, rudder

/// Heading at the last sample of every course leg (after the first) minus that leg's target.
std::vector<double> end_of_leg_errors(const std::vector<SimRow>& rows, const VesselModel& m,
                                      double rate_hz) {
  std::vector<double> err;
  const auto per_leg = static_cast<std::size_t>(std::lround(m.turn_period * rate_hz));
  for (std::size_t k = 2 * per_leg; k < rows.size(); k += per_leg) {
    // rows[k] is the first sample of a new leg; rows[k - 1] the last of the previous one
    const int leg = static_cast<int>(k / per_leg) - 1;
    const double target = leg % 2 == 0 ? m.turn_angle : -m.turn_angle;
    err.push_back(rows[k - 1].psi - target);
  }
  return err;
}

TEST(Simulator, AutopilotKeepsACourseUnstableVesselBounded) {
  // GIVEN a course-unstable vessel (an eigenvalue of A in the right half-plane)
  const VesselModel m = unstable_mariner();
  const Eigen::Vector2cd ev = m.A.eigenvalues();
  ASSERT_GT(std::max(ev(0).real(), ev(1).real()), 0.04);
  SimConfig c;
  c.vessel = m;
  c.rate_hz = 10.0;
  c.duration = 1800.0;
  c.seed = 3;
  // WHEN it sails half an hour of alternating +-20 deg course changes under the autopilot
  c.steering = Steering::kAutopilot;
  const auto rows = simulate(c);
  // THEN its states stay bounded
  double max_v = 0.0, max_r = 0.0, max_psi = 0.0;
  for (const SimRow& row : rows) {
    ASSERT_TRUE(std::isfinite(row.v_true) && std::isfinite(row.r_true) && std::isfinite(row.psi));
    max_v = std::max(max_v, std::abs(row.v_true));
    max_r = std::max(max_r, std::abs(row.r_true));
    max_psi = std::max(max_psi, std::abs(row.psi));
  }
  EXPECT_LT(max_v, 0.5);         // [m/s]
  EXPECT_LT(max_r, 1.0 * kDeg);  // [rad/s]
  EXPECT_LT(max_psi, 1.2 * m.turn_angle);
  EXPECT_GT(max_r, 0.1 * kDeg);  // it did turn
  // AND the heading follows the course: at the end of every 120 s leg it is within a quarter
  //   of the turn of the leg's target (a slow 0.06 rad/s loop on a large ship)
  const auto err = end_of_leg_errors(rows, m, c.rate_hz);
  ASSERT_GE(err.size(), 13u);
  for (double e : err) EXPECT_LT(std::abs(e), 0.25 * m.turn_angle);
  // AND the same vessel in open loop (the sine rudder) diverges: the autopilot is what
  //   keeps it bounded
  c.steering = Steering::kSine;
  c.duration = 1200.0;
  const auto open = simulate(c);
  EXPECT_GT(std::abs(open.back().r_true), 100.0 * max_r);
}

TEST(Simulator, AutopilotFollowsTheCourseOnTheShippedVessels) {
  for (const VesselModel& m : shipped_vessels()) {
    SCOPED_TRACE(m.name);
    SimConfig c;
    c.vessel = m;
    c.rate_hz = 10.0;
    c.duration = 8.0 * m.turn_period;
    const auto rows = simulate(c);
    const auto err = end_of_leg_errors(rows, m, c.rate_hz);
    ASSERT_EQ(err.size(), 7u);
    for (double e : err) EXPECT_LT(std::abs(e), 0.25 * m.turn_angle);
    // the reference filter moves psi_ref to the target, the loop psi to psi_ref
    for (const SimRow& row : rows) ASSERT_LE(std::abs(row.psi_ref), m.turn_angle * (1 + 1e-12));
  }
  // the fast Otter settles within half a degree
  const VesselModel& o = otter();
  SimConfig c;
  c.vessel = o;
  c.rate_hz = 10.0;
  c.duration = 8.0 * o.turn_period;
  for (double e : end_of_leg_errors(simulate(c), o, c.rate_hz)) EXPECT_LT(std::abs(e), 0.5 * kDeg);
}

TEST(Simulator, RudderRespectsSaturationAndRateLimit) {
  for (const VesselModel& base : shipped_vessels()) {
    for (const Steering steering : {Steering::kAutopilot, Steering::kSine}) {
      SCOPED_TRACE(base.name + (steering == Steering::kSine ? " sine" : " autopilot"));
      // GIVEN commands far beyond the rudder's limits: a 90 deg course change, or a sine
      //   of four times the maximum rudder
      VesselModel m = base;
      m.turn_angle = 90.0 * kDeg;
      m.autopilot_bandwidth *= 4.0;
      SimConfig c;
      c.vessel = m;
      c.rate_hz = 50.0;
      c.duration = 4.0 * m.turn_period;
      c.steering = steering;
      c.sine_amplitude = 4.0 * m.max_rudder;
      const auto rows = simulate(c);
      // THEN the rudder never exceeds its saturation nor its rate limit
      const double h = 1.0 / c.rate_hz;
      double max_abs = 0.0, max_rate = 0.0;
      for (std::size_t k = 0; k < rows.size(); ++k) {
        max_abs = std::max(max_abs, std::abs(rows[k].delta_true));
        if (k > 0) {
          max_rate = std::max(max_rate, std::abs(rows[k].delta_true - rows[k - 1].delta_true) / h);
        }
        // AND with no rudder noise the measured rudder is the true one
        ASSERT_EQ(rows[k].delta, rows[k].delta_true);
      }
      EXPECT_LE(max_abs, m.max_rudder * (1 + 1e-12));
      EXPECT_LE(max_rate, m.max_rudder_rate * (1 + 1e-9));
      // AND both limits are actually reached (the test exercises them)
      EXPECT_GT(max_abs, 0.99 * m.max_rudder);
      EXPECT_GT(max_rate, 0.99 * m.max_rudder_rate);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Noise

TEST(Simulator, MeasurementNoiseHasTheConfiguredStatistics) {
  for (const VesselModel& m : shipped_vessels()) {
    SCOPED_TRACE(m.name);
    SimConfig c;
    c.vessel = m;
    c.rate_hz = 50.0;
    c.duration = 1000.0;  // 50 001 samples: the std is known to ~0.3 %
    c.seed = 77;
    c.sigma_delta = 2e-3;
    // GIVEN the vessel's realistic noise (sigma_v, sigma_r < 0: the vessel's values)
    const auto rows = simulate(c);
    std::vector<double> nv, nr, nd;
    for (const SimRow& row : rows) {
      nv.push_back(row.v - row.v_true);
      nr.push_back(row.r - row.r_true);
      nd.push_back(row.delta - row.delta_true);
    }
    // THEN each channel's noise has zero mean, the configured std and is white
    const struct {
      const std::vector<double>* x;
      double sigma;
      const char* name;
    } chans[] = {{&nv, m.sigma_v, "v"}, {&nr, m.sigma_r, "r"}, {&nd, 2e-3, "delta"}};
    for (const auto& ch : chans) {
      const Stats s = stats(*ch.x);
      const double se = ch.sigma / std::sqrt(static_cast<double>(s.n));
      EXPECT_LT(std::abs(s.mean), 5.0 * se) << ch.name;
      EXPECT_NEAR(s.std / ch.sigma, 1.0, 0.015) << ch.name;
      EXPECT_LT(std::abs(s.lag1), 5.0 / std::sqrt(static_cast<double>(s.n))) << ch.name;
    }
    // AND the channels are uncorrelated
    double cvr = 0.0;
    for (std::size_t k = 0; k < nv.size(); ++k) cvr += nv[k] * nr[k];
    cvr /= static_cast<double>(nv.size()) * m.sigma_v * m.sigma_r;
    EXPECT_LT(std::abs(cvr), 5.0 / std::sqrt(static_cast<double>(nv.size())));
    // AND an explicit sigma overrides the vessel's
    c.sigma_v = 3.0 * m.sigma_v;
    c.sigma_r = 0.0;
    c.duration = 200.0;
    std::vector<double> nv3;
    for (const SimRow& row : simulate(c)) {
      nv3.push_back(row.v - row.v_true);
      ASSERT_EQ(row.r, row.r_true) << "sigma_r = 0 is noise-free";
    }
    EXPECT_NEAR(stats(nv3).std / (3.0 * m.sigma_v), 1.0, 0.03);
  }
}

TEST(Simulator, NoiseFreeIsExact) {
  SimConfig c;
  c.vessel = otter();
  c.sigma_v = 0.0;
  c.sigma_r = 0.0;
  c.duration = 50.0;
  for (const SimRow& row : simulate(c)) {
    ASSERT_EQ(row.v, row.v_true);
    ASSERT_EQ(row.r, row.r_true);
    ASSERT_EQ(row.delta, row.delta_true);
    ASSERT_EQ(row.fault_a, FaultKind::kUnknown);
    ASSERT_EQ(row.fault_g, FaultKind::kUnknown);
  }
}

TEST(Simulator, WaveDisturbanceWithNoiseFreeSensorsStaysFinite) {
  // The yaw-rate disturbance is scaled by the vessel's realistic noise ratio, never by the
  // configured sensor noise (which may be zero).
  SimConfig c;
  c.vessel = otter();
  c.sigma_v = 0.0;
  c.sigma_r = 0.0;
  c.disturbance = 1e-3;
  c.duration = 10.0;
  for (const SimRow& row : simulate(c)) {
    ASSERT_TRUE(std::isfinite(row.v_true) && std::isfinite(row.r_true)) << row.t;
  }
}

// ---------------------------------------------------------------------------------------
// Faults

struct FaultRun {
  std::vector<SimRow> healthy, faulty;
  FaultInjection f;
};

/// The same voyage with and without one injected fault (same seed).
FaultRun run_fault(Sensor sensor, FaultKind kind, double magnitude, double noise_scale = 1.0,
                   double duration = 60.0, double t0 = 20.0, double t1 = 40.0) {
  FaultRun out;
  SimConfig c;
  c.vessel = otter();
  c.rate_hz = 50.0;
  c.duration = duration;
  c.seed = 99;
  c.sigma_v = noise_scale * c.vessel.sigma_v;
  c.sigma_r = noise_scale * c.vessel.sigma_r;
  out.healthy = simulate(c);
  out.f.sensor = sensor;
  out.f.kind = kind;
  out.f.t_start = t0;
  out.f.t_end = t1;
  out.f.magnitude = magnitude;
  out.f.spike_rate = 2.0;
  c.faults = {out.f};
  out.faulty = simulate(c);
  return out;
}

bool inside(const FaultInjection& f, double t) { return t >= f.t_start && t < f.t_end; }

/// Checks what every fault shares: the plant and the other channel are untouched, the flag
/// marks the window exactly, and (for faults that draw no random numbers) the faulty
/// channel equals the healthy run outside the window.
void expect_confined(const FaultRun& run, bool draws_random) {
  const FaultInjection& f = run.f;
  ASSERT_EQ(run.healthy.size(), run.faulty.size());
  std::size_t in = 0;
  for (std::size_t k = 0; k < run.faulty.size(); ++k) {
    const SimRow& h = run.healthy[k];
    const SimRow& y = run.faulty[k];
    // the vessel itself never sees a sensor fault
    ASSERT_EQ(y.v_true, h.v_true);
    ASSERT_EQ(y.r_true, h.r_true);
    ASSERT_EQ(y.delta_true, h.delta_true);
    ASSERT_EQ(y.psi, h.psi);
    ASSERT_EQ(flag(y, f.sensor), inside(f, y.t) ? f.kind : FaultKind::kUnknown) << y.t;
    ASSERT_EQ(flag(y, other(f.sensor)), FaultKind::kUnknown) << y.t;
    if (inside(f, y.t)) ++in;
    if (!draws_random) {
      ASSERT_EQ(channel(y, other(f.sensor)), channel(h, other(f.sensor))) << y.t;
      ASSERT_EQ(y.delta, h.delta);
      if (!inside(f, y.t)) {
        ASSERT_EQ(channel(y, f.sensor), channel(h, f.sensor)) << y.t;
      }
    } else if (y.t < f.t_start) {
      ASSERT_TRUE(same_row(y, h)) << y.t;
    }
  }
  // the window is [t_start, t_end): the sample at t_start is faulty, the one at t_end not
  EXPECT_EQ(in, static_cast<std::size_t>(std::lround((f.t_end - f.t_start) * 50.0)));
}

class FaultShape : public ::testing::TestWithParam<Sensor> {
 protected:
  double sigma() const {
    return GetParam() == Sensor::kAccelerometer ? otter().sigma_v : otter().sigma_r;
  }
};

TEST_P(FaultShape, BiasAddsItsOffset) {
  const double m = 10.0 * sigma();
  const FaultRun run = run_fault(GetParam(), FaultKind::kBias, m);
  expect_confined(run, false);
  for (std::size_t k = 0; k < run.faulty.size(); ++k) {
    const double d = channel(run.faulty[k], GetParam()) - channel(run.healthy[k], GetParam());
    if (inside(run.f, run.faulty[k].t)) {
      ASSERT_NEAR(d, m, 1e-15) << run.faulty[k].t;
    }
  }
}

TEST_P(FaultShape, DriftGrowsAtItsRateFromTheStart) {
  const double rate = 0.5 * sigma();  // [unit/s]
  const FaultRun run = run_fault(GetParam(), FaultKind::kDrift, rate);
  expect_confined(run, false);
  double last = 0.0;
  for (std::size_t k = 0; k < run.faulty.size(); ++k) {
    const double t = run.faulty[k].t;
    if (!inside(run.f, t)) continue;
    const double d = channel(run.faulty[k], GetParam()) - channel(run.healthy[k], GetParam());
    ASSERT_NEAR(d, rate * (t - run.f.t_start), 1e-15) << t;
    last = d;
  }
  EXPECT_NEAR(last, rate * (run.f.t_end - run.f.t_start - 0.02), 1e-12);
}

TEST_P(FaultShape, StuckHoldsTheValueOfTheFirstFaultySample) {
  const FaultRun run = run_fault(GetParam(), FaultKind::kStuck, 0.0);
  expect_confined(run, false);
  double held = std::numeric_limits<double>::quiet_NaN();
  std::size_t n = 0;
  for (std::size_t k = 0; k < run.faulty.size(); ++k) {
    if (!inside(run.f, run.faulty[k].t)) continue;
    if (std::isnan(held)) held = channel(run.healthy[k], GetParam());  // the noisy value at t0
    ASSERT_EQ(channel(run.faulty[k], GetParam()), held) << run.faulty[k].t;
    ++n;
  }
  EXPECT_EQ(n, 1000u);
  // AND a second stuck window later holds a new value, not the old one
  SimConfig c;
  c.vessel = otter();
  c.duration = 60.0;
  c.seed = 99;
  c.faults = {{GetParam(), FaultKind::kStuck, 10.0, 20.0, 0.0, 2.0},
              {GetParam(), FaultKind::kStuck, 30.0, 40.0, 0.0, 2.0}};
  const auto rows = simulate(c);
  const double first = channel(rows[500], GetParam()), second = channel(rows[1500], GetParam());
  EXPECT_EQ(channel(rows[999], GetParam()), first);
  EXPECT_EQ(channel(rows[1999], GetParam()), second);
  EXPECT_NE(first, second);
}

TEST_P(FaultShape, NoiseAddsItsStd) {
  // noise-free sensors, so the measured channel minus truth is the injected noise alone
  const double m = 6.0 * sigma();
  const FaultRun run = run_fault(GetParam(), FaultKind::kNoise, m, 0.0, 500.0, 50.0, 450.0);
  expect_confined(run, true);
  std::vector<double> e;
  for (const SimRow& row : run.faulty) {
    const double d = channel(row, GetParam()) - channel_true(row, GetParam());
    if (inside(run.f, row.t)) {
      e.push_back(d);
    } else {
      ASSERT_EQ(d, 0.0) << row.t;
    }
  }
  ASSERT_EQ(e.size(), 20000u);
  const Stats s = stats(e);
  EXPECT_NEAR(s.std / m, 1.0, 0.02);
  EXPECT_LT(std::abs(s.mean), 5.0 * m / std::sqrt(20000.0));
  EXPECT_LT(std::abs(s.lag1), 5.0 / std::sqrt(20000.0));
  // AND on top of the sensor noise the stds add in quadrature
  const FaultRun noisy = run_fault(GetParam(), FaultKind::kNoise, m, 1.0, 500.0, 50.0, 450.0);
  std::vector<double> e2;
  for (const SimRow& row : noisy.faulty) {
    if (inside(noisy.f, row.t))
      e2.push_back(channel(row, GetParam()) - channel_true(row, GetParam()));
  }
  EXPECT_NEAR(stats(e2).std / std::hypot(m, sigma()), 1.0, 0.02);
}

TEST_P(FaultShape, SpikesComeAtTheirRateWithTheirAmplitude) {
  const double m = 25.0 * sigma();
  const FaultRun run = run_fault(GetParam(), FaultKind::kSpikes, m, 0.0, 500.0, 50.0, 450.0);
  expect_confined(run, true);
  int up = 0, down = 0;
  for (const SimRow& row : run.faulty) {
    const double d = channel(row, GetParam()) - channel_true(row, GetParam());
    if (!inside(run.f, row.t)) {
      ASSERT_EQ(d, 0.0) << row.t;
      continue;
    }
    // every faulty sample is either untouched or off by exactly +-amplitude
    if (d == 0.0) continue;
    ASSERT_NEAR(std::abs(d), m, 1e-15) << row.t;
    (d > 0 ? up : down) += 1;
  }
  // 400 s at 2 spikes/s: binomial(20000, 0.04), mean 800, std ~28
  const int n = up + down;
  EXPECT_NEAR(n, 800, 4 * 28);
  // symmetric signs: binomial(n, 1/2)
  EXPECT_NEAR(up - down, 0, 4 * std::sqrt(static_cast<double>(n)));
}

TEST_P(FaultShape, ScaleMultipliesTheTruthByOnePlusItsGain) {
  const double gain = 0.5;
  const FaultRun run = run_fault(GetParam(), FaultKind::kScale, gain);
  expect_confined(run, false);
  double max_effect = 0.0;
  for (std::size_t k = 0; k < run.faulty.size(); ++k) {
    const SimRow& y = run.faulty[k];
    if (!inside(run.f, y.t)) continue;
    const double d = channel(y, GetParam()) - channel(run.healthy[k], GetParam());
    ASSERT_NEAR(d, gain * channel_true(y, GetParam()), 1e-15) << y.t;
    max_effect = std::max(max_effect, std::abs(d));
  }
  EXPECT_GT(max_effect, 0.0);  // the vessel was moving
  // noise-free: the measurement is exactly (1 + gain) x truth
  const FaultRun clean = run_fault(GetParam(), FaultKind::kScale, gain, 0.0);
  for (const SimRow& y : clean.faulty) {
    if (inside(clean.f, y.t)) {
      ASSERT_NEAR(channel(y, GetParam()), 1.5 * channel_true(y, GetParam()),
                  1e-15 + 1e-15 * std::abs(channel_true(y, GetParam())));
    }
  }
}

TEST_P(FaultShape, StaleIsNaNAndInvalidIsInfinity) {
  const FaultRun stale = run_fault(GetParam(), FaultKind::kStale, 0.0);
  expect_confined(stale, false);
  const FaultRun invalid = run_fault(GetParam(), FaultKind::kInvalid, 0.0);
  expect_confined(invalid, false);
  for (std::size_t k = 0; k < stale.faulty.size(); ++k) {
    const double t = stale.faulty[k].t;
    const double s = channel(stale.faulty[k], GetParam());
    const double i = channel(invalid.faulty[k], GetParam());
    if (inside(stale.f, t)) {
      ASSERT_TRUE(std::isnan(s)) << t;
      ASSERT_TRUE(std::isinf(i) && i > 0) << t;
    } else {
      ASSERT_TRUE(std::isfinite(s) && std::isfinite(i)) << t;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BothSensors, FaultShape,
                         ::testing::Values(Sensor::kAccelerometer, Sensor::kGyro),
                         [](const ::testing::TestParamInfo<Sensor>& info) {
                           return std::string(info.param == Sensor::kGyro ? "Gyro"
                                                                          : "Accelerometer");
                         });

TEST(Simulator, FaultsOnBothSensorsAtOnceAreIndependent) {
  // GIVEN a gyro bias and an accelerometer drift overlapping in time
  SimConfig c;
  c.vessel = mariner();
  c.rate_hz = 10.0;
  c.duration = 100.0;
  c.seed = 5;
  const auto healthy = simulate(c);
  c.faults = {{Sensor::kGyro, FaultKind::kBias, 20.0, 60.0, 1e-3, 2.0},
              {Sensor::kAccelerometer, FaultKind::kDrift, 40.0, 80.0, 1e-3, 2.0}};
  const auto rows = simulate(c);
  // THEN each channel carries its own fault in its own window only
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double t = rows[k].t;
    const bool g = t >= 20.0 && t < 60.0, a = t >= 40.0 && t < 80.0;
    ASSERT_EQ(rows[k].fault_g, g ? FaultKind::kBias : FaultKind::kUnknown) << t;
    ASSERT_EQ(rows[k].fault_a, a ? FaultKind::kDrift : FaultKind::kUnknown) << t;
    ASSERT_NEAR(rows[k].r - healthy[k].r, g ? 1e-3 : 0.0, 1e-15) << t;
    ASSERT_NEAR(rows[k].v - healthy[k].v, a ? 1e-3 * (t - 40.0) : 0.0, 1e-15) << t;
  }
}

// ---------------------------------------------------------------------------------------
// The paper's scenario

TEST(Simulator, PaperScenarioHasThePapersTimings) {
  for (const VesselModel& m : shipped_vessels()) {
    SCOPED_TRACE(m.name);
    // GIVEN the paper's scenario at 50 Hz
    const SimConfig c = paper_scenario(m, 50.0, 7);
    // THEN it lasts 100 s, uses the sine rudder, keeps rate and seed
    EXPECT_EQ(c.duration, 100.0);
    EXPECT_EQ(c.rate_hz, 50.0);
    EXPECT_EQ(c.seed, 7u);
    EXPECT_EQ(c.steering, Steering::kSine);
    // AND has a gyro fault on [20, 40) s and an accelerometer fault on [60, 80) s, 10 sigma
    ASSERT_EQ(c.faults.size(), 2u);
    EXPECT_EQ(c.faults[0].sensor, Sensor::kGyro);
    EXPECT_EQ(c.faults[0].kind, FaultKind::kBias);
    EXPECT_EQ(c.faults[0].t_start, 20.0);
    EXPECT_EQ(c.faults[0].t_end, 40.0);
    EXPECT_EQ(c.faults[0].magnitude, 10.0 * m.sigma_r);
    EXPECT_EQ(c.faults[1].sensor, Sensor::kAccelerometer);
    EXPECT_EQ(c.faults[1].kind, FaultKind::kBias);
    EXPECT_EQ(c.faults[1].t_start, 60.0);
    EXPECT_EQ(c.faults[1].t_end, 80.0);
    EXPECT_EQ(c.faults[1].magnitude, 10.0 * m.sigma_v);
    // AND the simulated rows carry the faults exactly there
    const auto rows = simulate(c);
    ASSERT_EQ(rows.size(), 5001u);
    int g = 0, a = 0;
    for (const SimRow& row : rows) {
      const bool want_g = row.t >= 20.0 && row.t < 40.0, want_a = row.t >= 60.0 && row.t < 80.0;
      ASSERT_EQ(row.fault_g, want_g ? FaultKind::kBias : FaultKind::kUnknown) << row.t;
      ASSERT_EQ(row.fault_a, want_a ? FaultKind::kBias : FaultKind::kUnknown) << row.t;
      g += want_g;
      a += want_a;
    }
    EXPECT_EQ(g, 1000);
    EXPECT_EQ(a, 1000);
  }
}

TEST(Simulator, SineSteeringExcitesWithTheVesselsAmplitude) {
  // The open-loop identification input: a sum of two sines, amplitude 1.5 x the vessel's
  // sine_amplitude at most, through the servo.
  for (const VesselModel& m : shipped_vessels()) {
    SCOPED_TRACE(m.name);
    SimConfig c = paper_scenario(m, 50.0, 1);
    c.faults.clear();
    double max_abs = 0.0;
    for (const SimRow& row : simulate(c)) max_abs = std::max(max_abs, std::abs(row.delta_true));
    EXPECT_LE(max_abs, 1.5 * m.sine_amplitude + 1e-12);
    EXPECT_GT(max_abs, 0.5 * m.sine_amplitude);
  }
}

TEST(Simulator, AutopilotOnTheMeasuredStateSteersOnTheSensorNoise) {
  // GIVEN the Otter under its autopilot, steering on the true state (default) or on the
  // measured v, r and the heading integrated from the measured r
  const VesselModel m = shipped_vessels().front();
  SimConfig c;
  c.vessel = m;
  c.rate_hz = 10.0;
  c.duration = 200.0;
  c.seed = 3;
  SimConfig meas = c;
  meas.autopilot_on_measurement = true;
  const auto truth = simulate(c), measured = simulate(meas);
  ASSERT_EQ(truth.size(), measured.size());
  // THEN the measured-state autopilot moves the rudder differently (it sees the noise), but
  //   still holds the course (heading within the turn angle of its reference)
  double diff = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    diff = std::max(diff, std::abs(truth[i].delta_true - measured[i].delta_true));
    worst = std::max(worst, std::abs(measured[i].psi - measured[i].psi_ref));
  }
  EXPECT_GT(diff, 1e-4);
  EXPECT_LT(worst, std::abs(m.turn_angle));
  // AND with noise-free sensors both autopilots see the same state: the same voyage (the
  //   integrated heading differs from the true one by the trapezoid's O(h^2) error only)
  c.sigma_v = c.sigma_r = meas.sigma_v = meas.sigma_r = 0.0;
  const auto a = simulate(c), b = simulate(meas);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(a[i].delta_true, b[i].delta_true, 1e-3 * m.max_rudder) << a[i].t;
  }
}

}  // namespace
}  // namespace usvfdi
