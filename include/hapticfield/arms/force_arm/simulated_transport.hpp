#pragma once
/// @file simulated_transport.hpp
/// SimulatedTransport: connects a host (ForceArm) to a SimulatedArm, the
/// reference firmware core on the simulated mechanics, through report
/// bytes, on a time source (a virtual clock in tests). Link faults are made
/// at chosen firmware ticks on the firmware side: the firmware skips,
/// repeats, holds back or corrupts its state report, the wire stalls both
/// ways (the firmware's own watchdog then trips), the cable is pulled, the
/// firmware reboots; e-stop and driver flags are board inputs of the arm.

#include <cstdint>
#include <span>
#include <stdexcept>
#include <utility>

#include "hapticfield/arms/force_arm/link_faults.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

class SimulatedTransport final : public Transport {
 public:
  static constexpr std::size_t queue_capacity = ReportQueue::capacity;  ///< state reports in flight
  static constexpr std::size_t max_faults = LinkFaultSchedule::max_faults;

  /// @param arm  the arm (outlives the transport)
  /// @param now  time source [ns]; firmware tick k runs at start + (k - 1 + phase) periods
  /// @param phase  offset of the firmware ticks within a period [periods, 0..1)
  SimulatedTransport(SimulatedArm& arm, TimeSource now, double phase = 0.5) : arm_(&arm), now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("SimulatedTransport: a time source is required");
    if (!(phase >= 0.0 && phase < 1.0))
      throw std::invalid_argument("SimulatedTransport: phase must be in [0, 1) [periods]");
    period_ns_ = static_cast<std::int64_t>(arm.period_us()) * 1000;
    start_ns_ = now_() + static_cast<std::int64_t>(phase * static_cast<double>(period_ns_));
  }

  /// Schedules a fault at firmware tick `tick` (1-based, as SimulatedArm::ticks()) for `ticks` ticks.
  /// @throws std::invalid_argument when more than max_faults are scheduled.
  void inject(LinkFault fault, std::int64_t tick, std::int64_t ticks = 1) { faults_.inject(fault, tick, ticks); }

  /// Runs the firmware up to the time source's now, queueing its reports.
  void advance() noexcept {
    const std::int64_t now = now_();
    while (start_ns_ + arm_->ticks() * period_ns_ <= now) {
      const std::int64_t k = arm_->ticks() + 1;
      if (faults_.starts(LinkFault::reboot, k)) arm_->reboot();
      if (faults_.active(LinkFault::unplug, k)) unplugged_ = true;
      stalled_ = !unplugged_ && faults_.active(LinkFault::stall, k);
      arm_->tick();
      if (unplugged_ || stalled_) continue;
      queue_.send(arm_->report_bytes(), faults_, k);  // a dropped report uses its sequence too
    }
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int /*timeout_us*/) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    return queue_.receive(buffer, size);
  }

  Status write(std::span<const std::uint8_t> report) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    ++writes_;
    if (!stalled_) arm_->receive(report);  // else lost on the wire; the host cannot tell
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
  [[nodiscard]] std::uint64_t overflows() const noexcept { return queue_.overflows(); }
  [[nodiscard]] std::uint64_t writes() const noexcept { return writes_; }

 private:
  SimulatedArm* arm_;
  TimeSource now_;
  std::int64_t period_ns_{1'000'000};
  std::int64_t start_ns_{0};
  ReportQueue queue_;
  LinkFaultSchedule faults_{"SimulatedTransport"};
  std::uint64_t writes_{0};
  bool unplugged_{false};
  bool stalled_{false};
};

}  // namespace hapticfield
