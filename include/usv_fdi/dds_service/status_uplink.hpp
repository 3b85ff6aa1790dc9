// Which FdiStatus samples go to the shore (issue 13, section 5: a frugal uplink).
//
// The pipeline makes a status every service.status_rate period. Periodic mode sends every one.
// Event mode (the default) sends one when the shore's copy would no longer tell the truth:
//  * at once, when anything discrete differs from the last one sent: convergence, arming,
//    input health, flags, pause reasons, the message (its numbers aside), the incarnation,
//    the poles, the reference speed, a value becoming or ceasing to be finite, a problem counter
//    that starts counting (its growth goes with the heartbeat: the period's input flags say
//    that a problem goes on, so a steady loss does not make every status urgent);
//  * when the continuous values (A-hat, excitation, the channels' sigma, the surge speed and
//    speed ratio) have moved, relative to what was sent, past a dynamic event-triggering
//    threshold (seed 002; Girard's dynamic triggering): with e the weighted relative deviation
//    and eta >= 0 an internal budget,
//        send when  |e|^2 > sigma^2 + eta / theta,   then  eta <- max(0, lambda eta + sigma^2 -
//        |e'|^2)
//    (e' = 0 after a send). The budget a quiet period builds lets a brief excursion pass
//    unsent, and |e| never exceeds sigma sqrt(1 + 1 / (theta (1 - lambda))) (bound());
//  * at the evaluation nearest `heartbeat` s after the last one sent, so that a shore tells a
//    live vessel from a silent one: statuses are at most heartbeat + half a status period apart
//    (3.5 s at the defaults, 3 s and 1 Hz; keep that well under the shore's --silent-after, 5 s).
// The bound below holds at the evaluations, for the weighted sum of the relative deviations
// (the excitation, at weight 0.2, may move five times as far), relative to the values sent.
// Evaluations happen only at the status period: no two statuses closer than that (no Zeno
// behaviour).
#pragma once

#include <cstdint>
#include <string>

#include "usv_fdi/dds/types.hpp"

namespace usvfdi::dds_service {

struct UplinkOptions {
  bool event = true;        ///< false: every status is sent (periodic)
  double heartbeat = 3.0;   ///< [s] a status at least this often (see above)
  double tolerance = 0.08;  ///< sigma: relative deviation of the continuous values [-]
  double theta = 10.0;      ///< weight of the dynamic budget (infinity: static threshold)
  double decay = 0.9;       ///< lambda: the budget's decay per evaluation, 0 <= lambda < 1
  /// Weights of the relative deviations in |e|: the excitation moves with every manoeuvre and
  /// says only how well identification is fed, so it counts for less.
  double excitation_weight = 0.2;
};

/// Why a status was sent.
enum class UplinkReason : std::uint8_t {
  kNone = 0,    ///< not sent
  kFirst,       ///< nothing sent yet
  kPeriodic,    ///< periodic mode
  kDiscrete,    ///< a discrete field changed
  kContinuous,  ///< the continuous values moved past the dynamic threshold
  kHeartbeat,   ///< heartbeat
};
const char* to_string(UplinkReason r);

class StatusUplink {
 public:
  /// Throws std::invalid_argument on a bad option (naming it).
  explicit StatusUplink(const UplinkOptions& o = {});

  /// Offers the status of this evaluation at `now` [s, any monotonic clock]. Returns why it
  /// is to be sent (kNone: not); a status to be sent becomes the shore's copy.
  UplinkReason offer(const fdi::FdiStatus& s, double now);

  /// The weighted relative deviation |e| of s's continuous values from `sent`'s.
  double deviation(const fdi::FdiStatus& sent, const fdi::FdiStatus& s) const;
  /// Whether a discrete field differs; names the first in *what when given.
  static bool discrete_change(const fdi::FdiStatus& sent, const fdi::FdiStatus& s,
                              std::string* what = nullptr);
  /// The largest |e| event mode lets stand: sigma sqrt(1 + 1 / (theta (1 - lambda))).
  double bound() const;

  const UplinkOptions& options() const { return o_; }
  std::uint64_t offered() const { return offered_; }
  std::uint64_t sent(UplinkReason r) const { return sent_[static_cast<int>(r)]; }
  std::uint64_t sent_total() const;
  /// The discrete field that sent the last kDiscrete status.
  const std::string& last_change() const { return last_change_; }

 private:
  UplinkOptions o_;
  bool have_ = false;
  fdi::FdiStatus last_;
  double last_at_ = 0.0;
  bool have_offer_ = false;
  double last_offer_ = 0.0;
  double eta_ = 0.0;
  std::uint64_t offered_ = 0;
  std::uint64_t sent_[6] = {0, 0, 0, 0, 0, 0};
  std::string last_change_;
};

}  // namespace usvfdi::dds_service
