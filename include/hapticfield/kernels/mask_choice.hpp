#pragma once
/// @file mask_choice.hpp
/// Closed-form laws for choosing a Prewitt mask size, derived in
/// docs/tangible-images.md and verified by the section 5 experiment
/// (Vasudevan & Manivannan 2008, section 5: larger masks average noise away
/// but blur small features; higher resolution lets a larger mask feel the
/// same feature).

#include <cmath>
#include <stdexcept>

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/force_map.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// Standard deviation of each normalised force component of an m x m
/// Prewitt mask on white noise of standard deviation gray_noise_std [gray
/// levels]:  sigma_F = 2 sigma / (255 sqrt(3 h (h + 1))),  h = (m - 1) / 2.
/// A black/white edge gives 1, so 1 / sigma_F is the edge's SNR; it grows
/// about linearly with m.
/// @throws std::invalid_argument for a bad size or a negative / non-finite sigma.
[[nodiscard]] inline double prewitt_noise_std(int size, double gray_noise_std) {
  validate_mask_size(MaskKind::prewitt, size);
  if (!std::isfinite(gray_noise_std) || gray_noise_std < 0.0)
    throw std::invalid_argument("prewitt_noise_std: noise std must be finite and >= 0 [gray levels]");
  const double h = (size - 1) / 2.0;
  return 2.0 * gray_noise_std / (gray_full_scale * std::sqrt(3.0 * h * (h + 1.0)));
}

/// Measured standard deviation of fx and fy of an m x m Prewitt mask over
/// the region of a picture where the mask fits: how noisy the picture feels.
/// On white noise it matches prewitt_noise_std().
/// @throws std::invalid_argument as prewitt_force_map().
[[nodiscard]] inline glm::dvec2 prewitt_force_noise(const GrayImage& gray, int size) {
  const ForceMap map = prewitt_force_map(gray, size, Border::suspend);
  const int h = size / 2;
  double sx = 0.0, sxx = 0.0, sy = 0.0, syy = 0.0;
  double n = 0.0;
  for (int y = h; y < map.height - h; ++y)
    for (int x = h; x < map.width - h; ++x) {
      const double fx = map.fx[map.index(x, y)];
      const double fy = map.fy[map.index(x, y)];
      sx += fx, sxx += fx * fx, sy += fy, syy += fy * fy;
      n += 1.0;
    }
  return {std::sqrt(sxx / n - (sx / n) * (sx / n)), std::sqrt(syy / n - (sy / n) * (sy / n))};
}

/// Smallest separation [px] at which two thin (1 px) dark lines feel like
/// exactly two features through an m x m Prewitt mask (h = (m - 1) / 2):
/// d <= h + 1 pulls toward their midpoint and feels like one line;
/// h + 2 <= d <= 2h - 1 feels like both lines plus a phantom attractor
/// between them; d >= 2h = m - 1 feels like two, cleanly.
[[nodiscard]] inline int prewitt_min_separation_px(int size) {
  validate_mask_size(MaskKind::prewitt, size);
  return size - 1;
}

/// Largest odd Prewitt size that still separates two lines separation_mm
/// apart cleanly on a picture shown at px_per_mm; 0 when none does. Doubling
/// the resolution doubles the mask that can be used.
[[nodiscard]] inline int largest_separating_prewitt(double separation_mm, double px_per_mm) {
  if (!std::isfinite(separation_mm) || separation_mm <= 0.0 || !std::isfinite(px_per_mm) || px_per_mm <= 0.0)
    throw std::invalid_argument("largest_separating_prewitt: separation [mm] and resolution [px/mm] must be positive");
  const double d = std::floor(separation_mm * px_per_mm + 1e-9);  // [px]
  double m = d + 1.0;                                             // d >= m - 1
  if (std::fmod(m, 2.0) == 0.0) m -= 1.0;                         // odd sizes only
  if (m < min_mask_size) return 0;
  return m > max_mask_size ? max_mask_size : static_cast<int>(m);
}

}  // namespace hapticfield
