#pragma once
/// @file link_faults.hpp
/// The simulated wire between a host and a device-side model: a schedule of
/// link faults at chosen device ticks, and the queue of state reports in
/// flight with those faults applied (drop, duplicate, reorder, corrupt).
/// SimulatedTransport uses it.

#include <array>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>

#include "hapticfield/device/status.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

/// A fault the simulated link injects.
enum class LinkFault : std::uint8_t {
  drop,       ///< the state report of that tick is lost
  duplicate,  ///< the state report of that tick arrives twice
  reorder,    ///< the state report of that tick arrives after the next one
  corrupt,    ///< one byte of the state report is flipped (bad CRC)
  stall,      ///< for `ticks` ticks no report passes either way
  unplug,     ///< from that tick on every call returns disconnected
  reboot,     ///< the firmware restarts at that tick (sequence and timestamp from zero, unhomed)
  /// The state report of that tick carries encoder counts of +-2^31 with a
  /// valid CRC (a firmware bug, a bit flip before the CRC was computed).
  wild_counts,
};

/// Faults scheduled at device ticks (1-based), fixed capacity.
class LinkFaultSchedule {
 public:
  static constexpr std::size_t max_faults = 32;

  /// @param owner  named in errors
  explicit LinkFaultSchedule(const char* owner) : owner_(owner) {}

  /// Schedules a fault at tick `tick` for `ticks` ticks (unplug: for ever).
  /// @throws std::invalid_argument when more than max_faults are scheduled
  ///         or the duration is below one tick.
  void inject(LinkFault fault, std::int64_t tick, std::int64_t ticks = 1) {
    if (count_ == max_faults) throw std::invalid_argument(std::string(owner_) + ": too many faults scheduled");
    if (ticks < 1) throw std::invalid_argument(std::string(owner_) + ": fault duration must be >= 1 tick");
    faults_[count_++] = Scheduled{fault, tick, ticks};
  }

  /// True while fault f holds at tick k.
  [[nodiscard]] bool active(LinkFault f, std::int64_t k) const noexcept {
    for (std::size_t i = 0; i < count_; ++i) {
      const Scheduled& s = faults_[i];
      if (s.fault != f) continue;
      if (f == LinkFault::unplug ? k >= s.tick : (k >= s.tick && k < s.tick + s.ticks)) return true;
    }
    return false;
  }

  /// True when fault f was scheduled to start at tick k.
  [[nodiscard]] bool starts(LinkFault f, std::int64_t k) const noexcept {
    for (std::size_t i = 0; i < count_; ++i)
      if (faults_[i].fault == f && faults_[i].tick == k) return true;
    return false;
  }

 private:
  struct Scheduled {
    LinkFault fault{LinkFault::drop};
    std::int64_t tick{0};
    std::int64_t ticks{1};
  };
  const char* owner_;
  std::array<Scheduled, max_faults> faults_{};
  std::size_t count_{0};
};

/// State reports on their way to the host: a ring of fixed capacity whose
/// oldest report is overwritten when full (as a HID queue does).
class ReportQueue {
 public:
  static constexpr std::size_t capacity = 64;  ///< reports in flight

  /// Queues the report of tick k with the schedule's drop, corrupt, reorder
  /// and duplicate faults applied.
  void send(std::span<const std::uint8_t> report, const LinkFaultSchedule& faults, std::int64_t k) noexcept {
    if (faults.active(LinkFault::drop, k)) return;
    Slot slot;
    slot.size = report.size() < slot.bytes.size() ? report.size() : slot.bytes.size();
    std::memcpy(slot.bytes.data(), report.data(), slot.size);
    if (faults.active(LinkFault::wild_counts, k) && slot.size == protocol::state_size) {
      const std::span<std::uint8_t> b(slot.bytes.data(), slot.size);
      protocol::detail::put_i32(b, protocol::offset::state::encoder, INT32_MAX);
      protocol::detail::put_i32(b, protocol::offset::state::encoder + 4, INT32_MIN);
      protocol::detail::put_i32(b, protocol::offset::state::encoder + 8, INT32_MAX);
      protocol::detail::seal(b, slot.size);
    }
    if (faults.active(LinkFault::corrupt, k)) slot.bytes[protocol::offset::state::encoder] ^= 0x5A;
    if (faults.active(LinkFault::reorder, k)) {
      held_ = slot;
      holding_ = true;
      return;
    }
    push(slot);
    if (faults.active(LinkFault::duplicate, k)) push(slot);
    if (holding_) {
      push(held_);
      holding_ = false;
    }
  }

  /// The oldest report: ok, no_data when empty, short_report when buffer is too small.
  Status receive(std::span<std::uint8_t> buffer, std::size_t& size) noexcept {
    if (count_ == 0) return Status::no_data;
    const Slot& s = queue_[head_];
    if (buffer.size() < s.size) return Status::short_report;
    std::memcpy(buffer.data(), s.bytes.data(), s.size);
    size = s.size;
    head_ = (head_ + 1) % capacity;
    --count_;
    return Status::ok;
  }

  /// Reports overwritten because the host read too slowly.
  [[nodiscard]] std::uint64_t overflows() const noexcept { return overflows_; }

 private:
  struct Slot {
    std::array<std::uint8_t, protocol::max_report_size> bytes{};
    std::size_t size{0};
  };

  void push(const Slot& s) noexcept {
    if (count_ == capacity) {
      head_ = (head_ + 1) % capacity;
      --count_;
      ++overflows_;
    }
    queue_[(head_ + count_) % capacity] = s;
    ++count_;
  }

  std::array<Slot, capacity> queue_{};
  std::size_t head_{0};
  std::size_t count_{0};
  Slot held_{};
  bool holding_{false};
  std::uint64_t overflows_{0};
};

}  // namespace hapticfield
