#pragma once
/// @file property_map.hpp
/// One property of a surface over its texture coordinates: a constant, or a
/// picture (one channel of an image, any size) read by bilinear
/// interpolation; and an index picture read at the nearest texel (region
/// ids). Plain data (no OpenCV; material/material_image.hpp builds them from
/// images). Sampling is noexcept and allocation-free (servo path).
///
/// The picture covers uv [0, 1] x [0, 1] as a texture is laid on a mesh
/// (TriangleMesh uvs: u right, v up; the readers already turn glTF's v
/// down into v up): texel (i, j) (column i, row j from the top) is centred
/// at uv ((i + 0.5) / width, 1 - (j + 0.5) / height); UvLayout::v_down lays
/// row 0 at v = 0 instead. Outside
/// [0, 1] the picture repeats (UvWrap::repeat, the glTF default) or its
/// edge texels extend (UvWrap::clamp); between texel centres the value is
/// bilinear, so a property changes continuously across a region border.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

namespace hapticfield::material {

/// How uv outside [0, 1] reads a picture.
enum class UvWrap {
  repeat,  ///< the picture tiles the plane
  clamp,   ///< the edge texels extend
};

/// Where a picture lies in uv.
struct UvLayout {
  UvWrap wrap{UvWrap::repeat};
  bool v_down{false};  ///< row 0 at v = 0 (v grows down the picture); default: row 0 at v = 1
};

namespace detail {

/// One axis of a bilinear read: texels i0, i1 and the weight of i1.
struct Axis {
  int i0{0};
  int i1{0};
  double t{0.0};
};

/// Texel coordinate x (texel centres at integers) on an axis of n texels.
[[nodiscard]] inline Axis axis_of(double x, int n, UvWrap wrap) noexcept {
  const double f = std::floor(x);
  Axis a;
  a.t = x - f;
  if (wrap == UvWrap::clamp) {
    if (x <= 0.0) return Axis{0, 0, 0.0};
    if (x >= n - 1) return Axis{n - 1, n - 1, 0.0};
    a.i0 = static_cast<int>(f);
    a.i1 = a.i0 + 1;
    return a;
  }
  const double m = f - n * std::floor(f / n);  // f mod n, in [0, n)
  a.i0 = std::min(static_cast<int>(m), n - 1);
  a.i1 = a.i0 + 1 == n ? 0 : a.i0 + 1;
  return a;
}

/// uv -> texel coordinates (texel centres at integers); false for a
/// non-finite or huge uv.
[[nodiscard]] inline bool texel_of(glm::dvec2 uv, int width, int height, const UvLayout& layout, double& x,
                                   double& y) noexcept {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y) || std::fabs(uv.x) > 1e9 || std::fabs(uv.y) > 1e9) return false;
  const double v = layout.v_down ? uv.y : 1.0 - uv.y;
  x = uv.x * width - 0.5;
  y = v * height - 0.5;
  return true;
}

}  // namespace detail

/// A property over uv: a constant or a picture, read bilinearly.
class PropertyMap {
 public:
  /// A constant (0 by default). @throws std::invalid_argument when not finite.
  PropertyMap(double constant = 0.0) : constant_(constant) {  // NOLINT(google-explicit-constructor): a number is a map
    if (!std::isfinite(constant)) throw std::invalid_argument("PropertyMap: a constant property must be finite");
  }

  /// A picture of width x height values, row by row from the top row.
  /// @throws std::invalid_argument for an empty picture, a size that does
  ///         not match, or a value that is not finite.
  PropertyMap(int width, int height, std::vector<float> values, UvLayout layout = {})
      : width_(width), height_(height), values_(std::move(values)), layout_(layout) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("PropertyMap: the picture is empty");
    if (values_.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
      throw std::invalid_argument("PropertyMap: " + std::to_string(values_.size()) + " values for a " +
                                  std::to_string(width) + " x " + std::to_string(height) + " picture");
    for (std::size_t i = 0; i < values_.size(); ++i)
      if (!std::isfinite(values_[i]))
        throw std::invalid_argument("PropertyMap: picture value " + std::to_string(i) + " is not finite");
    double low = values_[0];
    double high = values_[0];
    for (const float v : values_) {
      low = std::fmin(low, v);
      high = std::fmax(high, v);
    }
    low_ = low;
    high_ = high;
    constant_ = low;
  }

  /// The value at uv; a non-finite uv reads the constant (a picture's least value).
  [[nodiscard]] double at(glm::dvec2 uv) const noexcept {
    if (values_.empty()) return constant_;
    double x = 0.0;
    double y = 0.0;
    if (!detail::texel_of(uv, width_, height_, layout_, x, y)) return constant_;
    const detail::Axis ax = detail::axis_of(x, width_, layout_.wrap);
    const detail::Axis ay = detail::axis_of(y, height_, layout_.wrap);
    const double v00 = texel(ax.i0, ay.i0);
    const double v10 = texel(ax.i1, ay.i0);
    const double v01 = texel(ax.i0, ay.i1);
    const double v11 = texel(ax.i1, ay.i1);
    const double top = v00 + ax.t * (v10 - v00);
    const double bottom = v01 + ax.t * (v11 - v01);
    return top + ay.t * (bottom - top);
  }

  [[nodiscard]] bool is_constant() const noexcept { return values_.empty(); }
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  /// Least and greatest value the map takes.
  [[nodiscard]] double lowest() const noexcept { return values_.empty() ? constant_ : low_; }
  [[nodiscard]] double highest() const noexcept { return values_.empty() ? constant_ : high_; }

 private:
  [[nodiscard]] double texel(int i, int j) const noexcept {
    return values_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i)];
  }

  double constant_{0.0};
  int width_{0};
  int height_{0};
  std::vector<float> values_;
  UvLayout layout_{};
  double low_{0.0};
  double high_{0.0};
};

/// Region ids over uv: a constant, or an index picture read at the nearest
/// texel (ids never blend).
class IndexMap {
 public:
  IndexMap(std::uint32_t constant = 0) : constant_(constant) {}  // NOLINT(google-explicit-constructor)

  /// @throws std::invalid_argument for an empty picture or a size that does not match.
  IndexMap(int width, int height, std::vector<std::uint32_t> ids, UvLayout layout = {})
      : width_(width), height_(height), ids_(std::move(ids)), layout_(layout) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("IndexMap: the picture is empty");
    if (ids_.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
      throw std::invalid_argument("IndexMap: " + std::to_string(ids_.size()) + " ids for a " + std::to_string(width) +
                                  " x " + std::to_string(height) + " picture");
    for (const std::uint32_t id : ids_)
      largest_ = id > largest_ ? id : largest_;
    constant_ = ids_[0];
  }

  /// The id of the texel nearest uv (the constant for a non-finite uv).
  [[nodiscard]] std::uint32_t at(glm::dvec2 uv) const noexcept {
    if (ids_.empty()) return constant_;
    double x = 0.0;
    double y = 0.0;
    if (!detail::texel_of(uv, width_, height_, layout_, x, y)) return constant_;
    return ids_[index(detail::axis_of(std::round(x), width_, layout_.wrap).i0,
                      detail::axis_of(std::round(y), height_, layout_.wrap).i0)];
  }

  /// The four texels around uv with their bilinear weights (ids may repeat);
  /// false for a non-finite uv. For switching between regions continuously.
  bool around(glm::dvec2 uv, std::uint32_t (&ids)[4], double (&weights)[4]) const noexcept {
    if (ids_.empty()) {
      ids[0] = ids[1] = ids[2] = ids[3] = constant_;
      weights[0] = 1.0;
      weights[1] = weights[2] = weights[3] = 0.0;
      return true;
    }
    double x = 0.0;
    double y = 0.0;
    if (!detail::texel_of(uv, width_, height_, layout_, x, y)) return false;
    const detail::Axis ax = detail::axis_of(x, width_, layout_.wrap);
    const detail::Axis ay = detail::axis_of(y, height_, layout_.wrap);
    ids[0] = ids_[index(ax.i0, ay.i0)];
    ids[1] = ids_[index(ax.i1, ay.i0)];
    ids[2] = ids_[index(ax.i0, ay.i1)];
    ids[3] = ids_[index(ax.i1, ay.i1)];
    weights[0] = (1.0 - ax.t) * (1.0 - ay.t);
    weights[1] = ax.t * (1.0 - ay.t);
    weights[2] = (1.0 - ax.t) * ay.t;
    weights[3] = ax.t * ay.t;
    return true;
  }

  /// The largest id in the map.
  [[nodiscard]] std::uint32_t largest() const noexcept { return ids_.empty() ? constant_ : largest_; }
  [[nodiscard]] bool is_constant() const noexcept { return ids_.empty(); }

 private:
  [[nodiscard]] std::size_t index(int i, int j) const noexcept {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i);
  }

  std::uint32_t constant_{0};
  int width_{0};
  int height_{0};
  std::vector<std::uint32_t> ids_;
  UvLayout layout_{};
  std::uint32_t largest_{0};
};

}  // namespace hapticfield::material
