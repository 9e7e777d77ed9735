#pragma once
/// @file probe.hpp
/// The haptic interface point (HIP) state handed to every field each tick.

#include <cstdint>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Probe::primitive and Contact::primitive when no triangle or grid cell is
/// touched.
inline constexpr std::uint32_t no_primitive = 0xFFFFFFFFu;

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
///
/// A constraint over a shape with texture coordinates (surface/) also tells
/// the parts where on the surface the contact is: the touched point's uv,
/// the unit directions of increasing u and v in the tangent plane, the
/// touched primitive (triangle or grid cell) and its material index. A
/// per-texel material is a lookup by (material, primitive, uv); a texture
/// laid on the surface works in the (tangent, bitangent, normal) frame.
struct Probe {
  glm::dvec3 position{0.0};               ///< HIP position [m]
  glm::dvec3 velocity{0.0};               ///< HIP velocity [m/s]
  double normal_force{0.0};               ///< magnitude of the constraint force |Fc| of this tick [N]
  glm::dvec3 surface_normal{0.0};         ///< unit normal of the touched surface, toward the user; zero: no surface
  double time{0.0};                       ///< time since the loop started [s]
  double period{servo_period};            ///< tick period [s]
  glm::dvec2 surface_uv{0.0};             ///< texture coordinates of the touched point (u right, v up) [-]
  glm::dvec3 surface_tangent{0.0};        ///< unit direction of increasing u in the tangent plane; zero: no uv
  glm::dvec3 surface_bitangent{0.0};      ///< unit direction of increasing v in the tangent plane; zero: no uv
  std::uint32_t primitive{no_primitive};  ///< touched triangle / grid cell id; no_primitive: none
  std::uint32_t material{0};              ///< material index of the touched primitive
};

}  // namespace hapticfield
