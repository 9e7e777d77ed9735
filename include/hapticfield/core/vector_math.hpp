#pragma once
/// @file vector_math.hpp
/// Small helpers on GLM vectors used on the servo path (all noexcept).

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// True when every component is finite (no NaN, no Inf).
[[nodiscard]] inline bool is_finite(const glm::dvec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// True when every component is finite (no NaN, no Inf).
[[nodiscard]] inline bool is_finite(const glm::dvec2& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y);
}

/// The largest component's magnitude, max(|x|, |y|, |z|) (the infinity
/// norm).
[[nodiscard]] inline double largest_component(const glm::dvec3& v) noexcept {
  return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
}

/// Scales v down so that |v| <= limit, keeping its direction. A non-finite
/// vector or a non-finite / negative limit gives zero.
[[nodiscard]] inline glm::dvec3 clamp_magnitude(const glm::dvec3& v, double limit) noexcept {
  if (!is_finite(v) || !std::isfinite(limit) || limit <= 0.0) return glm::dvec3{0.0};
  // Scale by the largest component first so |v| cannot overflow for huge v.
  const double largest = largest_component(v);
  if (largest <= limit / 2.0) return v;  // |v| <= sqrt(3) * largest < limit
  const glm::dvec3 unit_scaled = v / largest;
  const double magnitude = largest * glm::length(unit_scaled);
  if (magnitude <= limit) return v;
  return unit_scaled * (limit / glm::length(unit_scaled));
}

}  // namespace hapticfield
