#pragma once
/// @file model_texture.hpp
/// A model felt as it looks, in one call: textured_model(loaded mesh) lays
/// the mesh's base-colour texture (glTF baseColorTexture, kept by the
/// reader in io::LoadedMesh::base_colour_textures) on its surface by uv as
/// a tangible-image texture (Vasudevan & Manivannan, Haptics Symposium
/// 2008; kernels/tangible_field.hpp): a proxy on the mesh
/// (MaterialSurface) plus the picture's image force in the tangent plane.
/// Needs hapticfield::io and hapticfield::image (OpenCV).
///
/// The picture's size on the surface is measured, not guessed: each
/// triangle's metres per uv unit is sqrt(area in space / area in uv), their
/// median is the model's (metres_per_uv()), and a picture of W x H pixels
/// over uv [0, 1]^2 then has pixels metres_per_uv / W wide. (A non-square
/// picture is laid with that pixel size along u and v both, so its v span
/// is metres_per_uv H / W: textures are square in nearly every model.)

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/kernels/tangible_field.hpp"
#include "hapticfield/kernels/tangible_image.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/material/material_surface.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/on_surface.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield::material {

/// The median over the mesh's triangles of sqrt(area [m^2] / uv area) [m
/// per uv unit]; triangles with no uv area are left out.
/// @throws std::invalid_argument for a mesh without uvs or with no triangle of uv area.
[[nodiscard]] inline double metres_per_uv(const TriangleMesh& mesh) {
  if (!mesh.has_uvs()) throw std::invalid_argument("metres_per_uv: the mesh has no texture coordinates");
  std::vector<double> ratios;
  ratios.reserve(mesh.triangles.size());
  for (const TriangleIndices& t : mesh.triangles) {
    const glm::dvec3 e1 = mesh.positions[t[1]] - mesh.positions[t[0]];
    const glm::dvec3 e2 = mesh.positions[t[2]] - mesh.positions[t[0]];
    const glm::dvec2 f1 = mesh.uvs[t[1]] - mesh.uvs[t[0]];
    const glm::dvec2 f2 = mesh.uvs[t[2]] - mesh.uvs[t[0]];
    const double area = 0.5 * glm::length(glm::cross(e1, e2));  // [m^2]
    const double uv_area = 0.5 * std::fabs(f1.x * f2.y - f1.y * f2.x);
    if (uv_area > 1e-14 && area > 0.0 && std::isfinite(area / uv_area)) ratios.push_back(std::sqrt(area / uv_area));
  }
  if (ratios.empty()) throw std::invalid_argument("metres_per_uv: no triangle has an area in uv");
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  return *middle;
}

/// The decoded base-colour picture of material `material` of a loaded mesh.
/// @throws std::invalid_argument when that material has no base-colour
///         texture or its bytes are not a picture OpenCV decodes.
[[nodiscard]] inline cv::Mat base_colour_picture(const io::LoadedMesh& loaded, std::size_t material = 0) {
  if (material >= loaded.base_colour_textures.size() || loaded.base_colour_textures[material].empty())
    throw std::invalid_argument("base_colour_picture: material " + std::to_string(material) +
                                " has no base-colour texture (" + std::to_string(loaded.base_colour_textures.size()) +
                                " materials with textures listed)");
  const std::vector<unsigned char>& bytes = loaded.base_colour_textures[material];
  cv::Mat picture;
  try {
    picture =
        cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<unsigned char*>(bytes.data())),
                     cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(std::string("base_colour_picture: cannot decode the texture: ") + e.what());
  }
  if (picture.empty())
    throw std::invalid_argument("base_colour_picture: the texture of material " + std::to_string(material) +
                                " is not a picture OpenCV can decode");
  return picture;
}

struct ModelTextureConfig {
  ProxyConfig proxy{};        ///< stiffness, damping, friction, offset, radius of the contact
  double texture_gain{0.5};   ///< image force at a black/white edge [N]
  TangibleConfig tangible{};  ///< the tangible-image mask
  std::size_t material{0};    ///< whose base-colour texture is felt (index into material_names)
  MeshShapeConfig shape{};    ///< force shading, node budget
};

/// A shape felt with a picture laid on it by uv (textured_surface()).
template <Shape S>
using TexturedSurface = MaterialSurface<S, OnSurface<TangibleImageField<TangibleImage>>>;
/// The field textured_model() returns.
using TexturedModel = TexturedSurface<MeshShape>;

/// The uv mapping and plane mapping that lay a W x H picture over uv
/// [0, 1]^2 at `metres` per uv unit (row 0 at v = 1, as mesh uvs are v up).
struct PictureOnUv {
  UvMapping uv;
  PlaneMapping plane;
};
[[nodiscard]] inline PictureOnUv picture_on_uv(int width, int height, double metres) {
  if (width <= 0 || height <= 0 || !std::isfinite(metres) || metres <= 0.0)
    throw std::invalid_argument("picture_on_uv: a picture size > 0 [px] and metres per uv > 0 [m] are needed");
  const double px_per_m = width / metres;
  // flat (x, y) = metres (u, v H / W): image x = px_per_m x - 0.5, image y = H - 0.5 - px_per_m y
  return PictureOnUv{UvMapping{glm::dvec2{metres, metres * height / width}, glm::dvec2{0.0}},
                     PlaneMapping(px_per_m / 1000.0, glm::dvec2{-0.5, height - 0.5})};
}

/// textured_surface() (below) with the material read from `map` at the touched uv (a haptic
/// material's maps, io/gltf_haptic_material.hpp) instead of the proxy's
/// constants; config.proxy still gives the contact's offset and radius.
template <Shape S>
[[nodiscard]] TexturedSurface<std::remove_cvref_t<S>> textured_surface(S&& shape, const cv::Mat& picture, double metres,
                                                                       MaterialMap map,
                                                                       const ModelTextureConfig& config = {}) {
  if (picture.empty()) throw std::invalid_argument("textured_surface: the picture is empty");
  const PictureOnUv lay = picture_on_uv(picture.cols, picture.rows, metres);
  TangibleImageField<TangibleImage> image(TangibleImage(to_gray(picture), config.tangible), lay.plane,
                                          config.texture_gain);
  return TexturedSurface<std::remove_cvref_t<S>>(
      std::forward<S>(shape), config.proxy, std::move(map),
      OnSurface<TangibleImageField<TangibleImage>>(std::move(image), lay.uv));
}

/// Any shape with uvs (a mesh, posed or not) felt with `picture` laid on it
/// by uv at `metres` per uv unit (metres_per_uv() of its mesh) as a
/// tangible-image texture. The material is the proxy's everywhere; the
/// vibration id is each triangle's material.
/// @throws std::invalid_argument for an empty or too small picture, metres
///         that are not finite and > 0, or a bad proxy or texture configuration.
template <Shape S>
[[nodiscard]] TexturedSurface<std::remove_cvref_t<S>> textured_surface(S&& shape, const cv::Mat& picture, double metres,
                                                                       const ModelTextureConfig& config = {}) {
  MaterialMaps maps;
  maps.stiffness = config.proxy.stiffness;
  maps.damping = config.proxy.damping;
  maps.static_friction = config.proxy.static_friction;
  maps.dynamic_friction = config.proxy.dynamic_friction;
  maps.vibration = per_primitive_material;
  return textured_surface(std::forward<S>(shape), picture, metres, MaterialMap(std::move(maps)), config);
}

/// The loaded mesh felt with its own base-colour texture (see the file
/// comment): textured_surface() of its MeshShape, its material's picture
/// and its metres_per_uv().
/// @throws std::invalid_argument for a mesh without uvs, a material without
///         a base-colour texture, an undecodable or too small picture, or a
///         bad proxy or texture configuration.
[[nodiscard]] inline TexturedModel textured_model(io::LoadedMesh loaded, const ModelTextureConfig& config = {}) {
  const cv::Mat picture = base_colour_picture(loaded, config.material);
  const double metres = metres_per_uv(loaded.mesh);
  return textured_surface(MeshShape(std::move(loaded.mesh), config.shape), picture, metres, config);
}

}  // namespace hapticfield::material
