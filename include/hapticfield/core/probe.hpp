#pragma once
/// @file probe.hpp
/// The haptic interface point (HIP) state handed to every field each tick.

#include <glm/vec3.hpp>

namespace hapticfield {

/// Nominal servo period of a Phantom-class arm [s].
inline constexpr double servo_period = 1e-3;

/// State of the haptic interface point, in the device frame.
///
/// Every algorithm in the library needs no more than this: position for image
/// and lattice lookups, velocity for friction and direction of motion, the
/// constraint (normal) force and the normal of the surface being touched for
/// force-scaled textures and tangent-plane friction, time and period for
/// temporal sampling and filters.
///
/// normal_force and surface_normal describe the contact of this tick. A
/// ContactField (core/contact.hpp) fills them from its constraint before it
/// calls its parts; a probe that touches nothing has both zero.
struct Probe {
  glm::dvec3 position{0.0};        ///< HIP position [m]
  glm::dvec3 velocity{0.0};        ///< HIP velocity [m/s]
  double normal_force{0.0};        ///< magnitude of the constraint force |Fc| of this tick [N]
  glm::dvec3 surface_normal{0.0};  ///< unit normal of the touched surface, toward the user; zero: no surface
  double time{0.0};                ///< time since the loop started [s]
  double period{servo_period};     ///< tick period [s]
};

}  // namespace hapticfield
