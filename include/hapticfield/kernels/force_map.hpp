#pragma once
/// @file force_map.hpp
/// Force maps: the normalised force at every pixel centre as two float
/// planes, from any kernel, plus an O(1)-per-pixel Prewitt map built from
/// running sums that matches the per-pixel kernels to float rounding.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/image_force.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// fx and fy at every pixel centre, row-major, normalised (1 = a black/white
/// edge), x right and y down.
struct ForceMap {
  int width = 0;
  int height = 0;
  std::vector<float> fx;
  std::vector<float> fy;

  [[nodiscard]] std::size_t index(int x, int y) const noexcept {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
  }
  /// Largest force magnitude in the map.
  [[nodiscard]] double max_magnitude() const noexcept {
    double m = 0.0;
    for (std::size_t i = 0; i < fx.size(); ++i) m = std::max(m, std::hypot(double(fx[i]), double(fy[i])));
    return m;
  }
};

/// The map of anything with at_pixel(x, y), width() and height() (an
/// ImageForce or a TangibleImage): one kernel evaluation per pixel.
template <class Source>
[[nodiscard]] ForceMap force_map(const Source& source) {
  ForceMap map{source.width(), source.height(), {}, {}};
  map.fx.assign(static_cast<std::size_t>(map.width) * map.height, 0.0f);
  map.fy.assign(map.fx.size(), 0.0f);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const glm::dvec2 f = source.at_pixel(x, y);
      map.fx[map.index(x, y)] = static_cast<float>(f.x);
      map.fy[map.index(x, y)] = static_cast<float>(f.y);
    }
  }
  return map;
}

/// The Prewitt map of a gray picture in O(1) per pixel whatever the mask
/// size: a running vertical box sum B and first moment V down the columns,
/// then along each row a running sum of V (fy) and a running ramp over B
/// (fx). Equals force_map() of TangibleImage{prewitt, size, border} to float
/// rounding.
/// @throws std::invalid_argument as TangibleImage.
[[nodiscard]] inline ForceMap prewitt_force_map(const GrayImage& gray, int size, Border border,
                                                double fade_px = default_fade_px) {
  validate_mask_size(MaskKind::prewitt, size);
  validate_image_for_mask(gray, size);
  if (!std::isfinite(fade_px) || fade_px <= 0.0)
    throw std::invalid_argument("prewitt_force_map: fade width must be finite and positive [px]");
  const int h = size / 2;
  const int w = gray.width();
  const int ht = gray.height();
  const double scale = 1.0 / Mask<>::prewitt(size).step_response();

  // Inverted and padded by h: padded (x + h, y + h) is pixel (x, y).
  const detail::PaddedImage p(inverted(gray), h, border);
  const int pw = p.width();

  ForceMap map{w, ht, {}, {}};
  map.fx.assign(static_cast<std::size_t>(w) * ht, 0.0f);
  map.fy.assign(map.fx.size(), 0.0f);

  const bool full_mask = needs_full_mask(border);
  const int lo = full_mask ? h : 0;
  const int x_hi = full_mask ? w - 1 - h : w - 1;
  const int y_hi = full_mask ? ht - 1 - h : ht - 1;

  std::vector<double> box(static_cast<std::size_t>(pw), 0.0);     // B: sum over rows y-h..y+h
  std::vector<double> moment(static_cast<std::size_t>(pw), 0.0);  // V: sum of (row - y) P
  for (int i = -h; i <= h; ++i) {
    const double* r = p.row(lo + h + i);
    for (int c = 0; c < pw; ++c) {
      box[c] += r[c];
      moment[c] += i * r[c];
    }
  }
  for (int y = lo; y <= y_hi; ++y) {
    if (y > lo) {  // slide the column window down one row
      const double* out = p.row(y - 1);          // padded row of y - 1 - h
      const double* in = p.row(y + 2 * h);        // padded row of y + h
      for (int c = 0; c < pw; ++c) {
        box[c] += in[c] - out[c];
        moment[c] += h * out[c] + (h + 1) * in[c] - box[c];  // V(y) from V(y - 1)
      }
    }
    // Along the row: S = sum of B over the window, R = sum of j B[x + j],
    // T = sum of V over the window.
    double s = 0.0;
    double ramp = 0.0;
    double t = 0.0;
    for (int j = -h; j <= h; ++j) {
      const int c = lo + h + j;
      s += box[c];
      ramp += j * box[c];
      t += moment[c];
    }
    float* fx = &map.fx[map.index(0, y)];
    float* fy = &map.fy[map.index(0, y)];
    for (int x = lo; x <= x_hi; ++x) {
      if (x > lo) {
        const int leaving = x - 1;        // padded column of x - 1 - h
        const int entering = x + 2 * h;   // padded column of x + h
        s += box[entering] - box[leaving];
        ramp += h * box[leaving] + (h + 1) * box[entering] - s;  // R(x) from R(x - 1)
        t += moment[entering] - moment[leaving];
      }
      double gain = scale;
      if (border == Border::fade) {
        const double inside = std::min(std::min(x - lo, x_hi - x), std::min(y - lo, y_hi - y));
        gain *= std::clamp(inside / fade_px, 0.0, 1.0);
      }
      fx[x] = static_cast<float>(ramp * gain);
      fy[x] = static_cast<float>(t * gain);
    }
  }
  return map;
}

}  // namespace hapticfield
