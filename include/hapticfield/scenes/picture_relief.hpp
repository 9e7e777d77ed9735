#pragma once
/// @file picture_relief.hpp
/// picture_relief(): a picture felt as a relief in one line. Its gray
/// levels become heights (a HeightFieldShape under a ProxyConstraint) and
/// its tangible-image forces (Vasudevan & Manivannan, Haptics Symposium
/// 2008) are laid on that relief as a texture in its tangent plane
/// (on_surface), so the HIP rests on the picture's hills and is pushed
/// toward its darker pixels along them:
///
///   auto relief = hapticfield::picture_relief("photo.png", {.mm_per_level = 0.02, .width_m = 0.1});
///   glm::dvec3 f = relief.force(probe);  // Fc + the picture's force along the surface [N]
///
/// Geometry: pixel (column c, row r) of a W x H picture sits at
/// x = c s, y = (H - 1 - r) s, z = level x mm_per_level / 1000 [m] with the
/// pitch s = width_m / (W - 1): the footprint is width_m wide, its bottom-
/// left pixel at the origin, x right, y up the picture, z toward the user
/// (io::load_height_picture's frame). The tangible image is evaluated at
/// the same pixel the touched point lies over (the relief's uv mapped onto
/// the picture's pixels), its image force (1 at a black/white edge) times
/// texture_gain [N], in the tangent plane: image x along the surface's
/// +u tangent, image y (down the picture) along -v.
///
/// A composition of surface/, kernels/ and io/height_map.hpp; built once,
/// never in a tick. The force() of the result is the servo path (no
/// allocation, no exception).

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <opencv2/core.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/image/load.hpp"
#include "hapticfield/io/height_map.hpp"
#include "hapticfield/kernels/tangible_field.hpp"
#include "hapticfield/kernels/tangible_image.hpp"
#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/on_surface.hpp"
#include "hapticfield/surface/proxy.hpp"

namespace hapticfield {

/// How a picture becomes a relief with its tangible-image texture.
struct PictureReliefConfig {
  double mm_per_level = 0.01;     ///< height of one gray level [mm] (255 levels: 2.55 mm)
  double width_m = 0.1;           ///< width of the picture on the surface, first to last pixel centre [m]
  bool dark_is_high = false;      ///< true: black is the top; false (default): white is, dark pixels are valleys
  double blur_sigma = 0.0;        ///< Gaussian blur of the heights (not of the texture) [px]; 0: none
  double stiffness = 1500.0;      ///< k of the proxy [N/m]
  double damping = 0.0;           ///< b on the normal velocity while touching [N s/m]
  double static_friction = 0.0;   ///< mu_s of the proxy [-]
  double dynamic_friction = 0.0;  ///< mu_k of the proxy [-], <= mu_s
  double radius = 0.0;            ///< the tool's radius [m] (ProxyConfig::radius); 0: a point
  double texture_gain = 1.0;      ///< tangible-image force at a black/white edge [N]; 0: relief only
  TangibleConfig tangible{};      ///< mask, size, border of the tangible image (Prewitt 17 x 17 by default)
  GrayWeights weights = GrayWeights::paper;       ///< colour -> gray
  std::uint64_t max_pixels = default_max_pixels;  ///< largest picture accepted [px]
};

/// The texture of a relief: the tangible image laid on the surface.
using PictureReliefTexture = OnSurface<TangibleImageField<TangibleImage>>;
/// What picture_relief() returns: Fc of the proxy on the relief + the
/// picture's tangible-image force along the surface.
using PictureRelief = ContactField<ProxyConstraint<HeightFieldShape>, PictureReliefTexture>;

namespace detail {

inline void check_relief_config(const PictureReliefConfig& c) {
  if (!std::isfinite(c.width_m) || c.width_m <= 0.0)
    throw std::invalid_argument("picture_relief: width_m must be finite and > 0 [m], got " + std::to_string(c.width_m));
  if (!std::isfinite(c.texture_gain) || c.texture_gain < 0.0)
    throw std::invalid_argument("picture_relief: texture_gain must be finite and >= 0 [N], got " +
                                std::to_string(c.texture_gain));
}

}  // namespace detail

/// A relief from gray levels already in memory (0..255, see to_gray()).
/// @throws std::invalid_argument for a picture narrower or lower than 2 px
///         or than the tangible mask, or bad settings (proxy, mask, sizes).
[[nodiscard]] inline PictureRelief picture_relief(const GrayImage& gray, const PictureReliefConfig& config = {}) {
  detail::check_relief_config(config);
  if (gray.width() < 2 || gray.height() < 2)
    throw std::invalid_argument("picture_relief: the picture must be at least 2 x 2 px, got " +
                                std::to_string(gray.width()) + " x " + std::to_string(gray.height()));
  const double pitch = config.width_m / (gray.width() - 1.0);  // [m per px]
  io::PictureHeightConfig heights;
  heights.pixel_size = pitch;
  heights.mm_per_level = config.mm_per_level;
  heights.dark_is_high = config.dark_is_high;
  heights.blur_sigma = config.blur_sigma;
  heights.weights = config.weights;
  heights.max_pixels = config.max_pixels;
  const io::HeightGrid grid = io::height_grid_from_gray(gray, heights);
  ProxyConstraint<HeightFieldShape> proxy(HeightFieldShape(grid),
                                          ProxyConfig{.stiffness = config.stiffness,
                                                      .damping = config.damping,
                                                      .static_friction = config.static_friction,
                                                      .dynamic_friction = config.dynamic_friction,
                                                      .radius = config.radius});
  // uv (0..1 over the footprint) -> the flat frame in metres, x right and
  // y up from the bottom-left pixel; that frame -> pixels, y down from the
  // top row.
  const glm::dvec2 footprint{config.width_m, pitch * (gray.height() - 1.0)};
  const PlaneMapping to_pixels(1e-3 / pitch, glm::dvec2{0.0, gray.height() - 1.0});
  TangibleImageField<TangibleImage> texture(TangibleImage(gray, config.tangible), to_pixels, config.texture_gain);
  return contact(std::move(proxy), on_surface(std::move(texture), UvMapping{footprint, glm::dvec2{0.0}}));
}

/// A relief from a picture in memory (8- or 16-bit, gray, BGR or BGRA).
/// @throws std::invalid_argument for an empty picture, an unsupported
///         pixel format, or as picture_relief(GrayImage).
[[nodiscard]] inline PictureRelief picture_relief(const cv::Mat& picture, const PictureReliefConfig& config = {}) {
  return picture_relief(to_gray(picture, config.weights), config);
}

/// A relief from a picture file (PNG, JPEG, BMP, TIFF, Netpbm...).
/// @throws ImageError (a FileError) naming the file when it is missing,
///         too large (checked from its header) or cannot be decoded;
///         std::invalid_argument as picture_relief(GrayImage).
[[nodiscard]] inline PictureRelief picture_relief(const std::string& path, const PictureReliefConfig& config = {}) {
  detail::check_relief_config(config);
  return picture_relief(load_gray(path, config.weights, config.max_pixels), config);
}

/// The same for a string literal (picks the file overload, not cv::Mat's).
[[nodiscard]] inline PictureRelief picture_relief(const char* path, const PictureReliefConfig& config = {}) {
  return picture_relief(std::string(path), config);
}

}  // namespace hapticfield
