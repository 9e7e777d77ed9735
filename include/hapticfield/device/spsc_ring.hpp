#pragma once
/// @file spsc_ring.hpp
/// A fixed-size single-producer single-consumer ring of reports, lock-free
/// and allocation-free: how the HID I/O thread hands reports to the servo
/// thread and back.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "hapticfield/device/protocol.hpp"

namespace hapticfield::detail {

/// Ring of N reports of at most 64 bytes (N a power of two).
template <std::size_t N>
requires(N >= 2 && (N & (N - 1)) == 0) class ReportRing {
 public:
  /// Producer: false when full (the report is not queued).
  bool push(std::span<const std::uint8_t> report) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == N) return false;
    Slot& s = slots_[tail % N];
    s.size = report.size() < s.bytes.size() ? report.size() : s.bytes.size();
    std::memcpy(s.bytes.data(), report.data(), s.size);
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  /// Consumer: false when empty.
  bool pop(std::span<std::uint8_t> out, std::size_t& size) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return false;
    const Slot& s = slots_[head % N];
    size = s.size < out.size() ? s.size : out.size();
    std::memcpy(out.data(), s.bytes.data(), size);
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

 private:
  struct Slot {
    std::array<std::uint8_t, protocol::max_report_size> bytes{};
    std::size_t size{0};
  };
  std::array<Slot, N> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace hapticfield::detail
