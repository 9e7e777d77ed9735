#pragma once
/// @file border.hpp
/// What a mask sees where it would leave the image.

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "hapticfield/image/gray_image.hpp"

namespace hapticfield {

enum class Border {
  suspend,  ///< the paper: no force where the mask leaves the image
  clamp,    ///< pixels beyond the edge repeat the edge pixel (aaa|abc)
  reflect,  ///< mirror about the edge pixel (cb|abc, OpenCV's BORDER_REFLECT_101)
  fade,     ///< as suspend, with the force ramped to zero over the last k px
};

/// Every border policy, in the order the tools list them.
inline constexpr std::array<Border, 4> border_kinds{Border::suspend, Border::clamp, Border::reflect, Border::fade};

[[nodiscard]] constexpr const char* to_string(Border border) noexcept {
  switch (border) {
    case Border::suspend:
      return "suspend";
    case Border::clamp:
      return "clamp";
    case Border::reflect:
      return "reflect";
    case Border::fade:
      return "fade";
  }
  return "?";
}

/// True when the border policy evaluates only masks that lie inside the image.
[[nodiscard]] constexpr bool needs_full_mask(Border border) noexcept {
  return border == Border::suspend || border == Border::fade;
}

namespace detail {

/// Index of the source pixel for padded coordinate i in [-pad, n + pad).
[[nodiscard]] inline int border_index(int i, int n, Border border) noexcept {
  if (i >= 0 && i < n) return i;
  if (border == Border::reflect) {
    if (n == 1) return 0;
    const int period = 2 * (n - 1);
    int m = i % period;
    if (m < 0) m += period;
    return m < n ? m : period - m;
  }
  return std::clamp(i, 0, n - 1);  // clamp; suspend/fade never read these
}

/// An image with `pad` extra pixels on every side, filled by the border
/// policy (zeros for suspend and fade, which never read them).
class PaddedImage {
 public:
  PaddedImage(const GrayImage& image, int pad, Border border)
      : pad_(pad),
        width_(image.width() + 2 * pad),
        height_(image.height() + 2 * pad),
        pixels_(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0) {
    const bool fill = !needs_full_mask(border);
    for (int y = 0; y < height_; ++y) {
      const int sy = y - pad;
      if (!fill && (sy < 0 || sy >= image.height())) continue;
      const double* src = image.row(border_index(sy, image.height(), border));
      double* dst = &pixels_[static_cast<std::size_t>(y) * width_];
      for (int x = 0; x < width_; ++x) {
        const int sx = x - pad;
        if (!fill && (sx < 0 || sx >= image.width())) continue;
        dst[x] = src[border_index(sx, image.width(), border)];
      }
    }
  }

  [[nodiscard]] int pad() const noexcept { return pad_; }
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  /// Row y of the padded plane (y in padded coordinates).
  [[nodiscard]] const double* row(int y) const noexcept { return &pixels_[static_cast<std::size_t>(y) * width_]; }

 private:
  int pad_;
  int width_;
  int height_;
  std::vector<double> pixels_;
};

}  // namespace detail
}  // namespace hapticfield
