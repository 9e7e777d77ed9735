#pragma once
/// @file orbit_camera.hpp
/// A pinhole camera orbiting a target point: yaw about the device's y axis
/// (up), pitch above the target's horizontal plane, a distance [m]. yaw = 0,
/// pitch = 0 is the user's own view of the workspace: from +z (toward the
/// user), x to the right, y up. The image is width x height px with the
/// principal point at its centre; a pixel (i, j) covers [i, i + 1) x
/// [j, j + 1), so its centre is (i + 0.5, j + 0.5). Plain arithmetic, no
/// display.

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::view {

/// A point seen by the camera: image position [px] (x right, y down) and
/// depth along the view direction [m] (> 0: in front of the camera).
struct Projected {
  glm::dvec2 pixel{0.0};
  double depth{0.0};
};

struct OrbitCamera {
  glm::dvec3 target{0.0};                         ///< the point orbited and looked at [m]
  double yaw{0.0};                                ///< about +y [rad]; positive turns the camera toward +x
  double pitch{0.0};                              ///< above the target's horizontal plane [rad], within +-89 degrees
  double distance{0.2};                           ///< from the target [m]
  double fov_y{40.0 * std::numbers::pi / 180.0};  ///< vertical field of view [rad]
  int width{800};                                 ///< image width [px]
  int height{600};                                ///< image height [px]

  /// Focal length [px]: (height / 2) / tan(fov_y / 2).
  [[nodiscard]] double focal() const noexcept { return 0.5 * height / std::tan(0.5 * fov_y); }

  /// Unit vector from the target to the eye.
  [[nodiscard]] glm::dvec3 back() const noexcept {
    const double p = std::clamp(pitch, -max_pitch, max_pitch);
    return {std::sin(yaw) * std::cos(p), std::sin(p), std::cos(yaw) * std::cos(p)};
  }
  [[nodiscard]] glm::dvec3 eye() const noexcept { return target + distance * back(); }
  /// Unit view direction (from the eye toward the target).
  [[nodiscard]] glm::dvec3 forward() const noexcept { return -back(); }
  /// Unit image-right direction in the device frame.
  [[nodiscard]] glm::dvec3 right() const noexcept { return glm::normalize(glm::cross(forward(), up_axis)); }
  /// Unit image-up direction in the device frame.
  [[nodiscard]] glm::dvec3 up() const noexcept { return glm::cross(right(), forward()); }

  /// Where p [m] appears. depth <= 0: behind the eye (pixel meaningless).
  [[nodiscard]] Projected project(const glm::dvec3& p) const noexcept {
    const glm::dvec3 c = p - eye();
    const double z = glm::dot(c, forward());
    if (!(z > 0.0)) return {glm::dvec2{0.0}, z};
    const double f = focal() / z;
    return {glm::dvec2{0.5 * width + f * glm::dot(c, right()), 0.5 * height - f * glm::dot(c, up())}, z};
  }

  /// The point at image position `pixel` [px] and depth `depth` [m]: the
  /// inverse of project().
  [[nodiscard]] glm::dvec3 unproject(const glm::dvec2& pixel, double depth) const noexcept {
    const double s = depth / focal();
    return eye() + depth * forward() + s * (pixel.x - 0.5 * width) * right() - s * (pixel.y - 0.5 * height) * up();
  }

  /// Looks at a ball of `radius` [m] around `centre` so that it fills
  /// about 70 % of the image height.
  void frame(const glm::dvec3& centre, double radius) noexcept {
    target = centre;
    distance = std::max(1e-6, radius / std::sin(0.35 * fov_y));
  }

  static constexpr double max_pitch = 89.0 * std::numbers::pi / 180.0;
  static constexpr glm::dvec3 up_axis{0.0, 1.0, 0.0};
};

}  // namespace hapticfield::view
