#pragma once
/// @file firmware_loopback.hpp
/// FirmwareLoopback: a Transport that connects a host (ForceArm) to the
/// reference firmware core (firmware/core.hpp) running on the simulated
/// arm's mechanics (ArmPlant), on a time source (a virtual clock in tests).
/// Link faults are produced on the firmware side: the firmware skips,
/// repeats, holds back or corrupts its state report, the wire stalls both
/// ways (the firmware's own watchdog then trips), the cable is pulled, the
/// firmware reboots; e-stop and driver flags are board inputs.

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/vec3.hpp>

#include "hapticfield/arms/force_arm/link_faults.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/firmware/core.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

/// The firmware configuration that describes a simulated arm (geometry,
/// limits, rate, homing), with the given watchdog [us].
/// @throws std::invalid_argument when the result fails FirmwareConfig::check().
[[nodiscard]] inline firmware::FirmwareConfig firmware_config_for(const SimulatedArmConfig& arm,
                                                                  std::uint16_t watchdog_us = 5000) {
  firmware::FirmwareConfig f;
  for (std::size_t i = 0; i < 3; ++i) {
    const int k = static_cast<int>(i);
    f.counts_per_rev[i] = static_cast<std::uint32_t>(arm.kinematics.counts_per_rev[i]);
    f.max_torque_mnm[i] = static_cast<std::uint16_t>(std::lround(arm.kinematics.max_torque[k] * 1e3));
    f.q_min_mrad[i] = static_cast<std::int16_t>(std::lround(arm.kinematics.q_min[k] * 1e3));
    f.q_max_mrad[i] = static_cast<std::int16_t>(std::lround(arm.kinematics.q_max[k] * 1e3));
  }
  f.torque_unit_unm = static_cast<std::uint16_t>(std::lround(arm.torque_unit * 1e6));
  f.l1_um = static_cast<std::uint32_t>(std::lround(arm.kinematics.l1 * 1e6));
  f.l2_um = static_cast<std::uint32_t>(std::lround(arm.kinematics.l2 * 1e6));
  f.max_force_mn = static_cast<std::uint16_t>(std::lround(arm.max_force * 1e3));
  f.continuous_force_mn = static_cast<std::uint16_t>(std::lround(arm.continuous_force * 1e3));
  f.period_us = static_cast<std::uint32_t>(std::lround(1e6 / arm.rate));
  f.watchdog_us = watchdog_us;
  f.homing_ticks = static_cast<std::uint16_t>(arm.homing_ticks);
  if (const char* e = f.check()) throw std::invalid_argument(std::string("FirmwareConfig: ") + e);
  return f;
}

/// The firmware core on the simulated mechanics: one firmware period per
/// step(), with the board inputs a real board would measure.
class FirmwareArm {
 public:
  static constexpr double home_tolerance = 0.02;  ///< the dock sensor sees the arm at home within this [rad]

  /// @throws std::invalid_argument for a bad arm or firmware configuration.
  explicit FirmwareArm(const SimulatedArmConfig& arm = {}, std::uint16_t watchdog_us = 5000)
      : FirmwareArm(arm, firmware_config_for(arm, watchdog_us)) {}
  FirmwareArm(const SimulatedArmConfig& arm, const firmware::FirmwareConfig& config) : plant_(arm), core_(config) {
    if (const char* e = config.check()) throw std::invalid_argument(std::string("FirmwareConfig: ") + e);
    period_us_ = config.period_us;
  }

  /// One firmware period: board inputs from the mechanics, core tick, the
  /// limited torques drive the mechanics.
  void step() noexcept {
    ++ticks_;
    firmware::BoardInputs in;
    in.now_us = static_cast<std::uint32_t>((static_cast<std::uint64_t>(ticks_) * period_us_) & 0xFFFFFFFFu);
    const auto counts = plant_.kinematics().counts(plant_.q());
    for (std::size_t i = 0; i < 3; ++i)
      in.encoder[i] = counts[i] + plant_.config().unhomed_offset[i];  // counters start at an arbitrary value
    in.at_home = true;  // no dock sensor: homing takes the pose it finds as home
    for (int i = 0; i < 3 && dock_sensor_; ++i)
      if (std::fabs(plant_.q()[i] - plant_.config().initial_q[i]) > home_tolerance) in.at_home = false;
    in.buttons = buttons_;
    in.estop = estop_;
    in.over_current = over_current_;
    in.over_temperature = over_temperature_;
    over_current_ = over_temperature_ = false;  // the driver pulses its flag; the core latches it
    const firmware::MotorOutputs& out = core_.tick(in);
    const double unit = core_.config().torque_unit_unm * 1e-6;  // [N m]
    applied_ = glm::dvec3{out.torque[0] * unit, out.torque[1] * unit, out.torque[2] * unit};
    plant_.period(applied_, static_cast<double>(ticks_) * period_us_ * 1e-6);
  }

  /// With a dock sensor, homing completes only while the arm rests within
  /// home_tolerance of its home pose; without one (the default) the board
  /// reports at home always, as a board whose user docks it before homing.
  void set_dock_sensor(bool on) noexcept { dock_sensor_ = on; }
  void set_estop(bool pressed) noexcept { estop_ = pressed; }
  void flag_over_current() noexcept { over_current_ = true; }
  void flag_over_temperature() noexcept { over_temperature_ = true; }
  void set_buttons(std::uint8_t b) noexcept { buttons_ = b; }
  /// Power cycle of the board: the core restarts, the mechanics move on.
  void reboot() noexcept {
    core_.reset();
    ++boots_;
  }

  [[nodiscard]] firmware::FirmwareCore& core() noexcept { return core_; }
  [[nodiscard]] const firmware::FirmwareCore& core() const noexcept { return core_; }
  [[nodiscard]] ArmPlant& plant() noexcept { return plant_; }
  [[nodiscard]] const ArmPlant& plant() const noexcept { return plant_; }
  [[nodiscard]] glm::dvec3 applied_torque() const noexcept { return applied_; }
  [[nodiscard]] std::int64_t ticks() const noexcept { return ticks_; }
  [[nodiscard]] std::uint32_t period_us() const noexcept { return period_us_; }
  [[nodiscard]] int boots() const noexcept { return boots_; }

 private:
  ArmPlant plant_;
  firmware::FirmwareCore core_;
  glm::dvec3 applied_{0.0};
  std::int64_t ticks_{0};
  std::uint32_t period_us_{1000};
  int boots_{0};
  std::uint8_t buttons_{0};
  bool dock_sensor_{false};
  bool estop_{false};
  bool over_current_{false};
  bool over_temperature_{false};
};

/// Transport from a host to a FirmwareArm, with link faults made on the
/// firmware side at chosen firmware ticks (LinkFault, as SimulatedTransport).
class FirmwareLoopback final : public Transport {
 public:
  static constexpr std::size_t queue_capacity = ReportQueue::capacity;  ///< state reports in flight
  static constexpr std::size_t max_faults = LinkFaultSchedule::max_faults;

  /// @param now  time source [ns]; firmware tick k runs at start + (k + phase) periods
  FirmwareLoopback(FirmwareArm& arm, TimeSource now, double phase = 0.5) : arm_(&arm), now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("FirmwareLoopback: a time source is required");
    if (!(phase >= 0.0 && phase < 1.0))
      throw std::invalid_argument("FirmwareLoopback: phase must be in [0, 1) [periods]");
    period_ns_ = static_cast<std::int64_t>(arm.period_us()) * 1000;
    start_ns_ = now_() + static_cast<std::int64_t>(phase * static_cast<double>(period_ns_));
  }

  /// Schedules a fault at firmware tick `tick` (1-based) for `ticks` ticks.
  /// @throws std::invalid_argument when more than max_faults are scheduled.
  void inject(LinkFault fault, std::int64_t tick, std::int64_t ticks = 1) { faults_.inject(fault, tick, ticks); }

  /// Runs the firmware up to the time source's now.
  void advance() noexcept {
    const std::int64_t now = now_();
    while (start_ns_ + arm_->ticks() * period_ns_ <= now) {
      const std::int64_t k = arm_->ticks() + 1;
      if (faults_.starts(LinkFault::reboot, k)) arm_->reboot();
      if (faults_.active(LinkFault::unplug, k)) unplugged_ = true;
      stalled_ = !unplugged_ && faults_.active(LinkFault::stall, k);
      arm_->step();
      if (unplugged_ || stalled_) continue;
      queue_.send(arm_->core().report(), faults_, k);
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
    if (!stalled_) arm_->core().receive(report);
    return Status::ok;
  }

  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    if (buffer.empty()) return Status::short_report;
    return arm_->core().get_feature(buffer[0], buffer, size);
  }

  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    advance();
    if (unplugged_) return Status::disconnected;
    return arm_->core().set_feature(report);
  }

  [[nodiscard]] FirmwareArm& arm() noexcept { return *arm_; }
  [[nodiscard]] bool unplugged() const noexcept { return unplugged_; }

 private:
  FirmwareArm* arm_;
  TimeSource now_;
  std::int64_t period_ns_{1'000'000};
  std::int64_t start_ns_{0};
  ReportQueue queue_;
  LinkFaultSchedule faults_{"FirmwareLoopback"};
  bool unplugged_{false};
  bool stalled_{false};
};

}  // namespace hapticfield
