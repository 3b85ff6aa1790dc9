// The identification's consistency guard: the Kreisselmeier memory built from judged
// segments (docs/design.md section 8.1).
//
// The regression m = A q uses the measured y, so a sensor fault corrupts the memory before
// anything downstream can see it. The memory is a sum of segments of half a window
// (5 / eps1 s); every sample lies in two Hann-tapered windows half a window apart, and a
// segment enters the memory only when both windows that cover it agree with the memory
// (an equation-error statistic, chi-square with 4 degrees of freedom on healthy data).
// Accepted windows are judged again as the memory grows, and before convergence the recent
// data as a whole are compared with the memory (a Wald test), which is rebuilt from them
// when they agree among themselves and contradict it.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "usv_fdi/core/types.hpp"

namespace usvfdi {

/// A Kreisselmeier memory (weights e^{-lambda (t - s)}), or one segment of it: the
/// extension Phi = int z q^T, Y = int z m^T (Y = Phi A^T on noise-free data) for the
/// instruments z, and the least-squares pair of the regressor itself (z = q).
struct KreisselmeierMemory {
  Mat2 Phi = Mat2::Zero();     ///< int z q^T (the paper's Phi)
  Mat2 Y = Mat2::Zero();       ///< int z m^T
  Mat2 Phi_ls = Mat2::Zero();  ///< int q q^T (least squares; also the scale of q)
  Mat2 Y_ls = Mat2::Zero();    ///< int q m^T
  Mat2 Zw2 = Mat2::Zero();     ///< int w^2 z z^T: Cov(row i of A^) = s_i Phi^-1 Zw2 Phi^-T
  Vec2 Szz = Vec2::Zero();     ///< diag int z z^T
  double W2 = 0.0;             ///< the sum of squared weights [s]
  double decay = 1.0;          ///< a segment's own decay over its length, exp(-lambda len)
  double len = 0.0;            ///< a segment's length [s]

  /// One sample: decay by E, add dt times the products.
  void step(double E, double dt, const Vec2& q, const Vec2& m, const Vec2& z);
  /// this <- this decayed over the segment's length, plus the segment.
  void append(const KreisselmeierMemory& seg);
  /// this <- this minus the segment, decayed by E since it was appended.
  void remove(const KreisselmeierMemory& seg, double E);
  /// The estimate A^T = Phi^-1 Y (column i: row i of A); false when Phi is singular.
  bool estimate(Mat2* At) const;
};

/// One Hann-tapered window of data (h: the taper): the batch the guard judges, and a batch
/// of the noise level and the standard errors.
struct GuardWindow {
  Mat2 Phi = Mat2::Zero();  ///< int h z q^T
  Mat2 Y = Mat2::Zero();    ///< int h z m^T
  Mat2 Z = Mat2::Zero();    ///< int h^2 z z^T
  double H2 = 0.0;          ///< int h^2 dt
  double T = 0.0;           ///< time since the window began [s]
  int segs = 0;             ///< segments closed since it began
  bool active = false;
  std::uint64_t seg0 = 0, seg1 = 0;  ///< the segments it covers
  double clock = 0.0;                ///< the memory's clock when it was judged
  double t_end = 0.0;                ///< time it was judged [s]
  bool accepted = false;             ///< passed, and no covered segment was rejected

  /// The equation error's statistic per row under the estimate A^T: r_i^T Z^-1 r_i with r =
  /// Y - Phi A^T (chi-square with 2 degrees of freedom times s_i on healthy data); false
  /// when Z is not positive definite.
  bool chi2(const Mat2& At, Vec2* q) const;
};

/// What the guard reports after each sample (Estimate's fields of the same names).
struct GuardReport {
  bool consistent = true;              ///< the last judged window agreed with the memory
  double consistency = 0.0;            ///< its statistic (chi-square, 4 dof when healthy)
  double inconsistent_time = 0.0;      ///< length of the current run of rejected data [s]
  std::uint64_t rejected_windows = 0;  ///< windows kept out of the memory
  double rejected_time = 0.0;          ///< data kept out of the memory [s]
  std::uint64_t removed_windows = 0;   ///< windows taken out of the memory later
  std::uint64_t resets = 0;            ///< memory rebuilt from the recent data
  double memory_mismatch = 0.0;        ///< Wald statistic of memory against recent data
};

class ConsistencyGuard {
 public:
  struct Settings {
    bool enabled = true;         ///< identification.guard (off: every segment enters)
    double lambda = 0.005;       ///< forgetting rate [1/s]
    double eps1 = 1.0;           ///< F1's bandwidth: windows of kBatchLength / eps1 [s]
    double threshold = 40.0;     ///< identification.guard_threshold
    double min_shift = 1e-3;     ///< identification.guard_min_shift
    double recent_time = 60;     ///< identification.guard_recent_time [s]
    double settle_floor = 1e-4;  ///< floor of the relative shift's denominator
  };
  /// What one sample changed.
  struct Change {
    bool memory = false;     ///< the memory changed (the mixing and standard errors follow)
    bool unsettled = false;  ///< data were rejected or removed: settling starts again
    bool reset = false;      ///< the memory was rebuilt from the recent data
  };

  static constexpr int kWindows = 128;         ///< windows kept (~ the memory's length)
  static constexpr int kMinBatches = 3;        ///< no noise level from fewer windows
  static constexpr int kMinJudge = 6;          ///< no verdict from fewer windows
  static constexpr double kBatchLength = 5.0;  ///< window length x eps1 [-]

  explicit ConsistencyGuard(const Settings& s);

  /// A filter restart: a window must not straddle it, and the data no window has judged
  /// yet are dropped.
  void restart();
  /// One sample's regression pair and instruments. converged and supervised: see
  /// Identifier::set_supervised (after convergence, a lasting inconsistency that a
  /// supervising detector does not flag is let in).
  Change add(double t, double dt, const Vec2& q, const Vec2& m, const Vec2& z, bool converged,
             bool supervised);

  /// The committed memory (judged segments only).
  const KreisselmeierMemory& memory() const { return mem_; }
  /// The least-squares pair with the data still waiting for a verdict.
  void least_squares_with_pending(Mat2* Phi_ls, Mat2* Y_ls) const;
  /// Judged windows, oldest first.
  const std::deque<GuardWindow>& windows() const { return windows_; }
  int accepted_windows() const;
  /// Whether no data are being kept out and the guard can judge (always when disabled).
  bool consistent() const;
  const GuardReport& report() const { return report_; }

 private:
  struct Pending {
    KreisselmeierMemory mem;
    std::uint64_t id = 0;
    int needed = 2;  ///< verdicts needed (1 for the first segment after a restart)
    int votes = 0;
    bool bad = false;
  };
  struct Stored {
    KreisselmeierMemory mem;
    std::uint64_t id = ~std::uint64_t{0};
    double clock = 0.0;  ///< the memory's clock when it was committed
    bool in = false;     ///< part of the memory
  };
  static constexpr int kStored = 176;  ///< closed segments kept (> 2 kWindows: 440 s)

  bool close_segment(double t, bool converged, bool supervised, Change* c);
  bool judge(const GuardWindow& w, Change* c);
  bool rejudge(Change* c);
  bool check_memory(double t);
  void update_noise(const Mat2& At);
  void remove_segment(std::uint64_t id);
  bool in_memory(std::uint64_t id) const;
  bool final_segment(std::uint64_t id) const;
  /// The largest shift D = M^-1 r of an a_n, relative to max(|a_n|, settle_floor).
  double relative_shift(const Mat2& M, const Mat2& r, const Mat2& At) const;

  Settings s_;
  KreisselmeierMemory mem_;  ///< the memory the estimate comes from (committed segments)
  double clock_ = 0.0;       ///< the memory's clock: committed data so far [s]
  KreisselmeierMemory seg_;  ///< the segment being summed
  std::uint64_t next_seg_ = 0;
  std::deque<Pending> pending_;
  bool first_segment_ = true;        ///< the segment being summed is the first since a restart
  std::vector<Stored> stored_;       ///< ring by id, accepted or rejected
  std::array<GuardWindow, 2> open_;  ///< the two windows being summed
  std::deque<GuardWindow> windows_;  ///< judged windows, oldest first
  double inconsistent_run_ = 0.0;    ///< rejected data since the last accepted segment [s]
  bool suspended_ = false;           ///< after recent_time past convergence
  Vec2 noise_ = Vec2::Zero();        ///< robust noise level s_i per row (0: not known)
  std::vector<Vec2> chi2_;           ///< update_noise's statistic of each window (NaN: none)
  std::vector<double> scratch_[2];   ///< update_noise's values of each row (kept: no allocation)
  std::uint64_t gen_ = 0;  ///< counts the changes of windows_ (which, or which are accepted)
  std::uint64_t noise_gen_ = ~std::uint64_t{0};  ///< gen_ when noise_ and chi2_ were computed
  Mat2 noise_At_ = Mat2::Zero();                 ///< ... and under which A^T
  mutable std::uint64_t accepted_gen_ = ~std::uint64_t{0};  ///< gen_ of accepted_n_
  mutable int accepted_n_ = 0;                              ///< accepted windows
  GuardReport report_;
};

}  // namespace usvfdi
