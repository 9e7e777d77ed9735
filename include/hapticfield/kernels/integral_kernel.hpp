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
    table_.assign(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(padded.height() + 1), Cell{});
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
        const Cell& up = table_[above + c + 1];
        table_[here + c + 1] = Cell{up.sum + row_sum, up.moment_x + row_mx, up.moment_y + row_sum * dy};
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
      const Cell b = box(r0, r1, c0, c1);
      const double fx = b.moment_x - (cx - x0_) * b.sum;
      const double fy = b.moment_y - (cy - y0_) * b.sum;
      return glm::dvec2{fx * scale_, fy * scale_};
    }
    const double fx = box(r0, r1, cx + 1, c1).sum - box(r0, r1, c0, cx).sum;
    const double fy = box(cy + 1, r1, c0, c1).sum - box(r0, cy, c0, c1).sum;
    return glm::dvec2{fx * scale_, fy * scale_};
  }

 private:
  /// The three tables side by side, so one cache line serves all of them.
  struct Cell {
    double sum = 0.0;       ///< sum of P
    double moment_x = 0.0;  ///< sum of P (c - x0)
    double moment_y = 0.0;  ///< sum of P (r - y0)
  };

  /// Sums over padded rows [r0, r1) and columns [c0, c1).
  [[nodiscard]] Cell box(int r0, int r1, int c0, int c1) const noexcept {
    const std::size_t s = static_cast<std::size_t>(stride_);
    const Cell& a = table_[r1 * s + c1];
    const Cell& b = table_[r0 * s + c1];
    const Cell& c = table_[r1 * s + c0];
    const Cell& d = table_[r0 * s + c0];
    return Cell{a.sum - b.sum - c.sum + d.sum, a.moment_x - b.moment_x - c.moment_x + d.moment_x,
                a.moment_y - b.moment_y - c.moment_y + d.moment_y};
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
  std::vector<Cell> table_;
};

}  // namespace hapticfield
