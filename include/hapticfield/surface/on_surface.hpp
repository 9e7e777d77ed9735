#pragma once
/// @file on_surface.hpp
/// on_surface(field, mapping): any field laid on a surface by its texture
/// coordinates. A part of a ContactField over a ProxyConstraint (or any
/// constraint that reports uv and a tangent frame) sees, each tick, the
/// touched point's uv and the unit tangent t (increasing u), bitangent b
/// (increasing v) and normal n there. The wrapped field is evaluated in a
/// flat texture frame:
///
///   position  (offset + scale * uv, 0)    [m]  (x along u, y along v)
///   velocity  (v . t, v . b, v . n)       [m/s]
///   normal    +z, normal_force |Fc| (as the ContactField gave it)
///
/// and its force (fx, fy, fz) comes back as fx t + fy b + fz n. The frame
/// is made orthonormal about the contact normal n first (t and b turned
/// into the plane normal to n): at a crease n points at the crease line,
/// up to a degree from the shaded normal t x b, and a tangential field must
/// stay normal to Fc. So a tangible
/// image, a lattice or fBm texture, a HaTT texture, friction or a normals
/// field pushes along the curved surface, in its tangent plane (F = Fc +
/// Ft + Ff on any shape), scaled by |Fc| where the field asks for it.
/// A probe without a tangent frame (no contact, or a shape without uv) gets
/// no force.

#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// uv -> the flat texture frame of a field laid on a surface.
struct UvMapping {
  glm::dvec2 scale{1.0};   ///< [m per uv unit] along u and v
  glm::dvec2 offset{0.0};  ///< flat position of uv (0, 0) [m]
};

template <HapticField Field>
class OnSurface {
 public:
  /// @throws std::invalid_argument for a non-finite mapping.
  OnSurface(Field field, const UvMapping& mapping) : field_(std::move(field)), mapping_(mapping) {
    if (!is_finite(mapping.scale) || !is_finite(mapping.offset))
      throw std::invalid_argument("OnSurface: uv mapping scale [m] and offset [m] must be finite");
  }

  /// The field's force along the surface at the touched point [N].
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    const glm::dvec3& t = probe.surface_tangent;
    const glm::dvec3& b = probe.surface_bitangent;
    const glm::dvec3& n = probe.surface_normal;
    if (!is_finite(t) || !is_finite(b) || !is_finite(n) || !is_finite(probe.surface_uv) || !is_finite(probe.velocity))
      return glm::dvec3{0.0};
    if (glm::dot(t, t) == 0.0 || glm::dot(b, b) == 0.0 || glm::dot(n, n) == 0.0) return glm::dvec3{0.0};
    // the orthonormal frame (tangent, bitangent, normal) about the contact normal
    const glm::dvec3 normal = glm::normalize(n);
    glm::dvec3 tangent = t - glm::dot(t, normal) * normal;
    const double length = glm::length(tangent);
    if (!(length > 1e-6)) return glm::dvec3{0.0};  // t along n: no tangent plane to speak of
    tangent /= length;
    glm::dvec3 bitangent = glm::cross(normal, tangent);
    if (glm::dot(bitangent, b) < 0.0) bitangent = -bitangent;  // mirrored uvs keep their v direction
    Probe flat = probe;
    const glm::dvec2 at = mapping_.offset + mapping_.scale * probe.surface_uv;
    flat.position = glm::dvec3{at.x, at.y, 0.0};
    flat.velocity = glm::dvec3{glm::dot(probe.velocity, tangent), glm::dot(probe.velocity, bitangent),
                               glm::dot(probe.velocity, normal)};
    flat.surface_normal = glm::dvec3{0.0, 0.0, 1.0};
    flat.surface_tangent = glm::dvec3{1.0, 0.0, 0.0};
    flat.surface_bitangent = glm::dvec3{0.0, 1.0, 0.0};
    const glm::dvec3 f = field_.force(flat);
    const glm::dvec3 out = f.x * tangent + f.y * bitangent + f.z * normal;
    return is_finite(out) ? out : glm::dvec3{0.0};
  }

  void reset() noexcept { reset_if_stateful(field_); }

  [[nodiscard]] Field& inner() noexcept { return field_; }
  [[nodiscard]] const UvMapping& mapping() const noexcept { return mapping_; }

 private:
  Field field_;
  UvMapping mapping_;
};

/// The field laid on the touched surface through its uv (see the file
/// comment).
template <HapticField Field>
[[nodiscard]] OnSurface<std::remove_cvref_t<Field>> on_surface(Field&& field, const UvMapping& mapping = {}) {
  return OnSurface<std::remove_cvref_t<Field>>(std::forward<Field>(field), mapping);
}

}  // namespace hapticfield
