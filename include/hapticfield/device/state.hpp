#pragma once
/// @file state.hpp
/// DeviceState (what a force arm reports each tick), DeviceInfo (what it is)
/// and the Device concept.

#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <glm/vec3.hpp>

#include "hapticfield/device/status.hpp"

namespace hapticfield {

/// One timestamped state of the arm, in the device frame (x right, y up,
/// z toward the user; origin at the home pose).
struct DeviceState {
  double device_time{0.0};                ///< device timestamp [s]
  glm::dvec3 position{0.0};               ///< handle position [m]
  glm::dvec3 velocity{0.0};               ///< handle velocity [m/s] (filtered difference)
  glm::dvec3 joint_angles{0.0};           ///< q1 yaw, q2 shoulder, q3 elbow [rad]
  glm::dvec3 applied_torque{0.0};         ///< torques the motors applied [N m]
  std::array<std::int32_t, 3> encoder{};  ///< raw encoder counts
  std::array<std::int16_t, 3> gimbal{};   ///< raw gimbal values (device units)
  std::uint16_t sequence{0};              ///< report sequence number
  std::uint16_t command_echo{0};          ///< last command sequence the device applied
  std::uint16_t flags{0};                 ///< status_bits
  std::uint8_t buttons{0};                ///< button bit mask
  bool valid{false};                      ///< false until a report was decoded

  [[nodiscard]] bool homed() const noexcept { return (flags & status_bits::homed) != 0; }
  [[nodiscard]] bool armed() const noexcept { return (flags & status_bits::armed) != 0; }
  [[nodiscard]] bool faulted() const noexcept { return (flags & status_bits::any_fault) != 0; }
};

/// What a device is: limits, workspace and geometry. Figures in the defaults
/// are Omni-like defaults, not verified datasheet facts.
struct DeviceInfo {
  std::string name{"force arm"};
  double max_force{3.3};                           ///< peak force [N] (default, unverified)
  double continuous_force{0.88};                   ///< continuous force [N] (default, unverified)
  glm::dvec3 workspace_min{-0.08, -0.06, -0.035};  ///< workspace box corner [m]
  glm::dvec3 workspace_max{0.08, 0.06, 0.035};     ///< workspace box corner [m]
  double nominal_rate{1000.0};                     ///< state report rate [Hz]
  int degrees_of_freedom{3};                       ///< actuated DOF

  /// @throws std::invalid_argument naming the first limit that makes no sense.
  void validate() const {
    const auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
    if (bad(max_force)) throw std::invalid_argument("DeviceInfo: max_force must be finite and > 0 [N]");
    if (bad(continuous_force) || continuous_force > max_force)
      throw std::invalid_argument("DeviceInfo: continuous_force must be finite, > 0 and <= max_force [N]");
    if (bad(nominal_rate)) throw std::invalid_argument("DeviceInfo: nominal_rate must be finite and > 0 [Hz]");
    if (degrees_of_freedom < 1 || degrees_of_freedom > 6)
      throw std::invalid_argument("DeviceInfo: degrees_of_freedom must be 1..6");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(workspace_min[i]) || !std::isfinite(workspace_max[i]) || workspace_min[i] >= workspace_max[i])
        throw std::invalid_argument("DeviceInfo: workspace_min must be finite and < workspace_max [m]");
  }
};

/// A force arm: reads its newest state, takes a force command, describes
/// itself. All per-tick calls are noexcept and allocation-free.
template <class D>
concept Device = requires(D& device, const D& cdevice, DeviceState& state, const glm::dvec3& force, bool on) {
  { device.read(state) }
  noexcept->std::same_as<Status>;  // newest state; no_data when nothing new
  { device.write(force) }
  noexcept->std::same_as<Status>;  // command a force [N]
  { device.set_armed(on) }
  noexcept->std::same_as<Status>;  // request motors on/off
  { device.request_home() }
  noexcept->std::same_as<Status>;
  { cdevice.info() }
  noexcept->std::convertible_to<const DeviceInfo&>;
};

}  // namespace hapticfield
