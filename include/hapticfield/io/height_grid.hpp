#pragma once
/// @file height_grid.hpp
/// HeightGrid: heights on a regular grid [m], plain data (std only), as the
/// height-map readers (height_map.hpp) fill it and a height-field shape
/// takes it. Never used in a tick.

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticfield::io {

/// Heights on a width x height grid, row-major: heights[j * width + i] is
/// the height [m] at x = i * spacing_x, y = j * spacing_y. Row j = 0 is the
/// bottom row of the picture it came from, so x points right, y up and the
/// height toward the viewer (a right-handed frame seen from above).
struct HeightGrid {
  int width = 0;                ///< samples along x
  int height = 0;               ///< samples along y
  double spacing_x = 0.0;       ///< distance between samples along x [m]
  double spacing_y = 0.0;       ///< distance between samples along y [m]
  std::vector<double> heights;  ///< [m], width x height, row-major

  /// Height at column i, row j [m] (no bounds check).
  [[nodiscard]] double at(int i, int j) const noexcept {
    return heights[static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + static_cast<std::size_t>(i)];
  }

  /// Checks a positive size, finite positive spacings, width x height
  /// heights, all finite.
  /// @throws std::invalid_argument naming the first problem.
  void validate() const {
    if (width <= 0 || height <= 0)
      throw std::invalid_argument("HeightGrid: size must be positive, got " + std::to_string(width) + " x " +
                                  std::to_string(height));
    if (!std::isfinite(spacing_x) || !std::isfinite(spacing_y) || spacing_x <= 0.0 || spacing_y <= 0.0)
      throw std::invalid_argument("HeightGrid: spacings must be finite and positive, got " + std::to_string(spacing_x) +
                                  " x " + std::to_string(spacing_y) + " m");
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (heights.size() != n)
      throw std::invalid_argument("HeightGrid: " + std::to_string(heights.size()) + " heights for " +
                                  std::to_string(width) + " x " + std::to_string(height));
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(heights[k]))
        throw std::invalid_argument("HeightGrid: height at column " + std::to_string(k % std::size_t(width)) +
                                    ", row " + std::to_string(k / std::size_t(width)) + " is not finite");
  }
};

}  // namespace hapticfield::io
