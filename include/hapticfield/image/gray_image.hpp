#pragma once
/// @file gray_image.hpp
/// GrayImage: an owning, row-major plane of gray levels in [0, 255] (not
/// rounded), free of OpenCV so kernels can run on it without it.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticfield {

/// Full-scale gray level of the 8-bit range every plane is expressed in.
inline constexpr double gray_full_scale = 255.0;

class GrayImage {
 public:
  GrayImage() = default;

  /// A width x height plane filled with value.
  /// @throws std::invalid_argument for a non-positive size.
  GrayImage(int width, int height, double value = 0.0) : width_(width), height_(height) {
    if (width <= 0 || height <= 0)
      throw std::invalid_argument("GrayImage: size must be positive, got " + std::to_string(width) + " x " +
                                  std::to_string(height) + " px");
    pixels_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), value);
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] bool empty() const noexcept { return pixels_.empty(); }

  /// Gray level at column x, row y (no bounds check).
  [[nodiscard]] double at(int x, int y) const noexcept { return pixels_[index(x, y)]; }
  [[nodiscard]] double& at(int x, int y) noexcept { return pixels_[index(x, y)]; }

  [[nodiscard]] const double* row(int y) const noexcept { return pixels_.data() + index(0, y); }
  [[nodiscard]] double* row(int y) noexcept { return pixels_.data() + index(0, y); }
  [[nodiscard]] const std::vector<double>& pixels() const noexcept { return pixels_; }

 private:
  [[nodiscard]] std::size_t index(int x, int y) const noexcept {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
  }

  int width_ = 0;
  int height_ = 0;
  std::vector<double> pixels_;
};

/// The inverted image 255 - Y of the tangible-images paper: dark pixels
/// become high values, so a mask sum points toward darker pixels.
[[nodiscard]] inline GrayImage inverted(const GrayImage& gray) {
  GrayImage out = gray;
  for (int y = 0; y < out.height(); ++y) {
    double* r = out.row(y);
    for (int x = 0; x < out.width(); ++x)
      r[x] = gray_full_scale - r[x];
  }
  return out;
}

}  // namespace hapticfield
