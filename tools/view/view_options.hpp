#pragma once
/// @file view_options.hpp
/// --view YAW,PITCH and --distance MM: where the camera of a tool's 3D view
/// stands (servo_demo --snapshot, hapticfield_view --shape, feel_mujoco
/// --snapshot).

#include <numbers>
#include <optional>

#include "common/cli.hpp"
#include "view/orbit_camera.hpp"

namespace hapticfield::view {

/// The camera flags as given; aim() turns an OrbitCamera to them.
struct ViewOptions {
  double yaw_deg{25.0};               ///< about +y [degrees], in [-180, 180]
  double pitch_deg{30.0};             ///< above the target's plane [degrees], in [-89, 89]
  std::optional<double> distance_mm;  ///< from the target [mm], in [1, 1e5]; none: the tool's own

  /// Takes the current token when it is --view or --distance (true); leaves
  /// any other (false).
  /// @throws cli::UsageError for a value out of range; a pitch beyond 89
  ///         degrees (straight above or below, the camera would have no "up")
  ///         is named as such.
  bool take(cli::Parser& p) {
    if (p.is("--view")) {
      const auto [yaw, pitch] = p.pair(cli::closed(-180.0, 180.0));
      if (pitch < -89.0 || pitch > 89.0)
        throw cli::UsageError("--view pitch must be in [-89, 89] degrees, got " + cli::detail::number_text(pitch));
      yaw_deg = yaw;
      pitch_deg = pitch;
    } else if (p.is("--distance")) {
      distance_mm = p.real(cli::closed(1.0, 1e5));
    } else {
      return false;
    }
    return true;
  }

  /// Turns `camera` to the angles, and sets its distance when one was given.
  void aim(OrbitCamera& camera) const noexcept {
    constexpr double degree = std::numbers::pi / 180.0;
    if (distance_mm) camera.distance = *distance_mm * 1e-3;
    camera.yaw = yaw_deg * degree;
    camera.pitch = pitch_deg * degree;
  }
};

}  // namespace hapticfield::view
