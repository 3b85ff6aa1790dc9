// Bounded thread-safe queue with an explicit overflow policy (after okvis' threadsafe queue).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>

namespace usvfdi::pipeline {

enum class OverflowPolicy : std::uint8_t {
  kDropOldest = 0,  ///< a full queue discards its oldest element (inputs: newest data wins)
  kDropNewest,      ///< a full queue refuses the new element
};

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity, OverflowPolicy policy = OverflowPolicy::kDropOldest)
      : capacity_(capacity == 0 ? 1 : capacity), policy_(policy) {}

  /// Never blocks. Returns false when the element was not queued (shut down, or refused by
  /// kDropNewest); every discarded element is counted in dropped().
  bool push(T value) {
    {
      std::lock_guard<std::mutex> lock(m_);
      if (shutdown_) return false;
      if (q_.size() >= capacity_) {
        ++dropped_;
        if (policy_ == OverflowPolicy::kDropNewest) return false;
        q_.pop_front();
      }
      q_.push_back(std::move(value));
    }
    cv_.notify_one();
    return true;
  }

  /// Waits for an element; returns false once the queue is shut down and empty.
  bool pop(T* out) {
    std::unique_lock<std::mutex> lock(m_);
    cv_.wait(lock, [&] { return shutdown_ || !q_.empty(); });
    if (q_.empty()) return false;
    *out = std::move(q_.front());
    q_.pop_front();
    return true;
  }

  enum class PopResult : std::uint8_t { kValue, kTimeout, kShutdown };
  /// Waits at most timeout for an element.
  template <typename Rep, typename Period>
  PopResult pop_for(T* out, std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock<std::mutex> lock(m_);
    if (!cv_.wait_for(lock, timeout, [&] { return shutdown_ || !q_.empty(); })) {
      return PopResult::kTimeout;
    }
    if (q_.empty()) return PopResult::kShutdown;
    *out = std::move(q_.front());
    q_.pop_front();
    return PopResult::kValue;
  }

  /// Wakes every waiter; pop() drains what is left, then returns false.
  void shutdown() {
    {
      std::lock_guard<std::mutex> lock(m_);
      shutdown_ = true;
    }
    cv_.notify_all();
  }

  std::size_t size() const {
    std::lock_guard<std::mutex> lock(m_);
    return q_.size();
  }
  std::uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(m_);
    return dropped_;
  }
  std::size_t capacity() const { return capacity_; }

 private:
  const std::size_t capacity_;
  const OverflowPolicy policy_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<T> q_;
  std::uint64_t dropped_ = 0;
  bool shutdown_ = false;
};

}  // namespace usvfdi::pipeline
