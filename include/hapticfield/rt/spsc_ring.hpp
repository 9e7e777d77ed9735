#pragma once
/// @file spsc_ring.hpp
/// SpscRing<T, N>: a fixed-size single-producer single-consumer ring of
/// trivially copyable values, lock-free and allocation-free. try_push and
/// try_pop never wait: a full ring refuses the value (the producer counts
/// it), an empty ring returns nothing. Standard library only (the ground
/// floor: any room may use it).

#include <array>
#include <atomic>
#include <cstddef>
#include <optional>
#include <type_traits>

namespace hapticfield::rt {

/// Ring of N values of T (N a power of two). One thread pushes, one pops.
template <class T, std::size_t N>
requires(N >= 2 && (N & (N - 1)) == 0 && std::is_trivially_copyable_v<T>) class SpscRing {
 public:
  /// Producer: false when the ring is full (the value is not queued; the
  /// ring counts it in rejected()).
  bool try_push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == N) {
      rejected_.store(rejected_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      return false;
    }
    slots_[tail % N] = value;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  /// Consumer: the oldest value, or nothing when the ring is empty.
  std::optional<T> try_pop() noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return std::nullopt;
    const T value = slots_[head % N];
    head_.store(head + 1, std::memory_order_release);
    return value;
  }
  /// Values queued now (exact on either thread for its own side; a snapshot otherwise).
  [[nodiscard]] std::size_t size() const noexcept {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }
  [[nodiscard]] static constexpr std::size_t capacity() noexcept { return N; }
  /// Values the producer could not queue because the ring was full (readable from any thread).
  [[nodiscard]] std::size_t rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }

 private:
  std::array<T, N> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::size_t> rejected_{0};
};

}  // namespace hapticfield::rt
