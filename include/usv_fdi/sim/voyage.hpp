// Voyage simulator of the proving ground: drives any sim::Hull through scripted manoeuvres
// under a heading autopilot that steers on the MEASURED heading and yaw rate, in waves, wind
// and current, with realistic INS and rudder sensors and scripted INS faults. Depends on
// Eigen and the core types only. Deterministic by seed: every random process draws from its
// own stream derived from VoyageConfig::seed, so switching one on does not change the others.
//
// Signals (project conventions, usv_fdi/sim/hull.hpp):
//   hull state (low-frequency motion)   u, v_lf, r_lf, psi_lf   integrated from Hull::rates
//   first-order wave motion             v_w, r_w, psi_w        added to the hull's motion
//   current over ground (body frame)    v_c                    the INS moves with the water
//   true motion (what a perfect INS sees) v_true = v_lf + v_w + v_c, r_true = r_lf + r_w,
//                                       psi = psi_lf + psi_w
//   measured                            v, r, delta = sensor(true) with faults, quantised
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/types.hpp"
#include "usv_fdi/sim/hull.hpp"
#include "usv_fdi/sim/manoeuvre.hpp"

namespace usvfdi::sim {

// ----------------------------------------------------------------------------- scenario

/// What one leg of a voyage does.
enum class Manoeuvre : std::uint8_t {
  kHold = 0,  ///< autopilot holds the current course reference
  kCourse,    ///< autopilot turns by `heading` through its reference model
  kZigzag,    ///< open-loop zigzag: rudder +-`rudder` switched at +-`heading` off the base course
  kTurn,      ///< turning circle: rudder `rudder` until the heading changed by `heading`
  kSpeed,     ///< throttle step to `throttle`, autopilot holds the course
};

struct Leg {
  Manoeuvre kind = Manoeuvre::kHold;
  double duration = 60.0;  ///< [s]; zigzag and turn legs end earlier when complete
  double heading = 0.0;    ///< course change (kCourse), switch angle (kZigzag), turn (kTurn) [rad]
  double rudder = 0.0;     ///< zigzag / turning rudder angle [rad] (its sign: the first side)
  double throttle = -1.0;  ///< throttle from this leg on (< 0: unchanged)
};

/// Names of the voyage scenarios, for `--scenario` and errors.
std::vector<std::string> scenario_names();
/// The legs of a named scenario for a hull (periods scaled by its length and speed).
/// course: +-10 deg course changes; zigzag10 / zigzag20: 10/10 and 20/20 zigzags, the first
/// execute to `first`; turn: a turning circle to `first`, then one to the other side; speed:
/// throttle steps of -30 % and +30 % (deceleration and acceleration) under course changes;
/// slow: a slow passage at 50 % throttle with course changes; voyage: all of them, one after
/// another. `first` defaults to starboard (the legs are then those of before it existed).
/// Throws std::invalid_argument on an unknown name.
std::vector<Leg> scenario_legs(const std::string& name, const Hull& hull,
                               Side first = Side::kStarboard);
/// Time between course changes of the scripted voyages: max(20 s, 6 L / U0).
double leg_period(const Hull& hull);
/// Rudder of the turning circles: 35 deg (or the hull's maximum); on a linear hull, whose
/// steady turn at 35 deg no real ship reaches, the rudder of a circle of diameter 4 L.
double turning_rudder(const Hull& hull);

// -------------------------------------------------------------------------- environment

/// Significant wave height and peak period of a sea state (WMO code; calm for 0..2).
struct SeaState {
  int code = 0;
  double hs = 0.0;  ///< significant wave height [m]
  double tp = 0.0;  ///< peak period [s]
};
/// Sea states 0 (calm), 3 (Hs 0.88 m, Tp 7.5 s), 4 (1.88 m, 8.8 s), 5 (3.25 m, 9.7 s),
/// 6 (5.0 m, 12.4 s). Throws std::invalid_argument on another code.
SeaState sea_state(int code);

struct EnvironmentConfig {
  SeaState sea;                   ///< code 0: no wave motion
  double wave_damping = 0.1;      ///< relative damping lambda of the wave shaping filter [-]
  double wave_yaw_sigma = -1.0;   ///< std of the wave-induced yaw rate [rad/s]; < 0: from sea
  double wave_sway_sigma = -1.0;  ///< std of the wave-induced sway velocity [m/s]; < 0: from sea
  /// Current over ground: the hull moves with the water (no force on the hull: its
  /// hydrodynamics act on the velocity through the water), the INS reads the current's cross
  /// component in the sway velocity; as the hull turns that component changes. In the
  /// engine's x' = A x + B delta on the measured v this is the sway force and yaw moment
  /// -A [v_c 0]^T (plus v_c').
  double current = 0.0;                           ///< mean current speed [m/s]
  double current_sigma = 0.0;                     ///< Gauss-Markov std of the current speed [m/s]
  double current_direction = 1.5707963267948966;  ///< initial set, from the initial course [rad]
  double current_direction_rw = 0.002;            ///< random walk of the set [rad/sqrt(s)]
  double current_tau = 600.0;                     ///< correlation time of the speed [s]
  double wind = 0.0;        ///< mean wind yaw moment and sway force as an equivalent rudder [rad]
  double wind_sigma = 0.0;  ///< Gauss-Markov std of the gusts, same unit [rad]
  double wind_tau = 60.0;   ///< correlation time of the gusts [s]
};

// ------------------------------------------------------------------------------ sensors

/// How a channel is printed by its source.
struct Quantiser {
  double step = 0.0;  ///< round to multiples of step (> 0); 0: no step
  int digits = 0;     ///< round to this many significant digits (> 0); 0: none
  double apply(double x) const;
};
/// A yaw rate printed as NMEA ROT (degrees per minute, one decimal) [rad/s].
constexpr double kRotQuantum = 0.1 * 3.14159265358979323846 / 180.0 / 60.0;
/// A rudder angle printed to 0.1 deg [rad].
constexpr double kRudderQuantum = 0.1 * 3.14159265358979323846 / 180.0;

struct ChannelNoise {
  double white = 0.0;     ///< white noise std [unit]
  double gm_sigma = 0.0;  ///< first-order Gauss-Markov noise std [unit]
  double gm_tau = 30.0;   ///< its correlation time [s]
  double bias_rw = 0.0;   ///< bias instability: random walk [unit/sqrt(s)]
  double bias = 0.0;      ///< constant offset [unit]
  double lag = 0.0;       ///< first-order sensor lag [s] (0: none)
  Quantiser quantiser;
};

struct SensorConfig {
  ChannelNoise v;              ///< accelerometer channel (sway velocity) [m/s]
  ChannelNoise r;              ///< gyro [rad/s]
  ChannelNoise delta;          ///< rudder angle sensor [rad]
  double compass_sigma = 0.0;  ///< white noise of the heading reference [rad]
  double compass_tau = 100.0;  ///< the autopilot's heading: gyro integrated, pulled to the
                               ///< compass with this time constant [s] (0: compass alone)
  double jitter = 0.0;         ///< timestamp jitter std [s] (clipped to 0.45 / rate)
  double drop = 0.0;           ///< probability that a sample is lost [-]
  double duplicate = 0.0;      ///< probability that a sample is sent twice [-]
};

/// Sensor presets for `--sensor`: ideal (white noise of the shipped vessels only);
/// mems (gyro bias instability, Gauss-Markov noise at half the white sigma, ROT and rudder
/// quantisation, 0.5 deg rudder offset and 0.2 s lag, 2 ms jitter, 0.5 % drops, 0.2 %
/// duplicates). Returns false on an unknown name.
bool sensor_preset(const std::string& name, double sigma_v, double sigma_r, SensorConfig* out);
/// Applies one `key=value` setting (keys: see README, e.g. gyro.gm=2.5e-4, drop=0.01,
/// rot=nmea, v.digits=3). Returns false and says why in *error.
bool apply_sensor_setting(const std::string& setting, SensorConfig* out, std::string* error);

// ------------------------------------------------------------------------------ voyage

struct AutopilotConfig {
  double bandwidth = -1.0;     ///< natural frequency of the heading loop [rad/s]; < 0: 1.2 U0/L
  double damping = 0.9;        ///< relative damping [-]
  double integral = 0.1;       ///< integral gain relative to bandwidth * Kp [-] (0: PD)
  double dither = 0.0;         ///< rudder dither amplitude [rad] (0: none)
  double dither_period = 0.0;  ///< [s]; <= 0: 0.5 * leg period of the hull
};

struct VoyageConfig {
  double rate_hz = 10.0;
  double duration = 600.0;  ///< [s]; the legs repeat until then
  std::uint64_t seed = 1;
  int substeps = 10;      ///< RK4 steps per sample
  std::vector<Leg> legs;  ///< empty: hold course
  AutopilotConfig autopilot;
  EnvironmentConfig environment;
  SensorConfig sensors;
  /// The channels' sigma in which fault magnitudes are given; <= 0: the white noise sigma.
  double sigma_v = 0.0, sigma_r = 0.0;
  std::vector<FaultInjection> faults;  ///< in channel units (core semantics)
};

/// A fault with its magnitude in units of the channel's sigma (scale: relative; stuck,
/// stale, invalid: unused), converted to channel units for `cfg`.
FaultInjection sigma_fault(const VoyageConfig& cfg, Sensor sensor, FaultKind kind, double t_start,
                           double t_end, double k_sigma, double spike_rate = 2.0);
/// The standard fault set of the benchmark from t0, alternating sensors, `length` each with
/// `gap` between: bias 10 sigma, stuck, drift 10 sigma per 30 s, noise x8, scale +50 %,
/// spikes 25 sigma, stale, invalid; repeated until the end of the voyage.
std::vector<FaultInjection> standard_faults(const VoyageConfig& cfg, double t0,
                                            double length = 30.0, double gap = 60.0);
/// The sigma of a channel for fault magnitudes (cfg.sigma_* or its white noise).
double channel_sigma(const VoyageConfig& cfg, Sensor sensor);

/// One output sample: today's SimRow fields plus the voyage's.
struct VoyageRow : SimRow {
  double t_true = 0.0;                ///< sampling instant (t is the stamp, with jitter)
  double u_true = 0.0;                ///< surge speed [m/s] (CSV column `u`)
  double v_lf = 0.0, r_lf = 0.0;      ///< the hull's low-frequency motion
  double v_wave = 0.0, r_wave = 0.0;  ///< first-order wave motion
  double v_current = 0.0;             ///< cross component of the current (in v_true) [m/s]
  double psi_meas = 0.0;              ///< the autopilot's heading [rad]
  double delta_cmd = 0.0;  ///< rudder command (autopilot or manoeuvre, with dither) [rad]
  double throttle = 1.0;   ///< [-]
  double gyro_bias = 0.0;  ///< gyro bias (constant + random walk) [rad/s]
  double dist_v = 0.0, dist_r = 0.0;  ///< wind accelerations [m/s^2, rad/s^2]
  Manoeuvre manoeuvre = Manoeuvre::kHold;
  bool duplicate = false;  ///< this row repeats the previous one (a duplicated sample)
};

const char* to_string(Manoeuvre m);

class Voyage {
 public:
  /// Throws std::invalid_argument on a bad configuration.
  Voyage(std::shared_ptr<const Hull> hull, const VoyageConfig& cfg);
  ~Voyage();
  Voyage(const Voyage&) = delete;
  Voyage& operator=(const Voyage&) = delete;
  /// The next emitted row (dropped samples are skipped, duplicates repeated); false once
  /// the duration is over.
  bool next(VoyageRow* row);
  /// The hull's linearisation about straight running at its nominal speed (sim::linearise).
  const Linearisation& linearisation() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> p_;
};

/// Runs a whole voyage.
std::vector<VoyageRow> run_voyage(std::shared_ptr<const Hull> hull, const VoyageConfig& cfg);

/// Every hull a voyage can drive: the vessel zoo (usv_fdi/sim/hulls.hpp), then the core's
/// shipped vessels the zoo has no entry of that name for (otter: a linear hull with A ~ U/U0,
/// B ~ (U/U0)^2 and a first-order surge).
std::vector<std::string> voyage_hull_names();
/// Returns nullptr when there is no hull of that name.
std::shared_ptr<const Hull> voyage_hull(const std::string& name);

/// CSV of voyage rows: the SimRow columns first (t,v,r,delta,v_true,r_true,delta_true,psi,
/// psi_ref,fault_a,fault_g), then u,t_true,v_lf,r_lf,v_wave,r_wave,v_current,psi_meas,delta_cmd,
/// throttle,gyro_bias,dist_v,dist_r,manoeuvre,duplicate; numbers %.17g.
/// A measured channel whose sensor prints a number of significant digits (Quantiser::digits)
/// is written with those digits (as its source prints it; read back it is the same double).
class VoyageCsvWriter {
 public:
  explicit VoyageCsvWriter(std::ostream& out, const SensorConfig& sensors = SensorConfig{});
  void write(const VoyageRow& row);

 private:
  std::ostream& out_;
  int digits_[3] = {0, 0, 0};  ///< v, r, delta; 0: %.17g
};

}  // namespace usvfdi::sim
