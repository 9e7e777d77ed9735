#pragma once
/// @file data_texture.hpp
/// Data visualisation and false texturing (Fritz & Barner 1996, section 8):
/// a data value over the plane modulates a texture's amplitude and the
/// friction; a label map gives each region (or gray level) its own texture.
/// Core only: the maps are plain grids; texture/image_maps.hpp builds them
/// from OpenCV images.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/any_field.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield::texture {

/// A grid of data values [any unit] laid on the device plane, read by
/// bilinear interpolation between pixel centres.
class ScalarMap {
 public:
  /// @throws std::invalid_argument when values.size() != width * height,
  ///         for an empty grid, or for a non-finite value.
  ScalarMap(int width, int height, std::vector<float> values, PlaneMapping mapping)
      : width_(width), height_(height), values_(std::move(values)), mapping_(mapping) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("ScalarMap: width and height must be > 0 [px]");
    if (values_.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
      throw std::invalid_argument("ScalarMap: values.size() must equal width * height");
    for (float v : values_)
      if (!std::isfinite(v)) throw std::invalid_argument("ScalarMap: values must be finite");
  }

  /// Value at a device position [m]; `outside` off the image or for a
  /// non-finite position.
  [[nodiscard]] double value(const glm::dvec3& position, double outside = 0.0) const noexcept {
    if (!is_finite(position)) return outside;
    const glm::dvec2 px = mapping_.to_image(position);
    if (!(px.x >= -0.5 && px.y >= -0.5 && px.x <= width_ - 0.5 && px.y <= height_ - 0.5)) return outside;
    const double x = std::fmin(std::fmax(px.x, 0.0), width_ - 1.0);
    const double y = std::fmin(std::fmax(px.y, 0.0), height_ - 1.0);
    const int x0 = static_cast<int>(x);
    const int y0 = static_cast<int>(y);
    const int x1 = x0 + 1 < width_ ? x0 + 1 : x0;
    const int y1 = y0 + 1 < height_ ? y0 + 1 : y0;
    const double tx = x - x0;
    const double ty = y - y0;
    const double top = (1.0 - tx) * at(x0, y0) + tx * at(x1, y0);
    const double bottom = (1.0 - tx) * at(x0, y1) + tx * at(x1, y1);
    return (1.0 - ty) * top + ty * bottom;
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] const PlaneMapping& mapping() const noexcept { return mapping_; }

 private:
  [[nodiscard]] double at(int x, int y) const noexcept {
    return values_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
  }
  int width_;
  int height_;
  std::vector<float> values_;
  PlaneMapping mapping_;
};

/// F = (base + slope d(p)) F_inner(p): a data value d modulates the
/// amplitude of a texture (its variance scales with the square) or the
/// strength of friction. Off the map d = `outside`.
template <HapticField Field>
class DataModulated {
 public:
  /// @throws std::invalid_argument for non-finite base, slope or outside.
  DataModulated(Field field, ScalarMap map, double base, double slope, double outside = 0.0)
      : field_(std::move(field)), map_(std::move(map)), base_(base), slope_(slope), outside_(outside) {
    if (!std::isfinite(base) || !std::isfinite(slope) || !std::isfinite(outside))
      throw std::invalid_argument("DataModulated: base, slope and outside must be finite");
  }
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    const double k = base_ + slope_ * map_.value(probe.position, outside_);
    const glm::dvec3 f = k * glm::dvec3(field_.force(probe));
    return is_finite(f) ? f : glm::dvec3{0.0};
  }
  void reset() noexcept { reset_if_stateful(field_); }
  [[nodiscard]] Field& inner() noexcept { return field_; }

 private:
  Field field_;
  ScalarMap map_;
  double base_;
  double slope_;
  double outside_;
};

/// A grid of region labels laid on the device plane (nearest pixel).
class LabelMap {
 public:
  /// @throws std::invalid_argument when labels.size() != width * height or
  ///         for an empty grid.
  LabelMap(int width, int height, std::vector<std::uint16_t> labels, PlaneMapping mapping)
      : width_(width), height_(height), labels_(std::move(labels)), mapping_(mapping) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("LabelMap: width and height must be > 0 [px]");
    if (labels_.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
      throw std::invalid_argument("LabelMap: labels.size() must equal width * height");
  }
  /// Label under a device position [m], or -1 off the image.
  [[nodiscard]] int label(const glm::dvec3& position) const noexcept {
    if (!is_finite(position)) return -1;
    const glm::dvec2 px = mapping_.to_image(position);
    const double x = std::floor(px.x + 0.5);
    const double y = std::floor(px.y + 0.5);
    if (!(x >= 0.0 && y >= 0.0 && x < width_ && y < height_)) return -1;
    return labels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
  }
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] std::uint16_t max_label() const noexcept {
    std::uint16_t m = 0;
    for (auto l : labels_)
      m = l > m ? l : m;
    return m;
  }
  [[nodiscard]] const PlaneMapping& mapping() const noexcept { return mapping_; }

 private:
  int width_;
  int height_;
  std::vector<std::uint16_t> labels_;
  PlaneMapping mapping_;
};

/// False texturing: the field of the region under the HIP; zero off the map.
class FalseTexture {
 public:
  /// @param textures  one field per label 0..max_label (an empty AnyField
  ///                  is a smooth region)
  /// @throws std::invalid_argument when a label has no texture.
  FalseTexture(LabelMap labels, std::vector<AnyField> textures)
      : labels_(std::move(labels)), textures_(std::move(textures)) {
    if (textures_.size() <= labels_.max_label())
      throw std::invalid_argument("FalseTexture: need one texture per label (0..max label)");
  }
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    const int l = labels_.label(probe.position);
    if (l < 0) return glm::dvec3{0.0};
    return textures_[static_cast<std::size_t>(l)].force(probe);
  }
  void reset() noexcept {
    for (auto& t : textures_)
      t.reset();
  }
  [[nodiscard]] int region(const glm::dvec3& position) const noexcept { return labels_.label(position); }
  [[nodiscard]] const LabelMap& labels() const noexcept { return labels_; }

 private:
  LabelMap labels_;
  std::vector<AnyField> textures_;
};

static_assert(ResettableField<FalseTexture>);

}  // namespace hapticfield::texture
