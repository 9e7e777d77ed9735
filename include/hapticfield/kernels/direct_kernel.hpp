#pragma once
/// @file direct_kernel.hpp
/// The paper's per-HIP kernel, the reference: the m x m patch of the
/// inverted image around the HIP, multiplied element by element with the x
/// and y masks and summed (Vasudevan & Manivannan 2008, section 3).
/// Cost per pixel: 2 m^2 multiply-adds.

#include <stdexcept>
#include <string>
#include <utility>

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// Thrown when a picture cannot carry the requested mask.
inline void validate_image_for_mask(const GrayImage& image, int mask_size) {
  if (image.empty()) throw std::invalid_argument("tangible image: the image is empty (0 x 0 px)");
  if (image.width() < mask_size || image.height() < mask_size)
    throw std::invalid_argument("tangible image: the image (" + std::to_string(image.width()) + " x " +
                                std::to_string(image.height()) + " px) is smaller than the " +
                                std::to_string(mask_size) + " x " + std::to_string(mask_size) + " mask");
}

template <int Size = dynamic_size>
class DirectKernel {
 public:
  /// @param inverted  the inverted image 255 - Y (see inverted())
  /// @throws std::invalid_argument when the image is empty or smaller than the mask.
  DirectKernel(const GrayImage& inverted, Mask<Size> mask, Border border)
      : mask_(std::move(mask)),
        border_(border),
        width_(inverted.width()),
        height_(inverted.height()),
        padded_((validate_image_for_mask(inverted, mask_.size()), inverted), mask_.size(), border),
        scale_(1.0 / mask_.step_response()) {}

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] int mask_size() const noexcept { return mask_.size(); }
  [[nodiscard]] int anchor() const noexcept { return mask_.anchor(); }
  [[nodiscard]] Border border() const noexcept { return border_; }
  [[nodiscard]] const Mask<Size>& mask() const noexcept { return mask_; }

  /// Normalised force at the centre of pixel (x, y), pointing toward darker
  /// pixels (a black/white step edge gives magnitude 1). The caller keeps
  /// (x, y) inside the image, and inside the full-mask region for
  /// suspend / fade.
  [[nodiscard]] glm::dvec2 at_pixel(int x, int y) const noexcept {
    const int m = mask_.size();
    const int a = mask_.anchor();
    const int pad = padded_.pad();
    double fx = 0.0;
    double fy = 0.0;
    for (int r = 0; r < m; ++r) {
      const double* row = padded_.row(y - a + r + pad) + (x - a + pad);
      for (int c = 0; c < m; ++c) {
        fx += row[c] * mask_.x(r, c);
        fy += row[c] * mask_.y(r, c);
      }
    }
    return glm::dvec2{fx * scale_, fy * scale_};
  }

 private:
  Mask<Size> mask_;
  Border border_;
  int width_;
  int height_;
  detail::PaddedImage padded_;
  double scale_;
};

}  // namespace hapticfield
