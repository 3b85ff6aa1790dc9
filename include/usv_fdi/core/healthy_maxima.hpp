// The largest values a statistic took on healthy data over a sliding history, kept as the
// maxima of blocks of fixed length (constant memory, O(1) per sample): a threshold set at
// a margin above them follows the hull, the sea and the manoeuvres of the recent past.
// docs/design.md sections 8.3 and 8.6.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace usvfdi {

template <int N>
class HealthyMaxima {
 public:
  /// block: length of a block [s]; history: how far back the maxima reach [s] (>= block).
  HealthyMaxima(double block, double history)
      : block_(block),
        blocks_(static_cast<std::size_t>(std::max(1.0, std::ceil(history / block)))),
        full_log_(std::log1p(this->history())) {}

  /// One healthy sample of the N statistics at time t.
  void add(double t, const double (&x)[N]) {
    if (std::isnan(start_)) start_ = t;
    if (!std::isnan(last_) && t > last_) {
      covered_ = std::min(covered_ + std::min(t - last_, block_), history());
    }
    last_ = t;
    if (t - start_ >= block_) close(t);
    for (int i = 0; i < N; ++i) current_[i] = std::max(current_[i], x[i]);
    seen_ = true;
  }
  /// The largest value of statistic i over the history (0 before any sample).
  double max(int i) const { return std::max(done_[i], current_[i]); }
  /// ... scaled up while the history is not yet full: the largest of a few minutes of data
  /// underestimates that of the whole history. For a statistic whose tail is exponential
  /// (a chi-square) the largest of n independent values grows like ln n, so the maximum of
  /// the time covered so far is scaled by ln(1 + history / tau) / ln(1 + covered / tau),
  /// tau = 1 s (about the decorrelation time of a windowed statistic).
  double extrapolated_max(int i) const {
    // The logarithms are kept: the thresholds ask for them on every sample.
    if (!(covered_ == seen_for_)) {
      seen_for_ = covered_;
      seen_log_ = std::log1p(std::max(covered_, 1.0));
    }
    return max(i) * full_log_ / seen_log_;
  }
  /// Healthy time the maxima cover [s] (at most the history).
  double covered() const { return covered_; }
  double history() const { return block_ * static_cast<double>(blocks_.size()); }
  bool empty() const { return !seen_; }
  void clear() { *this = HealthyMaxima(block_, history()); }

 private:
  void close(double t) {
    blocks_[next_] = current_;
    next_ = (next_ + 1) % blocks_.size();
    for (int i = 0; i < N; ++i) {
      current_[i] = 0.0;
      done_[i] = 0.0;
      for (const Block& b : blocks_) done_[i] = std::max(done_[i], b.v[i]);
    }
    start_ = t;
  }
  struct Block {
    double v[N] = {};
    Block& operator=(const double (&x)[N]) {
      std::copy(x, x + N, v);
      return *this;
    }
  };
  double block_;
  std::vector<Block> blocks_;
  std::size_t next_ = 0;
  double start_ = NAN, last_ = NAN;
  double covered_ = 0.0;
  double current_[N] = {};
  double done_[N] = {};
  bool seen_ = false;
  double full_log_;                ///< ln(1 + history)
  mutable double seen_for_ = NAN;  ///< the covered time seen_log_ is of
  mutable double seen_log_ = 0.0;  ///< ln(1 + max(covered, 1))
};

}  // namespace usvfdi
