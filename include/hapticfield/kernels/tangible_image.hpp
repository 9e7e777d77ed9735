#pragma once
/// @file tangible_image.hpp
/// TangibleImage: the tangible-images method configured at run time (mask
/// kind, size, border, gray weights), for tools and scenes chosen on the
/// command line. Prewitt and emboss use the O(1) integral kernel unless the
/// direct one is asked for; the other masks use the direct kernel.

#include <stdexcept>
#include <string>
#include <variant>

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/image_force.hpp"
#include "hapticfield/kernels/integral_kernel.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// Which per-pixel kernel evaluates the mask.
enum class KernelChoice {
  automatic,  ///< integral (O(1)) where it exists, else direct
  direct,     ///< the paper's patch x mask sum, always
  integral,   ///< O(1); prewitt and emboss only
};

struct TangibleConfig {
  MaskKind mask = MaskKind::prewitt;
  int size = 17;       ///< mask size [px]; 2 for Roberts, 3 for Scharr
  double sigma = 0.0;  ///< Gaussian-derivative sigma [px]; <= 0 picks size / 6
  Border border = Border::suspend;
  double fade_px = default_fade_px;  ///< ramp width for Border::fade [px]
  KernelChoice kernel = KernelChoice::automatic;
};

class TangibleImage {
 public:
  using Direct = ImageForce<DirectKernel<>>;
  using Integral = ImageForce<IntegralKernel>;

  /// @param gray  gray levels in [0, 255] (see to_gray()); inverted here
  /// @throws std::invalid_argument for a bad mask, sigma, fade width, an
  ///         integral kernel asked for a mask that has none, or an image
  ///         that is empty or smaller than the mask.
  TangibleImage(const GrayImage& gray, const TangibleConfig& options)
      : options_(options), force_(build(inverted_checked(gray, options), options)) {}

  /// The same from an image already inverted as inverted(gray) inverts it
  /// (255 - Y): no copy (video frames are prepared this way).
  /// @throws std::invalid_argument as the constructor.
  [[nodiscard]] static TangibleImage from_inverted(const GrayImage& inverted, const TangibleConfig& options) {
    return TangibleImage(checked(inverted, options), options, Inverted{});
  }

  /// Normalised force at image position (x, y) [px]; see ImageForce::at().
  [[nodiscard]] glm::dvec2 at(double x, double y) const noexcept {
    return std::visit([x, y](const auto& f) noexcept { return f.at(x, y); }, force_);
  }

  /// Normalised force at the centre of pixel (x, y); see ImageForce::at_pixel().
  [[nodiscard]] glm::dvec2 at_pixel(int x, int y) const noexcept {
    return std::visit([x, y](const auto& f) noexcept { return f.at_pixel(x, y); }, force_);
  }

  [[nodiscard]] int width() const noexcept {
    return std::visit([](const auto& f) noexcept { return f.width(); }, force_);
  }
  [[nodiscard]] int height() const noexcept {
    return std::visit([](const auto& f) noexcept { return f.height(); }, force_);
  }
  [[nodiscard]] const TangibleConfig& options() const noexcept { return options_; }
  /// True when the O(1) integral kernel is in use.
  [[nodiscard]] bool uses_integral_kernel() const noexcept { return std::holds_alternative<Integral>(force_); }

 private:
  struct Inverted {};
  TangibleImage(const GrayImage& inverted, const TangibleConfig& options, Inverted)
      : options_(options), force_(build(inverted, options)) {}

  static const GrayImage& checked(const GrayImage& gray, const TangibleConfig& options) {
    validate_mask_size(options.mask, options.size);
    validate_image_for_mask(gray, options.size);
    return gray;
  }
  static GrayImage inverted_checked(const GrayImage& gray, const TangibleConfig& options) {
    return inverted(checked(gray, options));
  }

  static std::variant<Direct, Integral> build(const GrayImage& inv, const TangibleConfig& o) {
    const bool integral =
        o.kernel == KernelChoice::integral || (o.kernel == KernelChoice::automatic && has_integral_kernel(o.mask));
    if (integral) return Integral(IntegralKernel(inv, o.mask, o.size, o.border), o.fade_px);
    return Direct(DirectKernel<>(inv, Mask<>::make(o.mask, o.size, o.sigma), o.border), o.fade_px);
  }

  TangibleConfig options_;
  std::variant<Direct, Integral> force_;
};

}  // namespace hapticfield
