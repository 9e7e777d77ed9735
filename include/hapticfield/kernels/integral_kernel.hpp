#pragma once
/// @file integral_kernel.hpp
/// O(1)-per-pixel kernels for masks whose weights are linear in the column
/// (Prewitt) or a sign (block emboss), from integral images of the inverted
/// image and of its first moments (Crow 1984 summed-area tables):
///
///   Prewitt  Fx = sum P (c - x) = M1x(box) - (x - x0) M0(box)
///   emboss   Fx = M0(right half) - M0(left half)
///
/// with M0 the plain sum and M1x the sum of P (c - x0). Four table reads per
/// box whatever the mask size; equal to the direct kernel to rounding.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// True when MaskKind has an O(1) integral-image kernel.
[[nodiscard]] constexpr bool has_integral_kernel(MaskKind kind) noexcept {
  return kind == MaskKind::prewitt || kind == MaskKind::emboss;
}

class IntegralKernel {
 public:
  /// @param inverted  the inverted image 255 - Y
  /// @param kind      MaskKind::prewitt or MaskKind::emboss
  /// @param size      odd mask size 3..129 [px]
  /// @throws std::invalid_argument for another kind, a bad size, or an image
  ///         that is empty or smaller than the mask.
  IntegralKernel(const GrayImage& inverted, MaskKind kind, int size, Border border)
      : kind_(kind), size_(size), border_(border), width_(inverted.width()), height_(inverted.height()) {
    if (!has_integral_kernel(kind))
      throw std::invalid_argument(std::string("IntegralKernel: no O(1) kernel for mask ") + to_string(kind) +
                                  " (prewitt and emboss only)");
    validate_mask_size(kind, size);
    validate_image_for_mask(inverted, size);
    scale_ = 1.0 / Mask<>::make(kind, size).step_response();
    const detail::PaddedImage padded(inverted, size, border);
    pad_ = padded.pad();
    stride_ = padded.width() + 1;
    x0_ = padded.width() / 2;
    y0_ = padded.height() / 2;
    const std::size_t cells = static_cast<std::size_t>(stride_) * static_cast<std::size_t>(padded.height() + 1);
    sum_.assign(cells, 0.0);
    moment_x_.assign(cells, 0.0);
    moment_y_.assign(cells, 0.0);
    // Table (r + 1, c + 1) holds the sums over rows 0..r and columns 0..c.
    for (int r = 0; r < padded.height(); ++r) {
      const double* p = padded.row(r);
      double row_sum = 0.0;
      double row_mx = 0.0;
      const double dy = r - y0_;
      const std::size_t above = static_cast<std::size_t>(r) * stride_;
      const std::size_t here = above + stride_;
      for (int c = 0; c < padded.width(); ++c) {
        row_sum += p[c];
        row_mx += p[c] * (c - x0_);
        sum_[here + c + 1] = sum_[above + c + 1] + row_sum;
        moment_x_[here + c + 1] = moment_x_[above + c + 1] + row_mx;
        moment_y_[here + c + 1] = moment_y_[above + c + 1] + row_sum * dy;
      }
    }
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] int mask_size() const noexcept { return size_; }
  [[nodiscard]] int anchor() const noexcept { return size_ / 2; }
  [[nodiscard]] Border border() const noexcept { return border_; }
  [[nodiscard]] MaskKind kind() const noexcept { return kind_; }

  /// Normalised force at the centre of pixel (x, y); same contract as
  /// DirectKernel::at_pixel().
  [[nodiscard]] glm::dvec2 at_pixel(int x, int y) const noexcept {
    const int a = size_ / 2;
    const int cx = x + pad_;
    const int cy = y + pad_;
    const int c0 = cx - a;
    const int c1 = c0 + size_;  // exclusive
    const int r0 = cy - a;
    const int r1 = r0 + size_;  // exclusive
    if (kind_ == MaskKind::prewitt) {
      const double m0 = box(sum_, r0, r1, c0, c1);
      const double fx = box(moment_x_, r0, r1, c0, c1) - (cx - x0_) * m0;
      const double fy = box(moment_y_, r0, r1, c0, c1) - (cy - y0_) * m0;
      return glm::dvec2{fx * scale_, fy * scale_};
    }
    const double fx = box(sum_, r0, r1, cx + 1, c1) - box(sum_, r0, r1, c0, cx);
    const double fy = box(sum_, cy + 1, r1, c0, c1) - box(sum_, r0, cy, c0, c1);
    return glm::dvec2{fx * scale_, fy * scale_};
  }

 private:
  /// Sum over padded rows [r0, r1) and columns [c0, c1) of a table.
  [[nodiscard]] double box(const std::vector<double>& t, int r0, int r1, int c0, int c1) const noexcept {
    const std::size_t s = static_cast<std::size_t>(stride_);
    return t[r1 * s + c1] - t[r0 * s + c1] - t[r1 * s + c0] + t[r0 * s + c0];
  }

  MaskKind kind_;
  int size_;
  Border border_;
  int width_;
  int height_;
  int pad_ = 0;
  int stride_ = 0;
  int x0_ = 0;
  int y0_ = 0;
  double scale_ = 1.0;
  std::vector<double> sum_;
  std::vector<double> moment_x_;
  std::vector<double> moment_y_;
};

}  // namespace hapticfield
