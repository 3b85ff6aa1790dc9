// usv-fdi ros2, the parts without Fast DDS: ROS 2 (REP 103) signs to the project's, stamps,
// the assembly of INS samples from the yaw-rate and sway-velocity streams, and the
// diagnostic_msgs/DiagnosticStatus of one vessel's fault instances.
//
// Frames. ROS follows REP 103: body x forward, y to PORT, z UP; a yaw rate is positive
// counter-clockwise seen from above, a sway velocity positive to port. usv-fdi: x forward,
// y STARBOARD, z DOWN (v and r positive to starboard). Hence
//   v = -twist.linear.y,   r = -angular_velocity.z.
// The rudder angle (std_msgs/Float64, radians) has no ROS convention: δ = rudder_sign * data,
// the sign given by the user (--rudder-sign). It has no header either: it is paired with the
// Imu samples on the DDS source timestamps (the writers' clocks).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "monitor_model.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi::app::ros2 {

/// Profiles of the ROS 2 entities in config/qos/usv_fdi_profiles.xml.
inline constexpr const char* kSensorReaderProfile = "usv_fdi_ros2_sensor_reader";
inline constexpr const char* kDiagnosticsWriterProfile = "usv_fdi_ros2_diagnostics_writer";
inline constexpr const char* kFaultEventWriterProfile = "usv_fdi_ros2_fault_event_writer";
inline constexpr const char* kStatusWriterProfile = "usv_fdi_ros2_status_writer";

/// REP 103 sway velocity (linear.y, positive to port) -> usv-fdi v (positive to starboard).
inline double sway_from_rep103(double linear_y) { return -linear_y; }
/// REP 103 yaw rate (angular_velocity.z, positive counter-clockwise from above) -> usv-fdi r
/// (positive turning to starboard, clockwise from above).
inline double yaw_rate_from_rep103(double angular_z) { return -angular_z; }
/// The inverses (for a publisher of ROS messages).
inline double rep103_linear_y(double v) { return -v; }
inline double rep103_angular_z(double r) { return -r; }

/// builtin_interfaces/Time -> seconds.
inline double stamp_seconds(std::int32_t sec, std::uint32_t nanosec) {
  return static_cast<double>(sec) + 1e-9 * static_cast<double>(nanosec);
}
/// Seconds -> builtin_interfaces/Time (nanosec in [0, 1e9)).
void to_stamp(double t, std::int32_t* sec, std::uint32_t* nanosec);

/// The DDS topic of a ROS 2 topic: "/imu/data" and "imu/data" -> "rt/imu/data" (no node
/// namespace applies). Empty for a name ROS 2 would refuse (empty, "//", a trailing '/',
/// characters other than [A-Za-z0-9_/], a token starting with a digit).
std::string dds_topic_of(const std::string& ros_topic);

struct AssemblyParams {
  /// A sway sample up to this much older than an INS stamp (source time) is held; older:
  /// the INS sample's v is invalid (stale) [s]
  double sway_max_age = 0.2;
  /// Stamps this close are the same instant [s]
  double same_stamp = 1e-4;
  /// An INS sample waits at most this long (wall time) for a sway sample at or after its
  /// stamp, then is assembled from what there is [s]
  double pair_wait = 0.2;
  /// Pending INS samples at most (more: the oldest is assembled at once)
  std::size_t max_pending = 512;
  /// A rudder angle written up to this much before an Imu sample (writers' clocks) goes with
  /// it; older: the INS sample goes without one [s]
  double rudder_max_age = 1.0;
};

/// One yaw-rate sample (from sensor_msgs/Imu).
struct YawSample {
  double stamp = 0.0;  ///< header.stamp [s]
  /// When its writer wrote it: the DDS source timestamp, on the writer's clock [s]. The
  /// rudder angle (std_msgs/Float64, no header) is paired on this clock.
  double sent = 0.0;
  double r = 0.0;  ///< usv-fdi sign [rad/s]
  bool r_valid = false;
};

/// An INS sample (and the rudder angle to go with it) ready for the sidecar.
struct AssembledSample {
  double stamp = 0.0;
  double v = 0.0, r = 0.0;
  bool v_valid = false, r_valid = false;
  bool rudder = false;
  double delta = 0.0;
  bool delta_valid = false;
};

/// Assembles INS samples on the yaw-rate (Imu) stamps. Each waits until a sway sample at or
/// after its stamp and a rudder angle written at or after it have arrived, or for
/// params.pair_wait of wall time; then its v is
///  * the sway sample at the same stamp (within same_stamp), else
///  * linear interpolation between the sway samples around its stamp when they are at most
///    sway_max_age apart, else
///  * the latest sway sample before its stamp when it is at most sway_max_age old, else
///    invalid (no sway, or stale);
/// and its rudder angle the one written last before it (source timestamps, at most
/// rudder_max_age earlier), else none. The order of arrival does not matter: the readers of
/// different topics deliver on different threads (Fast DDS data sharing for the bounded
/// Float64), so a burst of one topic may arrive before or after the other's.
/// Samples leave in the order their Imu samples arrived.
class InsAssembler {
 public:
  explicit InsAssembler(const AssemblyParams& p) : p_(p) {}

  void add_sway(double stamp, double v);
  /// A rudder angle written at `sent` (source timestamp [s]); `valid` false: the writer sent
  /// a value that is not a number.
  void add_rudder(double sent, double delta, bool valid);
  void add_yaw(const YawSample& s, double wall_now);
  /// The samples ready at wall time `wall_now`, in order.
  std::vector<AssembledSample> release(double wall_now);

  std::uint64_t sway_stale() const { return sway_stale_; }          ///< assembled with v invalid
  std::uint64_t overflowed() const { return overflowed_; }          ///< released early: queue full
  std::uint64_t sway_rejected() const { return sway_rejected_; }    ///< non-finite or old
  std::uint64_t without_rudder() const { return without_rudder_; }  ///< none, or too old

 private:
  struct Pending {
    YawSample s;
    double arrived = 0.0;  ///< wall time
  };
  struct Rudder {
    double sent = 0.0;  ///< source timestamp [s]
    double delta = 0.0;
    bool valid = false;
  };
  AssembledSample assemble(const YawSample& s);
  void pair_rudder(const YawSample& s, AssembledSample* a);
  /// The first rudder angle written after `sent` (rudder_ is ordered by source time).
  std::deque<Rudder>::iterator first_rudder_after(double sent);

  AssemblyParams p_;
  std::deque<std::pair<double, double>> sway_;  ///< (stamp, v), stamps increasing
  std::deque<Rudder> rudder_;                   ///< source timestamps increasing
  /// The latest Imu sample's source timestamp (-inf: none yet) [s]
  double last_yaw_sent_ = -std::numeric_limits<double>::infinity();
  std::deque<Pending> pending_;
  std::uint64_t sway_stale_ = 0, overflowed_ = 0, sway_rejected_ = 0, without_rudder_ = 0;
};

/// Whether the clocks of two writers agree, from what their samples say: each sample's
/// reception time less its source time is the offset of its writer's clock from the reader's
/// plus the transport delay, and its least value over a block of samples is that offset plus
/// the least delay. The rudder angles are paired with the Imu samples on the writers' clocks,
/// so a difference between the two writers' offsets shifts the pairing by that much.
class ClockSkew {
 public:
  explicit ClockSkew(std::size_t block = 100) : block_(block) {}
  void add(bool rudder, double sent, double received);
  /// The rudder writer's clock less the Imu writer's [s]; NaN until each stream has filled a
  /// block.
  double skew() const;

 private:
  struct Stream {
    double current = std::numeric_limits<double>::infinity();  ///< least delay of this block
    double last = std::numeric_limits<double>::quiet_NaN();    ///< of the block before
    std::size_t n = 0;
  };
  std::size_t block_;
  Stream imu_, rudder_;
};

/// diagnostic_msgs/DiagnosticStatus levels.
enum class DiagLevel : std::uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };
const char* to_string(DiagLevel l);

/// One DiagnosticStatus, without Fast DDS.
struct DiagStatus {
  DiagLevel level = DiagLevel::kOk;
  std::string name;
  std::string message;
  std::string hardware_id;
  std::vector<std::pair<std::string, std::string>> values;
  bool operator==(const DiagStatus& o) const {
    return level == o.level && name == o.name && message == o.message &&
           hardware_id == o.hardware_id && values == o.values;
  }
  bool operator!=(const DiagStatus& o) const { return !(*this == o); }
};

/// The level of one fault instance: STALE when the vessel's sidecar has not been heard for
/// more than silent_after s (heard_age NaN: never heard); else by the latch state: raised ->
/// ERROR; active-acknowledged or cleared-unacknowledged -> WARN; normal or acknowledged -> OK.
/// An instance of the unknown sensor (a fault no sensor could be blamed for) is at most WARN.
/// `row` nullptr: no instance published (OK).
DiagLevel diagnostic_level(Sensor sensor, const Row* row, double heard_age, double silent_after);

/// What the vessel's FdiStatus says beyond its latched faults.
/// (PAUSE_FAULT is no suspicion: it is set on every freeze of identification, and for 10 s
/// after a clear.)
struct VesselNotes {
  bool model_mismatch = false;  ///< isolation_paused & PAUSE_MODEL_MISMATCH
  /// The status's peak J_N per channel [accelerometer, gyro] and the thresholds that clear
  /// and raise a fault (0: none in force).
  double j_peak[2] = {0.0, 0.0};
  double j_leave[2] = {0.0, 0.0};
  double j_raise[2] = {0.0, 0.0};
  /// A suspicion of channel c: its peak above the level that clears a fault (one in force),
  /// not raised. (NaN peak: none computed; a comparison with NaN is false.)
  bool suspected(int c) const { return j_leave[c] > 0.0 && j_peak[c] > j_leave[c]; }
  // Inputs the sidecar cannot judge a sensor from now (input_flags, fdi::INPUT_*).
  bool ins_silent = false;      ///< INPUT_INS_SILENT
  bool rudder_missing = false;  ///< INPUT_RUDDER_MISSING (FDI paused)
  bool accel_unusable = false;  ///< INPUT_ACCELEROMETER_UNUSABLE (stale, invalid or stuck)
  bool gyro_unusable = false;   ///< INPUT_GYRO_UNUSABLE
};
/// From a status's isolation pause flags (fdi::PAUSE_*) and input flags (fdi::INPUT_*).
VesselNotes vessel_notes(std::uint32_t isolation_paused, std::uint32_t input_flags = 0);
/// The same, with the status's residual statistics (FdiStatus version 4: j_peak, j_raise,
/// j_leave per channel [accelerometer, gyro]) for the suspicions.
VesselNotes vessel_notes(std::uint32_t isolation_paused, std::uint32_t input_flags,
                         const std::array<double, 2>& j_peak, const std::array<double, 2>& j_raise,
                         const std::array<double, 2>& j_leave);

/// The statuses of one vessel: "usv_fdi: <mmsi> accelerometer" and "... gyro" always,
/// "... unknown" once the sidecar has published that instance. hardware_id is the MMSI;
/// values C_a, C_g, J_N (the event's statistic), threshold, state, sequence, kind.
/// `row_of(sensor)` gives the vessel's instance of a sensor or nullptr. A sensor that would
/// be OK or WARN is STALE while the heard sidecar reports its input stale (the INS silent, no
/// usable rudder angle, or the sensor's own channel unusable: it cannot judge the sensor now;
/// a raised fault stays ERROR); one that would be OK is WARN while the vessel reports a model
/// mismatch (not a sensor fault), else while its channel is suspected (VesselNotes::suspected).
template <class RowOf>
std::vector<DiagStatus> vessel_diagnostics(std::uint32_t mmsi, RowOf row_of, double heard_age,
                                           double silent_after, const VesselNotes& notes = {});

DiagStatus instance_diagnostic(std::uint32_t mmsi, Sensor sensor, const Row* row, double heard_age,
                               double silent_after);

/// The status of `sensor` told what the vessel's FdiStatus adds (see vessel_diagnostics).
void add_vessel_notes(const VesselNotes& notes, Sensor sensor, DiagStatus* d);

template <class RowOf>
std::vector<DiagStatus> vessel_diagnostics(std::uint32_t mmsi, RowOf row_of, double heard_age,
                                           double silent_after, const VesselNotes& notes) {
  std::vector<DiagStatus> out;
  for (const Sensor s : {Sensor::kAccelerometer, Sensor::kGyro, Sensor::kUnknown}) {
    const Row* row = row_of(s);
    if (s == Sensor::kUnknown && row == nullptr) continue;
    out.push_back(instance_diagnostic(mmsi, s, row, heard_age, silent_after));
    add_vessel_notes(notes, s, &out.back());
  }
  return out;
}

}  // namespace usvfdi::app::ros2
