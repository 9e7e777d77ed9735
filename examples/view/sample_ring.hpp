#pragma once
/// @file sample_ring.hpp
/// What the servo thread tells the viewer each tick: a fixed-size
/// single-producer single-consumer ring of samples, lock-free and
/// allocation-free on the producer side. A full ring drops the newest sample
/// (the viewer is behind); the servo thread never waits.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::view {

/// One servo tick as the viewer draws it.
struct ViewSample {
  double t{0.0};          ///< loop time [s]
  glm::dvec2 pixel{0.0};  ///< probe in the picture [px] (x right, y down)
  glm::dvec3 force{0.0};  ///< commanded force, device frame [N]
};

/// SPSC ring of N samples (N a power of two) of type Sample.
template <std::size_t N, class Sample = ViewSample>
requires(N >= 2 && (N & (N - 1)) == 0) class SampleRing {
 public:
  /// Producer (servo thread): false when full (the sample is dropped).
  bool push(const Sample& s) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == N) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[tail % N] = s;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer (viewer thread): false when empty.
  bool pop(Sample& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return false;
    out = slots_[head % N];
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Samples dropped because the ring was full.
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::array<Sample, N> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace hapticfield::view
