#pragma once
/// @file uv_relief.hpp
/// A relief of small height laid on a surface by uv: a height map h(uv)
/// [m] over the surface's texture coordinates (a PropertyMap, bilinear),
/// felt by haptic bump mapping (Ho, Basdogan & Srinivasan, "Efficient
/// point-based rendering techniques for haptic display of virtual objects",
/// Presence 8(5), 1999): the contact is h deeper where the relief stands
/// up, and its force leans with the relief's slope. A part of a contact on
/// the surface, laid with on_surface() (surface/on_surface.hpp), so in the
/// flat texture frame (x along u, y along v, z the normal):
///
///   Fz = k h(uv)                         [N]
///   (Fx, Fy) = -(|Fc| + k h(uv)) grad h  [N]  (grad h in m per m, small slopes)
///
/// with |Fc| the contact's own force this tick (Probe::normal_force) and
/// grad h = (dh/du, dh/dv) / metres_per_uv by central differences one texel
/// wide. Out of contact (|Fc| = 0) it gives nothing. The heights are small
/// against the proxy's own geometry (a picture's gray levels as fractions of
/// a millimetre): the proxy stays on the mesh, and the relief is the force
/// it adds. force() is noexcept and allocation-free (servo path).

#include <cmath>
#include <stdexcept>
#include <utility>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/material/property_map.hpp"

namespace hapticfield::material {

class UvRelief {
 public:
  /// @param heights        h(uv) [m], >= 0 everywhere
  /// @param stiffness      k of the contact it lies on [N/m], > 0
  /// @param metres_per_uv  the surface's size of one uv unit [m], > 0
  /// @throws std::invalid_argument for a negative height or a stiffness or
  ///         scale that is not finite and > 0.
  UvRelief(PropertyMap heights, double stiffness, double metres_per_uv)
      : heights_(std::move(heights)), stiffness_(stiffness), metres_per_uv_(metres_per_uv) {
    if (heights_.lowest() < 0.0) throw std::invalid_argument("UvRelief: heights must be >= 0 [m]");
    if (!std::isfinite(stiffness) || stiffness <= 0.0)
      throw std::invalid_argument("UvRelief: stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(metres_per_uv) || metres_per_uv <= 0.0)
      throw std::invalid_argument("UvRelief: metres per uv unit must be finite and > 0 [m]");
    if (!heights_.is_constant()) {
      du_ = 1.0 / heights_.width();
      dv_ = 1.0 / heights_.height();
    }
  }

  /// The relief's force in the flat texture frame [N] (see the file comment).
  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept {
    const glm::dvec2 uv = probe.surface_uv;
    if (!(probe.normal_force > 0.0) || !std::isfinite(uv.x) || !std::isfinite(uv.y)) return glm::dvec3{0.0};
    const double h = heights_.at(uv);
    glm::dvec2 slope{0.0};
    if (du_ > 0.0) {
      slope.x = (heights_.at(uv + glm::dvec2{du_, 0.0}) - heights_.at(uv - glm::dvec2{du_, 0.0})) /
                (2.0 * du_ * metres_per_uv_);
      slope.y = (heights_.at(uv + glm::dvec2{0.0, dv_}) - heights_.at(uv - glm::dvec2{0.0, dv_})) /
                (2.0 * dv_ * metres_per_uv_);
    }
    const double along_normal = probe.normal_force + stiffness_ * h;
    return {-along_normal * slope.x, -along_normal * slope.y, stiffness_ * h};
  }

  [[nodiscard]] const PropertyMap& heights() const noexcept { return heights_; }

 private:
  PropertyMap heights_;
  double stiffness_;
  double metres_per_uv_;
  double du_{0.0};  ///< one texel along u [uv units]; 0 for a constant
  double dv_{0.0};
};

}  // namespace hapticfield::material
