#pragma once
/// @file image_force.hpp
/// ImageForce: the force at any continuous image position, from a per-pixel
/// kernel. Integer coordinates are pixel centres; between them the four
/// surrounding pixel forces are interpolated bilinearly, so a HIP moving
/// slowly never feels a step. The border policy decides what lies beyond the
/// region where the mask fits, and every policy fades the force out over a
/// band at the edge, so leaving the picture is no step either.

#include <algorithm>
#include <cmath>
#include <concepts>
#include <stdexcept>
#include <utility>

#include <glm/vec2.hpp>

#include "hapticfield/kernels/border.hpp"

namespace hapticfield {

/// A kernel that gives the normalised force at a pixel centre.
template <class K>
concept PixelKernel = requires(const K& k, int x, int y) {
  { k.at_pixel(x, y) }
  noexcept->std::same_as<glm::dvec2>;
  { k.width() } -> std::convertible_to<int>;
  { k.height() } -> std::convertible_to<int>;
  { k.mask_size() } -> std::convertible_to<int>;
  { k.anchor() } -> std::convertible_to<int>;
  { k.border() } -> std::same_as<Border>;
};

/// Default width of the band over which the force fades to zero at the
/// edge of the evaluated region, for every border policy [px]. A hand at
/// 0.1 m/s on a 6.4 px/mm picture moves 0.64 px per 1 kHz tick; the fade
/// alone then changes the force by at most 0.64 / 10 = 6.4% of the edge
/// force per tick, below the 7% force JND.
inline constexpr double default_fade_px = 10.0;

/// Force at any continuous image position, continuous along any path,
/// leaving the picture included.
///
/// The kernel is evaluated in a domain of pixel centres: the picture for
/// clamp and reflect, the pixels where the whole mask fits for suspend and
/// fade. Inside it, forces are interpolated bilinearly. Beyond it, every
/// policy carries the force of the nearest domain point outward and fades
/// it linearly to zero over fade_px [px] (Euclidean distance to the
/// domain), so no path meets a step:
///   - clamp, reflect: the edge force, faded over fade_px outside the picture;
///   - suspend: the paper's region; the last full-mask force fades over
///     fade_px beyond it (into the picture's margin, then outside);
///   - fade: ramps to zero over the last fade_px inside the full-mask region
///     and is zero everywhere beyond it.
template <PixelKernel Kernel>
class ImageForce {
 public:
  /// @param fade_px  width of the fade band [px], finite and > 0
  /// @throws std::invalid_argument for a bad fade width.
  explicit ImageForce(Kernel kernel, double fade_px = default_fade_px) : kernel_(std::move(kernel)), fade_px_(fade_px) {
    if (!std::isfinite(fade_px) || fade_px <= 0.0)
      throw std::invalid_argument("ImageForce: fade width must be finite and positive [px]");
    const int a = kernel_.anchor();
    const int tail = kernel_.mask_size() - 1 - a;  // pixels the mask reaches past its anchor
    if (needs_full_mask(kernel_.border())) {
      x_lo_ = a;
      y_lo_ = a;
      x_hi_ = kernel_.width() - 1 - tail;
      y_hi_ = kernel_.height() - 1 - tail;
    } else {
      x_lo_ = 0;
      y_lo_ = 0;
      x_hi_ = kernel_.width() - 1;
      y_hi_ = kernel_.height() - 1;
    }
  }

  /// Normalised force at image position (x, y) [px] (x right, y down): a
  /// black/white step edge gives magnitude 1 toward black. Zero for
  /// non-finite positions and from fade_px beyond the domain on (see the
  /// class comment).
  [[nodiscard]] glm::dvec2 at(double x, double y) const noexcept {
    if (!std::isfinite(x) || !std::isfinite(y)) return glm::dvec2{0.0};
    const double cx = std::clamp(x, double(x_lo_), double(x_hi_));
    const double cy = std::clamp(y, double(y_lo_), double(y_hi_));
    double outside = 1.0;  // fade beyond the domain
    if (cx != x || cy != y) {
      const double d = std::hypot(x - cx, y - cy);  // [px] to the nearest domain point
      if (!(d < fade_px_)) return glm::dvec2{0.0};
      outside = 1.0 - d / fade_px_;
    }
    const double xf = std::floor(cx);
    const double yf = std::floor(cy);
    const int x0 = static_cast<int>(xf);
    const int y0 = static_cast<int>(yf);
    const double tx = cx - xf;
    const double ty = cy - yf;
    glm::dvec2 f{0.0};
    f += corner(x0, y0, (1.0 - tx) * (1.0 - ty));
    f += corner(x0 + 1, y0, tx * (1.0 - ty));
    f += corner(x0, y0 + 1, (1.0 - tx) * ty);
    f += corner(x0 + 1, y0 + 1, tx * ty);
    if (kernel_.border() == Border::fade) f *= fade(cx, cy);
    return outside * f;
  }

  /// Normalised force at the centre of pixel (x, y) exactly as the border
  /// policy defines it (both fades included): what at(x, y) returns there.
  [[nodiscard]] glm::dvec2 at_pixel(int x, int y) const noexcept {
    if (in_domain(x, y)) {
      glm::dvec2 f = kernel_.at_pixel(x, y);
      if (kernel_.border() == Border::fade) f *= fade(x, y);
      return f;
    }
    return at(x, y);
  }

  [[nodiscard]] const Kernel& kernel() const noexcept { return kernel_; }
  [[nodiscard]] int width() const noexcept { return kernel_.width(); }
  [[nodiscard]] int height() const noexcept { return kernel_.height(); }

  /// True when pixel (x, y) is in the region where the kernel is evaluated.
  [[nodiscard]] bool in_domain(int x, int y) const noexcept {
    return x >= x_lo_ && x <= x_hi_ && y >= y_lo_ && y <= y_hi_;
  }

 private:
  /// One bilinear corner; (x, y) lies in the domain whenever weight != 0.
  [[nodiscard]] glm::dvec2 corner(int x, int y, double weight) const noexcept {
    if (weight == 0.0) return glm::dvec2{0.0};
    return weight * kernel_.at_pixel(x, y);
  }

  /// Linear ramp from 0 at the last pixel where the mask fits to 1 at
  /// fade_px inside it.
  [[nodiscard]] double fade(double x, double y) const noexcept {
    const double inside = std::min(std::min(x - x_lo_, x_hi_ - x), std::min(y - y_lo_, y_hi_ - y));
    return std::clamp(inside / fade_px_, 0.0, 1.0);
  }

  Kernel kernel_;
  double fade_px_;
  int x_lo_ = 0;
  int y_lo_ = 0;
  int x_hi_ = -1;
  int y_hi_ = -1;
};

}  // namespace hapticfield
