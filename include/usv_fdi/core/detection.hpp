// A change of one sensor's fault condition: what the isolation stage (isolation.hpp) decides
// and the latch (latch.hpp) turns into events. Its own header so that the latch, and every
// consumer of FaultEvent, need not include the isolation stack.
#pragma once

#include <string>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

/// A change of the fault condition of one sensor (the latch turns it into events).
struct Detection {
  Sensor sensor = Sensor::kUnknown;
  bool active = false;  ///< true: condition raised; false: condition cleared
  bool update = false;  ///< a raised condition's kind was refined (no state change)
  FaultKind kind = FaultKind::kUnknown;
  double c_a = 0.0, c_g = 0.0;
  double statistic = 0.0, threshold = 0.0;
  double onset_time = kNaN;      ///< estimated onset [s, source clock]
  double detection_time = kNaN;  ///< sample time of the decision [s]
  std::string message;
};

}  // namespace usvfdi
