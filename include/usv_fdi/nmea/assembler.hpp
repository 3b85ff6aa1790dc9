// SampleAssembler: NMEA sentences arriving at their own rates -> samples on a fixed time base.
//
// Inputs (each with the time it was measured or received [s], e.g. a TAG block's c: or the
// receive clock; times must not go backwards):
//   ROT  -> r     [rad/s]  = ROT [deg/min] * pi / 10800 (same sign: > 0 bow to starboard)
//   RSA  -> delta [rad]    = the starboard (single) rudder, or the port rudder when only that is
//                            valid; sign by AssemblerConfig::rudder_sign (delta_from_rsa)
//   VBW  -> v     [m/s]    = transverse WATER speed [kn] * 1852/3600 (same sign: > 0 to
//                            starboard); needs the water status A
//   VBW  -> u     [m/s]    = longitudinal water speed (speed through the water, what
//                            core/speed.hpp wants), first choice
//   VTG  -> u     [m/s]    = speed over ground, when no valid VBW water speed is fresh (a mode
//                            indicator N, E, M or S makes it invalid)
// A value whose status is V (or whose field is empty) invalidates the quantity from then on
// without refreshing its age. Each quantity holds its latest valid value (zero-order hold),
// never longer than max_age_s; with hold_until_due, not again once its next is overdue (below).
//
// Output: a sample at every grid time g = k / rate_hz (k integer, so several assemblers share
// the same grid), holding each quantity's latest valid value measured at or before g's look
// time g + L, and NaN where that value is older than max_age_s (g - tau), or none was
// received, or (hold_until_due) it is not given again (below). NaN is how usvfdi::Sample
// marks a missing value; u NaN = not measured. A grid time where every quantity is missing is
// not emitted (no flood of empty samples after a long silence). Samples are emitted when an
// input later than g + L arrives, or by advance(t) for g <= t. L is 0 with hold_until_due
// false (the latest value at or before g), else half a grid period: each value goes to the
// grid time nearest its measurement, so that sentences sent at the grid rate, whose times lie
// on the grid (the time base starts at the first one), do not fall before or after it by
// their jitter. The ages (g - tau) may then be negative, down to -L.
//
// Held until due (hold_until_due, off by default): each sentence's period P is learned as the
// median of its last 15 intervals (once it has kMinIntervals; an interval under 2 ms is
// another line of the same datagram or a copy, not an arrival), with a tolerance
// tol = max(4.5 MAD, 2 ms) for the jitter. A sentence is not periodic, and is held up to
// max_age_s, when its intervals scatter by more than P / 4 (MAD) or fewer than 80 % of them
// are whole multiples of P (within max(tol, P / 8): a lost sentence makes an interval of 2 P;
// two senders of one sentence make short and long intervals that are neither). Three
// intervals in a row off P +- tol restart the learning from them (a new rate); a copy within
// 2 ms is not read. A value measured at tau that is already in a sample is not given again
// once its successor is overdue, g + L >= tau + P + min(tol, L / 2): a lost or late sentence is a
// gap in that quantity, not the previous value again (a repeated value is a step of the signal's
// derivative, which the observers read as a fault). A value not yet in a sample is given
// however late its successor. So sentences faster than the grid give their latest value, and
// those slower than the grid (VBW at 1 Hz on a 10 Hz grid) are held over the grid times
// between their arrivals.
// Why off by default: L is the same for every sentence, so a sentence at the grid rate whose
// times lie about L from the grid (another sender's phase than the first datagram's) falls
// before or after the boundary by its jitter: gaps there (23 % of the grid times at a phase of
// 50 +- 3 ms, in a review's simulation), where the zero-order hold has none; and a sentence
// faster than the grid leads it by up to L. The cure, a look time per sentence centred on its
// own phase, is not built. Use it where the senders' TAG times lie on the grid (one INS that
// sends ROT, RSA and VBW together, the simulator).
//
// stale(t) names the sentences that have stopped: a quantity without a valid value for more
// than max_age_s (or never received, max_age_s after the first input), with its age. (A
// quantity invalidated by a status V within max_age_s is missing in the samples but not yet
// stale: its sentence still arrives.)
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "usv_fdi/nmea/navigation.hpp"

namespace usvfdi::nmea {

struct AssemblerConfig {
  double rate_hz = 10.0;   ///< output rate (> 0)
  double max_age_s = 1.0;  ///< a value older than this is missing in the sample (> 0)
  /// Each value to the grid time nearest it, and not given again once its sentence's next is
  /// due (the period learned from the sentence's arrivals; see above); false: the latest value
  /// at or before the grid time, held up to max_age_s (zero-order hold).
  bool hold_until_due = false;
  RudderSign rudder_sign = RudderSign::kPositiveToPort;  ///< the vessel model's (b2 < 0)
};

/// One output sample; NaN marks a missing value (as in usvfdi::Sample).
struct AssembledSample {
  double t = 0.0;                                           ///< grid time [s]
  double v = std::numeric_limits<double>::quiet_NaN();      ///< sway velocity [m/s]
  double r = std::numeric_limits<double>::quiet_NaN();      ///< yaw rate [rad/s]
  double delta = std::numeric_limits<double>::quiet_NaN();  ///< rudder angle [rad]
  double u = std::numeric_limits<double>::quiet_NaN();      ///< surge speed [m/s], optional
  /// Age at t of the value used for v, r, delta, u [s] (NaN where missing).
  double age_v = std::numeric_limits<double>::quiet_NaN();
  double age_r = std::numeric_limits<double>::quiet_NaN();
  double age_delta = std::numeric_limits<double>::quiet_NaN();
  double age_u = std::numeric_limits<double>::quiet_NaN();
};

/// What SampleAssembler::add_sentence did with a sentence.
enum class InputUse {
  kUsed,  ///< ROT, RSA, VBW or VTG with a valid value, read and held
  /// ROT, RSA, VBW or VTG read, but its status says the data are not valid (V, a VTG mode
  /// N/E/M/S) or the value it feeds is empty: that quantity is invalidated from now on. A VBW
  /// is valid when its transverse water speed (v) is; an RSA when either rudder is.
  kNotValid,
  kNotAnInput,  ///< another sentence formatter (HDT, THS, ALF, ...): nothing to do
  kRefused,     ///< its typed parser refused it (see the rejection)
  kOutOfOrder,  ///< its time is not finite or earlier than the latest input's
};

struct InputResult {
  InputUse use = InputUse::kUsed;
  Rejection rejection;  ///< for kRefused
};

/// A quantity whose sentence has stopped.
struct StaleInput {
  std::string quantity;  ///< "v", "r", "delta", "u"
  std::string sentence;  ///< the sentence that feeds it: "VBW", "ROT", "RSA", "VBW/VTG"
  double age_s = 0.0;    ///< since its last valid value (or since the first input)
  bool never_received = false;
};

class SampleAssembler {
 public:
  /// Refuses (std::invalid_argument) a rate or max age that is not finite and > 0: a
  /// configuration error, the one exception of this library.
  explicit SampleAssembler(const AssemblerConfig& config);

  // Each returns false (and changes nothing) for a time that is not finite or earlier than the
  // latest input's (counted in out_of_order()).
  bool add(double t, const Rot& rot);
  bool add(double t, const Rsa& rsa);
  bool add(double t, const Vbw& vbw);
  bool add(double t, const Vtg& vtg);

  /// Parses a sentence of any formatter and adds it when it is one of the inputs. The one
  /// place that dispatches on the formatter and judges validity: the log reader
  /// (io::NmeaSampleReader) and the live UDP input both call it.
  InputResult add_sentence(double t, const Sentence& s);

  /// True for the sentences add_sentence reads (ROT, RSA, VBW, VTG; not proprietary).
  static bool is_input(const Sentence& s);

  /// Emits the samples of every grid time <= t (time passing without input).
  void advance(double t);

  /// The samples emitted since the last call, oldest first.
  std::vector<AssembledSample> take();

  /// The quantities without a valid value for more than max_age_s at time t.
  std::vector<StaleInput> stale(double t) const;

  std::size_t out_of_order() const { return out_of_order_; }

  /// The learned period of a sentence ("ROT", "RSA", "VBW", "VTG") [s]; NaN while unknown
  /// (fewer than kMinIntervals intervals) or not periodic.
  double learned_period(const std::string& sentence) const;

  static constexpr int kMinIntervals = 4;    ///< before this, a value is held up to max_age_s
  static constexpr int kKeptIntervals = 15;  ///< the intervals the period is the median of

 private:
  /// The arrivals of one sentence formatter: the period and jitter it is learned from.
  struct Arrivals {
    double last = std::numeric_limits<double>::quiet_NaN();
    double intervals[kKeptIntervals] = {};
    int count = 0;  ///< intervals kept (up to kKeptIntervals)
    int next = 0;   ///< where the next interval goes
    double period = std::numeric_limits<double>::quiet_NaN();  ///< NaN: not learned
    double tolerance = 0.0;
    int off_period = 0;  ///< intervals in a row off period +- tolerance
    /// Learns from an arrival at t; false for a copy (within 2 ms of the last arrival).
    bool arrive(double t);
  };
  enum Feed { kRot = 0, kRsa, kVbw, kVtg, kFeeds };
  struct Held {
    double value = std::numeric_limits<double>::quiet_NaN();  ///< NaN: invalidated
    double time = std::numeric_limits<double>::quiet_NaN();   ///< of the last valid value
    bool used = false;                                        ///< the value is in an emitted sample
  };
  enum Slot { kV = 0, kR, kDelta, kUWater, kUGround, kSlots };
  static Feed feed_of(Slot slot);

  bool accept_time(double t);
  void emit_before(double t, bool inclusive);
  long long first_grid_index(double t, bool after) const;
  void set(Slot slot, double t, bool valid, double value);
  /// The held value of `slot` at grid time g, or NaN (missing / too old / overdue); *age its
  /// age. A value returned is marked used.
  double at(Slot slot, double g, double* age);

  AssemblerConfig config_;
  double period_;
  double look_ahead_;  ///< hold_until_due: half a grid period, else 0
  Held held_[kSlots];
  Arrivals arrivals_[kFeeds];
  double first_input_ = std::numeric_limits<double>::quiet_NaN();
  double latest_input_ = -std::numeric_limits<double>::infinity();
  long long next_k_ = 0;  ///< the next grid index to emit
  bool started_ = false;
  std::size_t out_of_order_ = 0;
  std::vector<AssembledSample> out_;
};

}  // namespace usvfdi::nmea
