#pragma once
/// @file mouse_device.hpp
/// The mouse as a force arm that feels nothing: the viewer's thread stores
/// the pointer's picture position, the servo loop reads it as the handle's
/// position on the picture plane (z = 0) and the commanded force goes
/// nowhere (it is shown, not felt). The 3D view of a shape stores a device
/// position instead (set_position: the pointer moves the handle in the view
/// plane, the wheel and keys push it in and out). Satisfies the Device concept; read()
/// and write() are lock-free and allocation-free.

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>

#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"

namespace hapticfield::view {

/// Settings of MouseDevice.
struct MouseDeviceConfig {
  double velocity_time_constant{0.02};  ///< low-pass on the position difference [s]
  double max_force{3.3};                ///< what the loop's safety chain clamps to [N]
};

template <class Clock>
class MouseDevice {
 public:
  /// @param mapping  picture [px] <-> device plane [m]
  /// @param clock    the loop's clock (now() in [ns])
  MouseDevice(const PlaneMapping& mapping, Clock& clock, MouseDeviceConfig config = {})
      : mapping_(mapping), clock_(&clock), config_(config) {
    info_.name = "mouse (forces shown, not felt)";
    info_.max_force = config.max_force;
    info_.continuous_force = config.max_force;
  }

  /// Viewer thread: the pointer is at picture position (x, y) [px].
  void set_pixel(double x, double y) noexcept {
    const auto fx = std::bit_cast<std::uint32_t>(static_cast<float>(x));
    const auto fy = std::bit_cast<std::uint32_t>(static_cast<float>(y));
    pixel_.store((static_cast<std::uint64_t>(fx) << 32) | fy, std::memory_order_relaxed);
  }

  /// Viewer thread: the handle at p [m] in the device frame (the 3D view),
  /// from then on instead of the pixel. Each axis is kept to 0.25 um within
  /// +-0.26 m (clamped), the three packed in one atomic word.
  void set_position(const glm::dvec3& p) noexcept {
    std::uint64_t packed = 0;
    for (int k = 0; k < 3; ++k) {
      const double q = std::clamp(std::round(p[k] / position_unit), -position_limit, position_limit);
      packed |= (static_cast<std::uint64_t>(static_cast<std::int64_t>(q) + (1 << 20)) & 0x1fffffu) << (21 * k);
    }
    position_.store(packed, std::memory_order_relaxed);
    three_d_.store(true, std::memory_order_release);
  }

  /// The handle's device position last stored with set_position() [m].
  [[nodiscard]] glm::dvec3 position() const noexcept {
    const std::uint64_t packed = position_.load(std::memory_order_relaxed);
    glm::dvec3 p{0.0};
    for (int k = 0; k < 3; ++k)
      p[k] = (static_cast<double>((packed >> (21 * k)) & 0x1fffffu) - (1 << 20)) * position_unit;
    return p;
  }

  /// The pointer's picture position last stored [px].
  [[nodiscard]] glm::dvec2 pixel() const noexcept {
    const std::uint64_t packed = pixel_.load(std::memory_order_relaxed);
    return {std::bit_cast<float>(static_cast<std::uint32_t>(packed >> 32)),
            std::bit_cast<float>(static_cast<std::uint32_t>(packed & 0xffffffffu))};
  }

  Status read(DeviceState& state) noexcept {
    const double t = static_cast<double>(clock_->now()) * 1e-9;  // [s]
    const glm::dvec3 p = three_d_.load(std::memory_order_acquire) ? position() : mapping_.to_device(pixel());
    if (primed_ && t > last_t_) {
      const double dt = t - last_t_;
      const glm::dvec3 raw = (p - last_p_) / dt;  // [m/s]
      velocity_ += (1.0 - std::exp(-dt / config_.velocity_time_constant)) * (raw - velocity_);
    }
    primed_ = true;
    last_t_ = t;
    last_p_ = p;
    state.device_time = t;
    state.position = p;
    state.velocity = velocity_;
    state.flags = status_bits::homed | status_bits::armed;
    state.sequence = static_cast<std::uint16_t>(state.sequence + 1);
    state.valid = true;
    return Status::ok;
  }

  Status write(const glm::dvec3& force) noexcept {
    last_force_ = force;
    return Status::ok;
  }
  Status set_armed(bool) noexcept { return Status::ok; }
  Status request_home() noexcept { return Status::ok; }
  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }

 private:
  PlaneMapping mapping_;
  Clock* clock_;
  MouseDeviceConfig config_;
  DeviceInfo info_{};
  static constexpr double position_unit = 0.25e-6;         ///< [m]
  static constexpr double position_limit = (1 << 20) - 1;  ///< [position units]
  std::atomic<std::uint64_t> pixel_{0};
  std::atomic<std::uint64_t> position_{0};
  std::atomic<bool> three_d_{false};
  bool primed_{false};
  double last_t_{0.0};
  glm::dvec3 last_p_{0.0};
  glm::dvec3 velocity_{0.0};
  glm::dvec3 last_force_{0.0};
};

}  // namespace hapticfield::view
