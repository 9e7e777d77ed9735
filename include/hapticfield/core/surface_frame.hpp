#pragma once
/// @file surface_frame.hpp
/// The frame of the surface under the HIP: its unit normal n (toward the
/// user) and two unit tangents t1, t2 with t1 x t2 = n. Friction and
/// textures act in this frame (Fritz & Barner 1996: Ft and Ff live on the
/// surface that Fc comes from), so they follow a tilted plane or a face.

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// An orthonormal, right-handed frame (t1, t2, n).
struct SurfaceFrame {
  glm::dvec3 tangent1{1.0, 0.0, 0.0};  ///< first tangent (unit)
  glm::dvec3 tangent2{0.0, 1.0, 0.0};  ///< second tangent (unit)
  glm::dvec3 normal{0.0, 0.0, 1.0};    ///< unit normal, toward the user

  /// Frame coordinates (along t1, t2, n) -> device frame.
  [[nodiscard]] glm::dvec3 to_device(const glm::dvec3& local) const noexcept {
    return local.x * tangent1 + local.y * tangent2 + local.z * normal;
  }
  /// v without its component along the normal.
  [[nodiscard]] glm::dvec3 tangential(const glm::dvec3& v) const noexcept { return v - glm::dot(v, normal) * normal; }
};

/// The frame whose normal is the unit vector n: the rotation about z x n
/// that takes +z to n, applied to x and y. So n = +z gives exactly the device
/// frame (x, y, z), and the frame turns smoothly with n everywhere except at
/// n = -z, where it is (x, -y, -z). n must be unit length.
[[nodiscard]] inline SurfaceFrame surface_frame(const glm::dvec3& n) noexcept {
  const double a = n.x, b = n.y, c = n.z;
  // d = 1 + c, computed without cancellation when c is near -1 (|n| = 1)
  const double d = c >= 0.0 ? 1.0 + c : (a * a + b * b) / (1.0 - c);
  if (!(d > 0.0)) return SurfaceFrame{{1.0, 0.0, 0.0}, {0.0, -1.0, 0.0}, {0.0, 0.0, -1.0}};
  const double ab = a * b / d;
  return SurfaceFrame{{1.0 - a * a / d, -ab, -a}, {-ab, 1.0 - b * b / d, -b}, n};
}

/// The unit normal a field should use this tick: the probe's surface normal
/// (set by a ContactField) when it has one, otherwise `fallback` (a field's
/// configured normal; zero for none). Zero when the probe's normal is not
/// finite.
[[nodiscard]] inline glm::dvec3 surface_normal_of(const Probe& probe, const glm::dvec3& fallback) noexcept {
  const glm::dvec3& n = probe.surface_normal;
  if (!is_finite(n)) return glm::dvec3{0.0};
  const double length = glm::length(n);
  if (length == 0.0) return fallback;
  return n / length;
}

}  // namespace hapticfield
