// Wait-free hand-offs between one producer thread and one consumer thread.
//
// LatestValue<T>: the newest value wins (triple buffer). The producer never
// waits and never fails; the consumer sees the latest complete value or none
// since its last look. For state that only matters when fresh (rope state to
// the publisher and the renderer).
//
// SpscQueue<T, N>: a bounded ring. try_push() fails when full (the caller
// counts the drop) and never blocks. For events that must arrive in order
// (commands into the real-time thread).
//
// Both: one producer thread and one consumer thread, no allocation after
// construction, no locks, no system calls; every call is O(1) plus one copy
// of T. Real-time safe on either side. T must be trivially copyable.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace visvol {

// Keeps hot indices on separate cache lines (no false sharing between sides).
inline constexpr std::size_t kCacheLine = 64;

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue holds plain data");

 public:
  LatestValue() = default;
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  // Producer: the slot to fill, then publish() it. The slot is the
  // producer's alone until publish().
  T& back() { return slots_[back_]; }
  void publish() {
    const unsigned prev = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = prev & kIndex;
  }
  void write(const T& value) {
    back() = value;
    publish();
  }

  // Consumer: whether a value was published since the last take() (a peek:
  // take() still returns it).
  bool fresh() const { return (middle_.load(std::memory_order_acquire) & kFresh) != 0; }

  // Consumer: the newest published value, or nullptr when nothing new was
  // published since the last take(). The pointer stays valid until the next
  // take().
  const T* take() {
    if (!fresh()) return nullptr;
    const unsigned prev = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = prev & kIndex;
    return &slots_[front_];
  }

 private:
  static constexpr unsigned kIndex = 3u;
  static constexpr unsigned kFresh = 4u;

  std::array<T, 3> slots_{};
  alignas(kCacheLine) unsigned back_ = 0;   // producer only
  alignas(kCacheLine) unsigned front_ = 1;  // consumer only
  alignas(kCacheLine) std::atomic<unsigned> middle_{2};
};

template <typename T, std::size_t N>
class SpscQueue {
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds plain data");
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity must be a power of two");

 public:
  SpscQueue() = default;
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  static constexpr std::size_t capacity() { return N; }

  // Producer: false when full (nothing is written; count the drop).
  bool try_push(const T& value) {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= N) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= N) return false;
    }
    slots_[head & (N - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer: false when empty.
  bool try_pop(T& out) {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & (N - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Either side: an estimate (exact when the other side is idle).
  std::size_t size_approx() const {
    return static_cast<std::size_t>(head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire));
  }

 private:
  std::array<T, N> slots_{};
  alignas(kCacheLine) std::atomic<std::uint64_t> head_{0};  // next slot to write
  std::uint64_t tail_cache_ = 0;                            // producer's view of tail_
  alignas(kCacheLine) std::atomic<std::uint64_t> tail_{0};  // next slot to read
  std::uint64_t head_cache_ = 0;                            // consumer's view of head_
};

}  // namespace visvol
