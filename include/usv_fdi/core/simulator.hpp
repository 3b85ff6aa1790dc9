// Vessel simulator: Nomoto sway-yaw model with a heading autopilot (so that course-unstable
// vessels stay bounded), rudder saturation, rate limit and servo lag, sensor noise and
// scripted INS faults of every kind of docs/design.md section 4.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "usv_fdi/core/types.hpp"
#include "usv_fdi/core/vessel.hpp"

namespace usvfdi {

struct FaultInjection {
  Sensor sensor = Sensor::kGyro;  ///< accelerometer (v channel) or gyro (r channel)
  FaultKind kind = FaultKind::kBias;
  double t_start = 0.0;  ///< [s]
  double t_end = 0.0;    ///< [s], exclusive
  /// bias: offset [channel unit]; drift: rate [unit/s]; noise: extra std [unit];
  /// spikes: amplitude [unit]; scale: relative gain error (0.5 = +50 %);
  /// stuck, stale (missing value), invalid (+Inf): unused.
  double magnitude = 0.0;
  double spike_rate = 2.0;  ///< spikes per second (spikes only)
};

enum class Steering : std::uint8_t {
  kAutopilot = 0,  ///< heading autopilot following alternating course changes
  kSine,           ///< open-loop sinusoidal rudder (identification experiments)
};

struct SimConfig {
  VesselModel vessel;
  double rate_hz = 50.0;
  double duration = 100.0;  ///< [s]
  std::uint64_t seed = 1;
  double sigma_v = -1;       ///< measurement noise [m/s]; < 0: the vessel's realistic value
  double sigma_r = -1;       ///< [rad/s]; < 0: the vessel's realistic value
  double sigma_delta = 0.0;  ///< rudder measurement noise [rad]
  /// White process noise (waves): std on v' [m/s^2/sqrt(s)]; on r' the same times the
  /// vessel's realistic sigma_r / sigma_v [rad/s^2/sqrt(s)], whatever the sensor noise.
  double disturbance = 0.0;
  Steering steering = Steering::kAutopilot;
  double sine_amplitude = -1;  ///< [rad]; < 0: the vessel's
  double sine_frequency = -1;  ///< [rad/s]; < 0: the vessel's
  /// The autopilot steers on the MEASURED state (v and r as the INS gives them, heading
  /// integrated from the measured r, as an autopilot with a gyro-based heading does), so
  /// the rudder carries a filtered trace of the sensor noise; false: on the true state.
  bool autopilot_on_measurement = false;
  int substeps = 10;  ///< RK4 steps per sample
  std::vector<FaultInjection> faults;
};

struct SimRow {
  double t = 0.0;
  double v = 0.0, r = 0.0, delta = 0.0;  ///< measured (faults applied)
  double v_true = 0.0, r_true = 0.0, delta_true = 0.0, psi = 0.0, psi_ref = 0.0;
  FaultKind fault_a = FaultKind::kUnknown;  ///< kUnknown: no accelerometer fault
  FaultKind fault_g = FaultKind::kUnknown;  ///< kUnknown: no gyro fault
};

class Simulator {
 public:
  /// Throws std::invalid_argument on a bad configuration.
  explicit Simulator(const SimConfig& cfg);
  /// Produces the next sample; false once the duration is over.
  bool next(SimRow* row);

 private:
  using State = Eigen::Matrix<double, 4, 1>;  // v, r, psi, delta
  State deriv(const State& z, double delta_c) const;
  double autopilot(double psi_ref) const;
  double apply_faults(int channel, double t, double truth, double noisy, FaultKind* active);

  SimConfig c_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  std::uniform_real_distribution<double> u01_{0.0, 1.0};
  State z_ = State::Zero();
  double psi_ref_ = 0.0, target_ = 0.0;
  Eigen::Vector3d measured_ = Eigen::Vector3d::Zero();  ///< last valid v, r; integrated heading
  std::uint64_t k_ = 0;
  double sigma_[2] = {0, 0};
  std::vector<double> held_;  ///< stuck values per injection
};

/// Runs a whole simulation.
std::vector<SimRow> simulate(const SimConfig& cfg);

/// The paper's scenario: gyro fault on t in (20, 40) s, accelerometer fault on (60, 80) s.
SimConfig paper_scenario(const VesselModel& vessel, double rate_hz, std::uint64_t seed);

}  // namespace usvfdi
