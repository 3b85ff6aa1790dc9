// Typed NMEA 0183 (IEC 61162-1) sentences the FDI sidecar reads: ROT, RSA, HDT, THS, VBW, VTG.
//
// Every parser takes a Sentence of any talker (proprietary sentences are refused), checks the
// formatter and the field count, and returns the struct or a Rejection. Empty fields are
// absent (std::nullopt); a status 'V' (or a mode indicator saying "not valid") is kept in the
// struct, and valid() tells whether the value may be used. Numbers are [+-]digits[.digits];
// absurd values are refused with kOutOfRange. Each format_*() builds the sentence back (numbers
// in the shortest text that reads back to the same double) and refuses what its parser would.
//
// Field layouts and signs (IEC 61162-1 / NMEA 0183, as quoted by the interface chapters of
// Furuno RD-50, JRC JLN-720 and JLR-30, Trimble SPS receiver, Furuno SC-50 and ECT NP5000
// manuals and a NOAA NCEI VBW format note, found with the search tool):
//   $--ROT,x.x,A            rate of turn [deg/min], "-" = bow turns to port; status A/V
//   $--RSA,x.x,A,x.x,A      starboard (or single) rudder sensor, status; port rudder sensor,
//                           status. "Relative measurement of rudder angle without units,
//                           '-' = bow turns to port. Sensor output is proportional to rudder
//                           angle but not necessarily 1:1." Read here as degrees.
//                           SIGN: RSA > 0 turns the bow to STARBOARD. The engine's delta has
//                           the sign of the vessel model's B (docs/vessels.md, "Sign of delta
//                           per hull"): in the shipped configurations (config/vessels/otter.yaml,
//                           mariner.yaml: b2 < 0) delta > 0 gives r < 0, a turn to PORT, the
//                           OPPOSITE of RSA: delta [rad] = -RSA [deg] * pi / 180. Hulls with
//                           b2 > 0 (container, kvlcc2) share RSA's sign. See delta_from_rsa.
//   $--HDT,x.x,T            heading, degrees true
//   $--THS,x.x,a            true heading; mode A autonomous, E estimated (dead reckoning),
//                           M manual input, S simulator, V not valid
//   $--VBW,x.x,x.x,A,x.x,x.x,A[,x.x,A,x.x,A]
//                           longitudinal / transverse water speed [kn], status; longitudinal /
//                           transverse ground speed [kn], status; then (optional) stern
//                           transverse water speed, status; stern transverse ground speed,
//                           status. Longitudinal "-" = astern, transverse "-" = port.
//   $--VTG,x.x,T,x.x,M,x.x,N,x.x,K[,a]
//                           course over ground true, magnetic [deg]; speed over ground [kn],
//                           [km/h]; mode indicator A autonomous, D differential, E estimated,
//                           M manual, S simulator, N not valid, P precise (absent before
//                           NMEA 2.3).
#pragma once

#include <optional>
#include <string>

#include "usv_fdi/nmea/result.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::nmea {

/// Largest |rate of turn| accepted [deg/min] (JRC: 0 - 9999.9; 10000 deg/min = 2.9 rad/s).
constexpr double kMaxRateOfTurn = 10000.0;
/// Largest |rudder angle| accepted [deg].
constexpr double kMaxRudderAngle = 90.0;
/// Largest |speed| accepted [kn].
constexpr double kMaxSpeedKnots = 100.0;
/// km per nautical mile (speeds in km/h are checked against kMaxSpeedKnots * this).
constexpr double kKmPerNauticalMile = 1.852;

/// A status field: 'A' data valid, 'V' data invalid, or empty.
enum class Status : char { kAbsent = '\0', kValid = 'A', kInvalid = 'V' };

/// $--ROT: rate of turn.
struct Rot {
  std::string talker = "HE";
  std::optional<double> rate_deg_per_min;  ///< "-" = bow turns to port
  Status status = Status::kAbsent;
  bool valid() const { return rate_deg_per_min && status == Status::kValid; }
  bool operator==(const Rot& o) const {
    return talker == o.talker && rate_deg_per_min == o.rate_deg_per_min && status == o.status;
  }
};

/// $--RSA: rudder sensor angle (see the sign note above: opposite to the shipped vessels' delta).
struct Rsa {
  std::string talker = "AG";
  std::optional<double> starboard_deg;  ///< starboard or single rudder; "-" = bow turns to port
  Status starboard_status = Status::kAbsent;
  std::optional<double> port_deg;  ///< port rudder (twin rudders), same sign
  Status port_status = Status::kAbsent;
  bool starboard_valid() const { return starboard_deg && starboard_status == Status::kValid; }
  bool port_valid() const { return port_deg && port_status == Status::kValid; }
  bool operator==(const Rsa& o) const {
    return talker == o.talker && starboard_deg == o.starboard_deg &&
           starboard_status == o.starboard_status && port_deg == o.port_deg &&
           port_status == o.port_status;
  }
};

/// $--HDT: heading, true (no status field: valid when present).
struct Hdt {
  std::string talker = "HE";
  std::optional<double> heading_deg;  ///< [0, 360]
  bool valid() const { return heading_deg.has_value(); }
  bool operator==(const Hdt& o) const { return talker == o.talker && heading_deg == o.heading_deg; }
};

/// THS mode indicator.
enum class HeadingMode : char {
  kAbsent = '\0',
  kAutonomous = 'A',
  kEstimated = 'E',
  kManual = 'M',
  kSimulator = 'S',
  kNotValid = 'V',
};

/// $--THS: true heading and status.
struct Ths {
  std::string talker = "HE";
  std::optional<double> heading_deg;  ///< [0, 360]
  HeadingMode mode = HeadingMode::kAbsent;
  /// Only an autonomous heading is a measurement (E, M, S and V are not).
  bool valid() const { return heading_deg && mode == HeadingMode::kAutonomous; }
  bool operator==(const Ths& o) const {
    return talker == o.talker && heading_deg == o.heading_deg && mode == o.mode;
  }
};

/// $--VBW: dual ground/water speed [kn]; longitudinal "-" = astern, transverse "-" = port.
struct Vbw {
  std::string talker = "VD";
  std::optional<double> water_longitudinal_kn;
  std::optional<double> water_transverse_kn;
  Status water_status = Status::kAbsent;
  std::optional<double> ground_longitudinal_kn;
  std::optional<double> ground_transverse_kn;
  Status ground_status = Status::kAbsent;
  std::optional<double> stern_water_transverse_kn;
  Status stern_water_status = Status::kAbsent;
  std::optional<double> stern_ground_transverse_kn;
  Status stern_ground_status = Status::kAbsent;
  bool water_valid() const { return water_status == Status::kValid; }
  bool ground_valid() const { return ground_status == Status::kValid; }
  /// Whether a stern field or status is present (then format_vbw writes all ten fields).
  bool has_stern() const {
    return stern_water_transverse_kn || stern_water_status != Status::kAbsent ||
           stern_ground_transverse_kn || stern_ground_status != Status::kAbsent;
  }
  bool operator==(const Vbw& o) const;
};

/// Mode indicator of VTG (and other positioning sentences).
enum class PositioningMode : char {
  kAbsent = '\0',
  kAutonomous = 'A',
  kDifferential = 'D',
  kEstimated = 'E',
  kManual = 'M',
  kSimulator = 'S',
  kNotValid = 'N',
  kPrecise = 'P',
};

/// $--VTG: course over ground and ground speed.
struct Vtg {
  std::string talker = "GP";
  std::optional<double> course_true_deg;      ///< [0, 360]
  std::optional<double> course_magnetic_deg;  ///< [0, 360]
  std::optional<double> speed_kn;             ///< [0, kMaxSpeedKnots]
  std::optional<double> speed_kmh;            ///< [0, kMaxSpeedKnots * 1.852]
  PositioningMode mode = PositioningMode::kAbsent;
  /// Speed usable as a measurement: mode A, D or P, or no mode field (before NMEA 2.3).
  bool valid() const {
    return mode == PositioningMode::kAbsent || mode == PositioningMode::kAutonomous ||
           mode == PositioningMode::kDifferential || mode == PositioningMode::kPrecise;
  }
  bool operator==(const Vtg& o) const {
    return talker == o.talker && course_true_deg == o.course_true_deg &&
           course_magnetic_deg == o.course_magnetic_deg && speed_kn == o.speed_kn &&
           speed_kmh == o.speed_kmh && mode == o.mode;
  }
};

Result<Rot> parse_rot(const Sentence& s);
Result<Rsa> parse_rsa(const Sentence& s);
Result<Hdt> parse_hdt(const Sentence& s);
Result<Ths> parse_ths(const Sentence& s);
Result<Vbw> parse_vbw(const Sentence& s);
Result<Vtg> parse_vtg(const Sentence& s);

Sentence to_sentence(const Rot& x);
Sentence to_sentence(const Rsa& x);
Sentence to_sentence(const Hdt& x);
Sentence to_sentence(const Ths& x);
Sentence to_sentence(const Vbw& x);
Sentence to_sentence(const Vtg& x);

// Conversions to the project's quantities and signs (include/usv_fdi/core/types.hpp: v and r
// positive to starboard, SI units; the sign of delta is the vessel model's, see RudderSign).

/// Metres per second in one knot (1852 m / 3600 s).
constexpr double kMetresPerSecondPerKnot = 1852.0 / 3600.0;
constexpr double kPi = 3.14159265358979323846;

/// r [rad/s], > 0 bow to starboard, from ROT [deg/min] ("-" = bow to port): the same sign.
inline double yaw_rate_from_rot(double deg_per_min) { return deg_per_min * kPi / (180.0 * 60.0); }
/// Which way a positive delta of the vessel model turns the bow.
enum class RudderSign {
  kPositiveToPort,       ///< b2 < 0: otter, mariner (the shipped configurations), coaster, ...
  kPositiveToStarboard,  ///< b2 > 0: container, kvlcc2 (docs/vessels.md)
};
/// The sign of a model whose B = [b1, b2] (r positive to starboard): b2 < 0 turns to port.
inline RudderSign rudder_sign_from_b2(double b2) {
  return b2 < 0.0 ? RudderSign::kPositiveToPort : RudderSign::kPositiveToStarboard;
}
/// delta [rad] from RSA [deg] ("-" = bow to port): the opposite sign for kPositiveToPort.
inline double delta_from_rsa(double rsa_deg, RudderSign sign) {
  const double rad = rsa_deg * kPi / 180.0;
  return sign == RudderSign::kPositiveToPort ? -rad : rad;
}
/// v or u [m/s] from a VBW/VTG speed [kn]: the same sign (VBW transverse "-" = port, v > 0 to
/// starboard; longitudinal "-" = astern, u > 0 ahead).
inline double speed_from_knots(double kn) { return kn * kMetresPerSecondPerKnot; }

/// The sentence with checksum and CR LF; refused (never throws) where the parser would refuse.
Result<std::string> format_rot(const Rot& x);
Result<std::string> format_rsa(const Rsa& x);
Result<std::string> format_hdt(const Hdt& x);
Result<std::string> format_ths(const Ths& x);
Result<std::string> format_vbw(const Vbw& x);
Result<std::string> format_vtg(const Vtg& x);

}  // namespace usvfdi::nmea
