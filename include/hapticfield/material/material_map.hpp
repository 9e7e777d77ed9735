#pragma once
/// @file material_map.hpp
/// A surface's material over its texture coordinates: stiffness, damping,
/// static and dynamic friction, the gain of its texture and the id of its
/// vibration, each a constant or a picture (material/property_map.hpp), so
/// a photograph and a painted mask can say "this region is sandpaper, that
/// one is glass". sample(uv) is noexcept and allocation-free (servo path)
/// and always gives usable values: stiffness > 0, damping and mu_s >= 0,
/// mu_k in [0, mu_s], gain >= 0 (a map's bilinear mix of two regions can
/// never leave these bounds, so clamping only guards rounding).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <glm/vec2.hpp>

#include "hapticfield/material/property_map.hpp"

namespace hapticfield::material {

/// The material at one point.
struct MaterialSample {
  double stiffness{1500.0};      ///< k [N/m]
  double damping{0.0};           ///< b on the normal velocity [N s/m]
  double static_friction{0.0};   ///< mu_s [-]
  double dynamic_friction{0.0};  ///< mu_k [-]
  double texture_gain{1.0};      ///< multiplies the surface's texture force [-]
  std::uint32_t vibration{0};    ///< the vibration's material id (vibration/tap.hpp), nearest texel
};

/// Maps of every property (see the file comment).
struct MaterialMaps {
  PropertyMap stiffness{1500.0};      ///< [N/m], > 0
  PropertyMap damping{0.0};           ///< [N s/m], >= 0
  PropertyMap static_friction{0.0};   ///< mu_s [-], >= 0
  PropertyMap dynamic_friction{0.0};  ///< mu_k [-], >= 0 (clamped to mu_s where it is larger)
  PropertyMap texture_gain{1.0};      ///< [-], >= 0
  IndexMap vibration{0};              ///< material id per region
};

class MaterialMap {
 public:
  /// @throws std::invalid_argument for a stiffness map that is not > 0
  ///         everywhere, or a damping, friction or gain map below 0.
  explicit MaterialMap(MaterialMaps maps) : maps_(std::move(maps)) {
    if (!(maps_.stiffness.lowest() > 0.0))
      throw std::invalid_argument("MaterialMap: stiffness must be > 0 [N/m] everywhere (least value " +
                                  std::to_string(maps_.stiffness.lowest()) + ")");
    require_not_negative(maps_.damping, "damping [N s/m]");
    require_not_negative(maps_.static_friction, "static friction [-]");
    require_not_negative(maps_.dynamic_friction, "dynamic friction [-]");
    require_not_negative(maps_.texture_gain, "texture gain [-]");
  }

  /// The material at uv (a non-finite uv reads each map's constant / least value).
  [[nodiscard]] MaterialSample sample(glm::dvec2 uv) const noexcept {
    MaterialSample s;
    s.stiffness = std::fmax(maps_.stiffness.at(uv), maps_.stiffness.lowest());
    s.damping = std::fmax(maps_.damping.at(uv), 0.0);
    s.static_friction = std::fmax(maps_.static_friction.at(uv), 0.0);
    s.dynamic_friction = std::clamp(maps_.dynamic_friction.at(uv), 0.0, s.static_friction);
    s.texture_gain = std::fmax(maps_.texture_gain.at(uv), 0.0);
    s.vibration = maps_.vibration.at(uv);
    return s;
  }

  [[nodiscard]] const MaterialMaps& maps() const noexcept { return maps_; }

 private:
  static void require_not_negative(const PropertyMap& map, const char* what) {
    if (map.lowest() < 0.0)
      throw std::invalid_argument(std::string("MaterialMap: ") + what + " must be >= 0 everywhere (least value " +
                                  std::to_string(map.lowest()) + ")");
  }

  MaterialMaps maps_;
};

}  // namespace hapticfield::material
