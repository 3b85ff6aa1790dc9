#include "ros2_adapter.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>

namespace usvfdi::app::ros2 {

void to_stamp(double t, std::int32_t* sec, std::uint32_t* nanosec) {
  double whole = std::floor(t);
  auto ns = static_cast<std::int64_t>(std::llround((t - whole) * 1e9));
  if (ns >= 1000000000) {
    whole += 1.0;
    ns -= 1000000000;
  }
  *sec = static_cast<std::int32_t>(whole);
  *nanosec = static_cast<std::uint32_t>(ns);
}

std::string dds_topic_of(const std::string& ros_topic) {
  std::string name = ros_topic;
  if (!name.empty() && name.front() == '/') name.erase(0, 1);
  if (name.empty() || name.back() == '/') return {};
  bool token_start = true;
  for (const char c : name) {
    if (c == '/') {
      if (token_start) return {};  // "//"
      token_start = true;
      continue;
    }
    const auto u = static_cast<unsigned char>(c);
    if (!std::isalnum(u) && c != '_') return {};
    if (token_start && std::isdigit(u)) return {};
    token_start = false;
  }
  return "rt/" + name;
}

void InsAssembler::add_sway(double stamp, double v) {
  if (!std::isfinite(stamp) || !std::isfinite(v) ||
      (!sway_.empty() && stamp <= sway_.back().first)) {
    ++sway_rejected_;  // repeated or backward stamps: a second source or a replay
    return;
  }
  sway_.emplace_back(stamp, v);
  // Keep what a pending INS sample can still use: sway_max_age before the oldest one.
  const double keep_from =
      (pending_.empty() ? stamp : std::min(stamp, pending_.front().s.stamp)) - 2 * p_.sway_max_age;
  while (sway_.size() > 2 && sway_[1].first < keep_from) sway_.pop_front();
  while (sway_.size() > 4096) sway_.pop_front();
}

std::deque<InsAssembler::Rudder>::iterator InsAssembler::first_rudder_after(double sent) {
  return std::upper_bound(rudder_.begin(), rudder_.end(), sent,
                          [](double t, const Rudder& x) { return t < x.sent; });
}

void InsAssembler::add_rudder(double sent, double delta, bool valid) {
  if (!std::isfinite(sent)) return;
  const Rudder r{sent, valid ? delta : 0.0, valid && std::isfinite(delta)};
  // One writer's source timestamps increase; a second writer's may interleave with them.
  rudder_.insert(first_rudder_after(sent), r);
  // Keep what an INS sample can still use, pending or yet to come (the Imu reader may lag the
  // rudder reader): the last angle written rudder_max_age before the oldest pending one (none
  // pending: the latest Imu sample added), and everything after it.
  const double newest = rudder_.back().sent;
  const double keep_from =
      std::min(newest, pending_.empty() ? last_yaw_sent_ : pending_.front().s.sent) -
      p_.rudder_max_age;
  while (rudder_.size() > 2 && rudder_[1].sent < keep_from) rudder_.pop_front();
  while (rudder_.size() > 4096) rudder_.pop_front();
}

void InsAssembler::add_yaw(const YawSample& s, double wall_now) {
  pending_.push_back({s, wall_now});
  if (std::isfinite(s.sent)) last_yaw_sent_ = std::max(last_yaw_sent_, s.sent);
}

std::vector<AssembledSample> InsAssembler::release(double wall_now) {
  std::vector<AssembledSample> out;
  while (!pending_.empty()) {
    const Pending& p = pending_.front();
    const bool caught_up = !sway_.empty() && sway_.back().first >= p.s.stamp - p_.same_stamp &&
                           !rudder_.empty() && rudder_.back().sent >= p.s.sent;
    const bool waited = wall_now - p.arrived >= p_.pair_wait;
    const bool full = pending_.size() > p_.max_pending;
    if (!caught_up && !waited && !full) break;
    if (full && !caught_up && !waited) ++overflowed_;
    out.push_back(assemble(p.s));
    pending_.pop_front();
  }
  return out;
}

AssembledSample InsAssembler::assemble(const YawSample& s) {
  AssembledSample a;
  a.stamp = s.stamp;
  a.r = s.r;
  a.r_valid = s.r_valid;
  pair_rudder(s, &a);
  // The last sway sample at or before the stamp (within same_stamp), and the one after it.
  const std::pair<double, double>* before = nullptr;
  const std::pair<double, double>* after = nullptr;
  for (const auto& w : sway_) {
    if (w.first <= s.stamp + p_.same_stamp) {
      before = &w;
    } else {
      after = &w;
      break;
    }
  }
  if (before != nullptr && std::abs(before->first - s.stamp) <= p_.same_stamp) {
    a.v = before->second;
    a.v_valid = true;
  } else if (before != nullptr && after != nullptr &&
             after->first - before->first <= p_.sway_max_age) {
    const double w = (s.stamp - before->first) / (after->first - before->first);
    a.v = before->second + w * (after->second - before->second);
    a.v_valid = true;
  } else if (before != nullptr && s.stamp - before->first <= p_.sway_max_age) {
    a.v = before->second;
    a.v_valid = true;
  }
  if (!a.v_valid) ++sway_stale_;
  return a;
}

void InsAssembler::pair_rudder(const YawSample& s, AssembledSample* a) {
  // The last angle written at or before the Imu sample (the same instant counts: a writer
  // that publishes the rudder first, as an autopilot's loop does, pairs exactly).
  const auto after = first_rudder_after(s.sent);
  if (after == rudder_.begin() || !(s.sent - std::prev(after)->sent <= p_.rudder_max_age)) {
    ++without_rudder_;
    return;
  }
  a->rudder = true;
  a->delta = std::prev(after)->delta;
  a->delta_valid = std::prev(after)->valid;
}

void ClockSkew::add(bool rudder, double sent, double received) {
  const double d = received - sent;
  if (!std::isfinite(d)) return;
  Stream& s = rudder ? rudder_ : imu_;
  s.current = std::min(s.current, d);
  if (++s.n < block_) return;
  s.last = s.current;
  s.current = std::numeric_limits<double>::infinity();
  s.n = 0;
}

double ClockSkew::skew() const {
  // d = received - sent: a writer's clock behind the reader's makes d larger, so the rudder's
  // clock less the Imu's is the Imu's least delay less the rudder's.
  return imu_.last - rudder_.last;
}

const char* to_string(DiagLevel l) {
  switch (l) {
    case DiagLevel::kOk:
      return "OK";
    case DiagLevel::kWarn:
      return "WARN";
    case DiagLevel::kError:
      return "ERROR";
    case DiagLevel::kStale:
      return "STALE";
  }
  return "?";
}

DiagLevel diagnostic_level(Sensor sensor, const Row* row, double heard_age, double silent_after) {
  if (!(heard_age <= silent_after)) return DiagLevel::kStale;  // NaN: never heard
  if (row == nullptr) return DiagLevel::kOk;
  DiagLevel l = DiagLevel::kOk;
  switch (row->ev.state) {
    case FaultState::kRaised:
      l = DiagLevel::kError;
      break;
    case FaultState::kActiveAcknowledged:
    case FaultState::kClearedUnacknowledged:
      l = DiagLevel::kWarn;
      break;
    case FaultState::kNormal:
    case FaultState::kAcknowledged:
      l = DiagLevel::kOk;
      break;
  }
  if (sensor == Sensor::kUnknown && l == DiagLevel::kError) l = DiagLevel::kWarn;
  return l;
}

VesselNotes vessel_notes(std::uint32_t isolation_paused, std::uint32_t input_flags) {
  VesselNotes n;
  n.model_mismatch = (isolation_paused & fdi::PAUSE_MODEL_MISMATCH) != 0;
  n.ins_silent = (input_flags & fdi::INPUT_INS_SILENT) != 0;
  n.rudder_missing = (input_flags & fdi::INPUT_RUDDER_MISSING) != 0;
  n.accel_unusable = (input_flags & fdi::INPUT_ACCELEROMETER_UNUSABLE) != 0;
  n.gyro_unusable = (input_flags & fdi::INPUT_GYRO_UNUSABLE) != 0;
  return n;
}

VesselNotes vessel_notes(std::uint32_t isolation_paused, std::uint32_t input_flags,
                         const std::array<double, 2>& j_peak, const std::array<double, 2>& j_raise,
                         const std::array<double, 2>& j_leave) {
  VesselNotes n = vessel_notes(isolation_paused, input_flags);
  for (int c = 0; c < 2; ++c) {
    n.j_peak[c] = j_peak[c];
    n.j_raise[c] = j_raise[c];
    n.j_leave[c] = j_leave[c];
  }
  return n;
}

namespace {

/// Why the sidecar cannot judge `sensor` now ("": it can).
std::string stale_input(const VesselNotes& n, Sensor sensor) {
  std::string why;
  const auto add = [&why](const char* w) { why += (why.empty() ? "" : ", ") + std::string(w); };
  if (n.ins_silent) add("no INS samples");
  if (n.rudder_missing) add("no usable rudder angle");
  if (n.accel_unusable && sensor == Sensor::kAccelerometer)
    add("the accelerometer channel is stale, invalid or stuck");
  if (n.gyro_unusable && sensor == Sensor::kGyro)
    add("the gyro channel is stale, invalid or stuck");
  return why;
}

}  // namespace

void add_vessel_notes(const VesselNotes& notes, Sensor sensor, DiagStatus* d) {
  if (d->level == DiagLevel::kOk || d->level == DiagLevel::kWarn) {
    const std::string why = stale_input(notes, sensor);
    if (!why.empty()) {
      d->level = DiagLevel::kStale;
      d->message =
          "input stale (" + why + "): the sidecar cannot judge this sensor now; " + d->message;
      return;
    }
  }
  if (d->level != DiagLevel::kOk) return;
  if (notes.model_mismatch) {
    d->level = DiagLevel::kWarn;
    d->message =
        "model mismatch, not a sensor fault: the vessel's dynamics differ from the identified "
        "model (" +
        d->message + ")";
    return;
  }
  const int c = sensor == Sensor::kAccelerometer ? 0 : sensor == Sensor::kGyro ? 1 : -1;
  if (c < 0 || !notes.suspected(c)) return;
  d->level = DiagLevel::kWarn;
  d->message = fmt::format(
      "suspected: the {} channel's residual J_N {:.3g} is above the level that clears a fault "
      "({:.3g}), not at the one that raises it ({:.3g}) ({})",
      c == 0 ? "accelerometer" : "gyro", notes.j_peak[c], notes.j_leave[c], notes.j_raise[c],
      d->message);
}

DiagStatus instance_diagnostic(std::uint32_t mmsi, Sensor sensor, const Row* row, double heard_age,
                               double silent_after) {
  DiagStatus d;
  d.level = diagnostic_level(sensor, row, heard_age, silent_after);
  d.name = fmt::format("usv_fdi: {} {}", mmsi, to_string(sensor));
  d.hardware_id = std::to_string(mmsi);
  if (std::isnan(heard_age)) {
    d.message = "the vessel's usv-fdi sidecar has not been heard";
  } else if (d.level == DiagLevel::kStale) {
    d.message = fmt::format(
        "the vessel's usv-fdi sidecar has not been heard for {:.0f} s; last "
        "known state: {}",
        heard_age, row == nullptr ? "no fault" : to_string(row->ev.state));
  } else if (row == nullptr) {
    d.message = "no fault";
  } else {
    d.message = fmt::format("{} ({})", to_string(row->ev.state), row->ev.message);
  }
  if (row != nullptr) {
    const FaultEvent& e = row->ev;
    d.values = {{"C_a", fmt::format("{:.3f}", e.c_a)},
                {"C_g", fmt::format("{:.3f}", e.c_g)},
                {"J_N", fmt::format("{:.6g}", e.statistic)},
                {"threshold", fmt::format("{:.6g}", e.threshold)},
                {"state", to_string(e.state)},
                {"sequence", std::to_string(e.sequence)},
                {"kind", to_string(e.kind)}};
  }
  return d;
}

}  // namespace usvfdi::app::ros2
