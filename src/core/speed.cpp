#include "usv_fdi/core/speed.hpp"

#include <stdexcept>
#include <string>

namespace usvfdi {
namespace {
void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string(field) + " = " + std::to_string(value) + ": " + what);
  }
}
}  // namespace

void SpeedParams::validate() const {
  require(reference_speed >= 0 && std::isfinite(reference_speed), "model.reference_speed",
          reference_speed, "must be >= 0 (0: the first measured speed)");
  require(min_ratio > 0 && std::isfinite(min_ratio), "speed.min_ratio", min_ratio, "must be > 0");
  require(max_ratio > min_ratio && std::isfinite(max_ratio), "speed.max_ratio", max_ratio,
          "must be finite and > speed.min_ratio");
  require(quantum > 0 && quantum < 0.1, "speed.quantum", quantum, "must lie in (0, 0.1)");
  require(input_exponent >= 0 && input_exponent <= 3, "speed.input_exponent", input_exponent,
          "must lie in [0, 3]");
}

}  // namespace usvfdi
