// Helpers shared by the Isolator's translation units (isolation.cpp: the orchestration,
// sensor and jump checks; isolation_bank.cpp: the observer banks and their statistics;
// isolation_decision.cpp: the decision and the conditions). Not part of the public headers.
#pragma once

#include <cmath>
#include <deque>
#include <utility>

#include "usv_fdi/core/isolation.hpp"

namespace usvfdi::isolation_detail {

/// Finite and within the plausible limit.
inline bool within(double x, double lim) { return std::isfinite(x) && std::abs(x) <= lim; }

/// Slack of the time comparisons (hold, enter and leave times) [s].
constexpr double kEpsT = 1e-9;

inline int sensor_index(Sensor s) { return static_cast<int>(s); }
inline Sensor channel_sensor(int ch) { return ch == kV ? Sensor::kAccelerometer : Sensor::kGyro; }

inline void prune(std::deque<double>* q, double t_min) {
  while (!q->empty() && q->front() < t_min) q->pop_front();
}
inline void prune(std::deque<std::pair<double, double>>* q, double t_min) {
  while (!q->empty() && q->front().first < t_min) q->pop_front();
}

}  // namespace usvfdi::isolation_detail
