#pragma once
/// @file model_relief.hpp
/// A model felt as it looks, with its picture's relief: relief_model(loaded
/// mesh, height) is textured_model() (scenes/model_texture.hpp: the
/// base-colour picture as a tangible-image texture laid by uv, at the size
/// the uvs give it) plus the picture's gray levels as a relief of small
/// height on the mesh (material/uv_relief.hpp: white stands `height` metres
/// up, black lies on the mesh), felt by haptic bump mapping. The
/// tangible-image texture can be turned off with a texture_gain of 0, to
/// feel the relief alone. Built once; the force() of the result is the
/// servo path (no allocation, no exception).

#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <opencv2/core.hpp>

#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/material/material_image.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/material/material_surface.hpp"
#include "hapticfield/material/uv_relief.hpp"
#include "hapticfield/scenes/model_texture.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/on_surface.hpp"

namespace hapticfield::material {

/// A shape felt with a picture as texture and as relief (relief_surface()).
template <Shape S>
using ReliefSurface = MaterialSurface<S, OnSurface<TangibleImageField<TangibleImage>>, OnSurface<UvRelief>>;
/// The field relief_model() returns.
using ReliefModel = ReliefSurface<MeshShape>;

/// The picture's gray levels (to_gray: 0..255) as heights 0..height [m]
/// over uv (row 0 at v = 1, as mesh uvs are v up).
/// @throws std::invalid_argument for an empty picture or a height that is
///         not finite and >= 0.
[[nodiscard]] inline PropertyMap relief_heights(const cv::Mat& picture, double height) {
  if (!std::isfinite(height) || height < 0.0)
    throw std::invalid_argument("relief_heights: the relief height must be finite and >= 0 [m]");
  if (picture.empty()) throw std::invalid_argument("relief_heights: the picture is empty");
  const GrayImage gray = to_gray(picture);
  cv::Mat levels(gray.height(), gray.width(), CV_32FC1);
  for (int y = 0; y < gray.height(); ++y)
    for (int x = 0; x < gray.width(); ++x)
      levels.at<float>(y, x) = static_cast<float>(gray.at(x, y) / 255.0);  // to_gray gives 0..255
  return property_map_from_image(levels, 0, 0.0, height);
}

/// textured_surface() of `shape` plus the picture's relief, `height` [m] at
/// white, on the proxy's stiffness.
/// @throws std::invalid_argument as textured_surface() and relief_heights().
template <Shape S>
[[nodiscard]] ReliefSurface<std::remove_cvref_t<S>> relief_surface(S&& shape, const cv::Mat& picture, double metres,
                                                                   double height,
                                                                   const ModelTextureConfig& config = {}) {
  if (picture.empty()) throw std::invalid_argument("relief_surface: the picture is empty");
  const PictureOnUv lay = picture_on_uv(picture.cols, picture.rows, metres);
  MaterialMaps maps;
  maps.stiffness = config.proxy.stiffness;
  maps.damping = config.proxy.damping;
  maps.static_friction = config.proxy.static_friction;
  maps.dynamic_friction = config.proxy.dynamic_friction;
  maps.vibration = per_primitive_material;
  TangibleImageField<TangibleImage> image(TangibleImage(to_gray(picture), config.tangible), lay.plane,
                                          config.texture_gain);
  return ReliefSurface<std::remove_cvref_t<S>>(
      std::forward<S>(shape), config.proxy, MaterialMap(std::move(maps)),
      OnSurface<TangibleImageField<TangibleImage>>(std::move(image), lay.uv),
      OnSurface<UvRelief>(UvRelief(relief_heights(picture, height), config.proxy.stiffness, metres), UvMapping{}));
}

/// The loaded mesh felt with its own base-colour texture and its relief
/// (`height` [m] at white): relief_surface() of its MeshShape, its
/// material's picture and its metres_per_uv().
/// @throws std::invalid_argument as textured_model() and relief_heights().
[[nodiscard]] inline ReliefModel relief_model(io::LoadedMesh loaded, double height,
                                              const ModelTextureConfig& config = {}) {
  const cv::Mat picture = base_colour_picture(loaded, config.material);
  const double metres = metres_per_uv(loaded.mesh);
  return relief_surface(MeshShape(std::move(loaded.mesh), config.shape), picture, metres, height, config);
}

}  // namespace hapticfield::material
