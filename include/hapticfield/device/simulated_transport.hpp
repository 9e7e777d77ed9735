#pragma once
/// @file simulated_transport.hpp
/// SimulatedTransport: connects a host to a SimulatedArm through report
/// bytes, on a time source (a virtual clock in tests), with fault injection
/// at chosen firmware ticks: drop, duplicate, reorder, corrupt (bad CRC),
/// stall (nothing passes either way) and unplug.

#include <array>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <utility>

#include "hapticfield/device/protocol.hpp"
#include "hapticfield/device/simulated_arm.hpp"
#include "hapticfield/device/transport.hpp"

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
};

class SimulatedTransport final : public Transport {
 public:
  static constexpr std::size_t queue_capacity = 64;  ///< queued input reports
  static constexpr std::size_t max_faults = 32;

  /// @param arm  the arm (outlives the transport)
  /// @param now  time source [ns]; firmware tick k runs at start + (k + phase) / rate
  /// @param phase  offset of the firmware ticks within a period [periods, 0..1)
  SimulatedTransport(SimulatedArm& arm, TimeSource now, double phase = 0.5) : arm_(&arm), now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("SimulatedTransport: a time source is required");
    if (!(phase >= 0.0 && phase < 1.0))
      throw std::invalid_argument("SimulatedTransport: phase must be in [0, 1) [periods]");
    period_ns_ = static_cast<std::int64_t>(1e9 / arm.config().rate + 0.5);
    start_ns_ = now_() + static_cast<std::int64_t>(phase * static_cast<double>(period_ns_));
  }

  /// Schedules a fault at firmware tick `tick` (1-based, as SimulatedArm::ticks()).
  /// @throws std::invalid_argument when more than max_faults are scheduled.
  void inject(LinkFault fault, std::int64_t tick, std::int64_t ticks = 1) {
    if (fault_count_ == max_faults) throw std::invalid_argument("SimulatedTransport: too many faults scheduled");
    if (ticks < 1) throw std::invalid_argument("SimulatedTransport: fault duration must be >= 1 tick");
    faults_[fault_count_++] = Scheduled{fault, tick, ticks};
  }

  /// Advances the arm to the time source's now, queueing its reports.
  void advance() noexcept {
    const std::int64_t now = now_();
    while (start_ns_ + (arm_->ticks()) * period_ns_ <= now) {
      arm_->tick();
      const std::int64_t k = arm_->ticks();
      if (starts(LinkFault::reboot, k)) arm_->reboot();
      if (active(LinkFault::unplug, k)) unplugged_ = true;
      if (unplugged_ || active(LinkFault::stall, k)) {
        stalled_ = !unplugged_;
        continue;
      }
      stalled_ = false;
      Slot slot;
      slot.size = protocol::encode(arm_->report(), slot.bytes);
      if (active(LinkFault::drop, k)) continue;
      if (active(LinkFault::corrupt, k)) slot.bytes[protocol::offset::state::encoder] ^= 0x5A;
      if (active(LinkFault::reorder, k)) {
        held_ = slot;
        holding_ = true;
        continue;
      }
      push(slot);
      if (active(LinkFault::duplicate, k)) push(slot);
      if (holding_) {
        push(held_);
        holding_ = false;
      }
    }
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int /*timeout_us*/) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    if (count_ == 0) return Status::no_data;
    const Slot& s = queue_[head_];
    if (buffer.size() < s.size) return Status::short_report;
    std::memcpy(buffer.data(), s.bytes.data(), s.size);
    size = s.size;
    head_ = (head_ + 1) % queue_capacity;
    --count_;
    return Status::ok;
  }

  Status write(std::span<const std::uint8_t> report) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    ++writes_;
    if (stalled_) return Status::ok;  // lost on the wire; the host cannot tell
    arm_->receive(report);
    return Status::ok;
  }

  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    return arm_->get_feature(buffer, size);
  }

  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    return arm_->send_feature(report);
  }

  [[nodiscard]] SimulatedArm& arm() noexcept { return *arm_; }
  [[nodiscard]] bool unplugged() const noexcept { return unplugged_; }
  [[nodiscard]] std::uint64_t overflows() const noexcept { return overflows_; }
  [[nodiscard]] std::uint64_t writes() const noexcept { return writes_; }

 private:
  struct Slot {
    std::array<std::uint8_t, protocol::max_report_size> bytes{};
    std::size_t size{0};
  };
  struct Scheduled {
    LinkFault fault{LinkFault::drop};
    std::int64_t tick{0};
    std::int64_t ticks{1};
  };

  [[nodiscard]] bool active(LinkFault f, std::int64_t k) const noexcept {
    for (std::size_t i = 0; i < fault_count_; ++i) {
      const Scheduled& s = faults_[i];
      if (s.fault != f) continue;
      if (f == LinkFault::unplug ? k >= s.tick : (k >= s.tick && k < s.tick + s.ticks)) return true;
    }
    return false;
  }

  [[nodiscard]] bool starts(LinkFault f, std::int64_t k) const noexcept {
    for (std::size_t i = 0; i < fault_count_; ++i)
      if (faults_[i].fault == f && faults_[i].tick == k) return true;
    return false;
  }

  void push(const Slot& s) noexcept {
    if (count_ == queue_capacity) {  // the oldest report is overwritten, as a HID queue does
      head_ = (head_ + 1) % queue_capacity;
      --count_;
      ++overflows_;
    }
    queue_[(head_ + count_) % queue_capacity] = s;
    ++count_;
  }

  SimulatedArm* arm_;
  TimeSource now_;
  std::int64_t period_ns_{1'000'000};
  std::int64_t start_ns_{0};
  std::array<Slot, queue_capacity> queue_{};
  std::size_t head_{0};
  std::size_t count_{0};
  Slot held_{};
  bool holding_{false};
  std::array<Scheduled, max_faults> faults_{};
  std::size_t fault_count_{0};
  std::uint64_t overflows_{0};
  std::uint64_t writes_{0};
  bool unplugged_{false};
  bool stalled_{false};
};

}  // namespace hapticfield
