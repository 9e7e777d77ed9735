#pragma once
/// @file tangible_field.hpp
/// TangibleImageField: forces felt from a picture (Vasudevan & Manivannan,
/// "Tangible images: runtime generation of haptic textures from images",
/// Haptics Symposium 2008) as a HapticField. The HIP's device position is
/// mapped onto the picture, the normalised image force (magnitude 1 at a
/// black/white edge) is scaled by a gain [N] and mapped back into the device
/// frame. The force lies in the picture's plane; add a constraint field to
/// hold the HIP on it.

#include <cmath>
#include <stdexcept>
#include <utility>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/kernels/tangible_image.hpp"

namespace hapticfield {

/// Something that gives a normalised 2D force at an image position.
template <class S>
concept ImageForceSource = requires(const S& s, double x, double y) {
  { s.at(x, y) }
  noexcept->std::same_as<glm::dvec2>;
};

template <ImageForceSource Source = TangibleImage>
class TangibleImageField {
 public:
  /// @param gain  force at full scale (a black/white edge) [N], finite and >= 0
  /// @throws std::invalid_argument for a bad gain.
  TangibleImageField(Source source, PlaneMapping mapping, double gain)
      : source_(std::move(source)), mapping_(mapping), gain_(gain) {
    if (!std::isfinite(gain) || gain < 0.0)
      throw std::invalid_argument("TangibleImageField: gain must be finite and non-negative [N]");
  }

  /// Force on the HIP [N], in the picture's plane, toward darker pixels.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept {
    if (!is_finite(probe.position)) return glm::dvec3{0.0};
    const glm::dvec2 px = mapping_.to_image(probe.position);
    return gain_ * mapping_.vector_to_device(source_.at(px.x, px.y));
  }

  [[nodiscard]] const Source& source() const noexcept { return source_; }
  [[nodiscard]] const PlaneMapping& mapping() const noexcept { return mapping_; }
  [[nodiscard]] double gain() const noexcept { return gain_; }

 private:
  Source source_;
  PlaneMapping mapping_;
  double gain_;
};

static_assert(HapticField<TangibleImageField<>>);

}  // namespace hapticfield
