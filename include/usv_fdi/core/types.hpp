// usv-fdi core types. Depends on Eigen only.
//
// Symbols follow Bazylev & Margun, "Algorithm for detecting INS faults of an unmanned
// surface vessel with unknown parameters" (ITMO): x = [v r]^T, x' = A x + B delta, y = C x,
// C = I, A = [[a1 a2], [a3 a4]] unknown, B known.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <string>

namespace usvfdi {

using Vec2 = Eigen::Matrix<double, 2, 1>;
using Mat2 = Eigen::Matrix<double, 2, 2>;
using Vec4 = Eigen::Matrix<double, 4, 1>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Named indices of the state / output vector.
enum StateIndex : int { kV = 0, kR = 1 };

/// One synchronised input sample. NaN marks a missing or invalid value.
struct Sample {
  double t = kNaN;      ///< source time [s]
  double v = kNaN;      ///< sway velocity from the accelerometer channel [m/s]
  double r = kNaN;      ///< yaw rate from the gyro [rad/s]
  double delta = kNaN;  ///< rudder angle [rad]
  /// Surge speed through the water [m/s], optional (NaN: not measured; core/speed.hpp).
  double u = kNaN;
};

/// The INS sensor a fault is attributed to.
enum class Sensor : std::uint8_t { kAccelerometer = 0, kGyro = 1, kUnknown = 2 };

/// Fault kinds (docs/design.md section 4); kUnknown where they cannot be told apart.
enum class FaultKind : std::uint8_t {
  kUnknown = 0,
  kBias,
  kDrift,
  kStuck,
  kNoise,
  kSpikes,
  kScale,
  kStale,
  kInvalid,
};

/// Alert states after IEC 62923 bridge alert management.
enum class FaultState : std::uint8_t {
  kNormal = 0,             ///< no fault; nothing latched
  kRaised,                 ///< active, unacknowledged
  kActiveAcknowledged,     ///< active, acknowledged by an operator
  kClearedUnacknowledged,  ///< rectified, not yet acknowledged: stays latched
  kAcknowledged,           ///< rectified and acknowledged (the final word on an instance)
};

const char* to_string(Sensor s);
const char* to_string(FaultKind k);
const char* to_string(FaultState s);
bool parse_sensor(const std::string& text, Sensor* out);
bool parse_fault_kind(const std::string& text, FaultKind* out);
bool parse_fault_state(const std::string& text, FaultState* out);

/// Row-major A as [a1 a2 a3 a4].
inline Vec4 to_params(const Mat2& A) { return Vec4(A(0, 0), A(0, 1), A(1, 0), A(1, 1)); }
inline Mat2 from_params(const Vec4& a) {
  Mat2 A;
  A << a(0), a(1), a(2), a(3);
  return A;
}

}  // namespace usvfdi
