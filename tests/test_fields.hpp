#pragma once
// Small fields the servo and device tests feel through the loop.
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"

namespace hapticfield::testing {

/// A stiff virtual wall: the half-space y < wall_y pushes back along +y.
struct Wall {
  double wall_y{0.0};        ///< [m]
  double stiffness{2000.0};  ///< [N/m]
  glm::dvec3 force(const Probe& p) const noexcept {
    const double depth = wall_y - p.position.y;
    return depth > 0.0 ? glm::dvec3{0.0, stiffness * depth, 0.0} : glm::dvec3{0.0};
  }
};

/// The same force everywhere [N].
struct Constant {
  glm::dvec3 f{0.0};
  glm::dvec3 force(const Probe&) const noexcept { return f; }
};

}  // namespace hapticfield::testing
