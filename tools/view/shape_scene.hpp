#pragma once
/// @file shape_scene.hpp
/// A shape file made ready to feel and to show: a mesh (.stl, .obj, .gltf,
/// .glb) or a height map picture, scaled so its footprint (x and y) spans
/// the workspace's 80 mm (a height map: heights from gray levels, white the
/// highest) and moved so that it is centred on x = y = 0 with its top 1 mm
/// below the handle's start (z = 0, z toward the user). The file's own axes
/// are kept: unlike feel_shape and Python, which keep a file's units
/// (scaled by --scale / scale) and place it only where told (--rotate,
/// --translate / pose), the view fits any shape to the workspace. A mesh is
/// force-shaded as everywhere else (io/mesh_shading.hpp: the file's vertex
/// normals, else normals from the faces), so the same file pushes along the
/// same normals here, only scaled. The proxy feels the full shape; the
/// display mesh may be decimated (display_mesh.hpp). ShapeProxyField is the
/// proxy on it as a field in the device frame. Needs hapticfield::io.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/io/height_map.hpp"
#include "hapticfield/io/load_mesh.hpp"
#include "hapticfield/io/mesh_shading.hpp"
#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "view/display_mesh.hpp"

namespace hapticfield::view {

struct ShapeSceneConfig {
  double span_mm{80.0};                                       ///< the larger of the footprint's x and y extents [mm]
  double height_mm{4.0};                                      ///< a height map: the height of white over black [mm]
  double top_mm{-1.0};                                        ///< where the shape's top goes on z [mm]
  std::size_t display_triangles{default_display_triangles};   ///< display budget
  std::uint64_t max_pixels{100'000'000};                      ///< a height map's largest picture [px]
  std::size_t max_triangles{io::default_max_mesh_triangles};  ///< a mesh's most triangles, refused before reading
};

/// The shape (one of the two), where it sits, and what the view draws.
struct ShapeScene {
  std::optional<MeshShape> mesh;                 ///< a mesh file, scaled [m], in its own axes
  std::optional<HeightFieldShape> height_field;  ///< a height map [m]
  glm::dvec3 shift{0.0};                         ///< device frame = shape frame + shift [m]
  DisplayMesh display;                           ///< device frame
  glm::dvec3 centre{0.0};                        ///< of the bounding box, device frame [m]
  double radius{0.0};                            ///< half the bounding box's diagonal [m]
  glm::dvec3 top{0.0};                           ///< the bounding box's top centre, device frame [m]
  std::string label;                             ///< what it is, for the status line
};

/// A height map by the name's ending (else a mesh).
[[nodiscard]] inline bool is_height_picture(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm", ".pnm"})
    if (ext == e) return true;
  return false;
}

/// Loads `path` (a mesh, or a height map picture) and places it.
/// @throws hapticfield::FileError and std::invalid_argument as the readers
///         do, and std::invalid_argument for a shape with no extent.
[[nodiscard]] inline ShapeScene load_shape_scene(const std::string& path, const ShapeSceneConfig& config = {}) {
  if (!(config.span_mm > 0.0) || !std::isfinite(config.span_mm))
    throw std::invalid_argument("the shape's span must be finite and > 0 [mm]");
  ShapeScene scene;
  const double span = config.span_mm * 1e-3;
  glm::dvec3 lo{0.0}, hi{0.0};
  const std::string name = std::filesystem::path(path).filename().string();
  char text[200];
  if (is_height_picture(path)) {
    io::PictureHeightConfig hc;
    hc.mm_per_level = config.height_mm / 255.0;
    hc.max_pixels = config.max_pixels;
    io::HeightGrid grid = io::load_height_picture(path, hc);
    const double spacing = span / std::max(1, std::max(grid.width, grid.height) - 1);
    grid.spacing_x = grid.spacing_y = spacing;
    scene.height_field.emplace(grid);
    const auto [zlo, zhi] = std::minmax_element(grid.heights.begin(), grid.heights.end());
    lo = {0.0, 0.0, *zlo};
    hi = {(grid.width - 1) * spacing, (grid.height - 1) * spacing, *zhi};
    scene.shift = glm::dvec3{-0.5 * (lo.x + hi.x), -0.5 * (lo.y + hi.y), config.top_mm * 1e-3 - hi.z};
    scene.display = display_height_grid(grid, scene.shift, config.display_triangles);
    std::snprintf(text, sizeof text, "%s: %d x %d heights, %.1f mm", name.c_str(), grid.width, grid.height,
                  config.height_mm);
  } else {
    io::MeshReadConfig read;
    read.max_triangles = config.max_triangles;
    io::LoadedMesh loaded = io::load_mesh(path, read);
    TriangleMesh& mesh = loaded.mesh;
    if (mesh.triangles.empty()) throw std::invalid_argument("'" + path + "' has no triangles");
    lo = glm::dvec3{std::numeric_limits<double>::max()};
    hi = -lo;
    for (const glm::dvec3& p : mesh.positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    double extent = std::max(hi.x - lo.x, hi.y - lo.y);
    if (!(extent > 0.0)) extent = hi.z - lo.z;  // a mesh seen edge-on
    if (!(extent > 0.0) || !std::isfinite(extent)) throw std::invalid_argument("'" + path + "' has no extent");
    const double scale = span / extent;
    for (glm::dvec3& p : mesh.positions)
      p *= scale;
    lo *= scale;
    hi *= scale;
    scene.shift = glm::dvec3{-0.5 * (lo.x + hi.x), -0.5 * (lo.y + hi.y), config.top_mm * 1e-3 - hi.z};
    // the shading of every tool and of Python (io/mesh_shading.hpp); refuses a mesh with nothing to touch
    scene.mesh.emplace(io::mesh_shape_from(loaded, path));
    const TriangleMesh& placed = scene.mesh->mesh();
    scene.display = display_mesh(placed, scene.shift, config.display_triangles);
    std::snprintf(text, sizeof text, "%s: %zu triangles", name.c_str(), placed.triangles.size());
  }
  scene.label = text;
  scene.centre = 0.5 * (lo + hi) + scene.shift;
  scene.radius = 0.5 * glm::length(hi - lo);
  scene.top = glm::dvec3{scene.centre.x, scene.centre.y, hi.z + scene.shift.z};
  return scene;
}

/// The proxy on a shape placed with `shift`, as a field in the device
/// frame: F = Fc of the proxy. The proxy starts at `outside` (a free point
/// above the shape, device frame) and sweeps from there to the first HIP,
/// so a handle that is already inside the solid when the field starts (or
/// restarts: reset()) is pushed out rather than taken as free. Servo path:
/// noexcept, no allocation.
template <Shape S>
class ShapeProxyField {
 public:
  ShapeProxyField(S shape, const glm::dvec3& shift, const glm::dvec3& outside, const ProxyConfig& config = {})
      : proxy_(std::move(shape), config), shift_(shift), outside_(outside) {}

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    Probe local = probe;
    if (fresh_) {  // the proxy's first position: outside
      fresh_ = false;
      proxy_.reset();
      local.position = outside_ - shift_;
      local.velocity = glm::dvec3{0.0};
      (void)proxy_.contact(local);
      local = probe;
    }
    local.position -= shift_;
    contact_ = proxy_.contact(local);
    return contact_.force;
  }
  /// The proxy's look-ahead (core/field.hpp) in the shape's frame; none
  /// before the first tick, which starts the proxy afresh.
  void anticipate(const Probe& next) const noexcept {
    if (fresh_) return;
    Probe local = next;
    local.position -= shift_;
    proxy_.anticipate(local);
  }
  [[nodiscard]] bool looks_ahead() const noexcept { return proxy_.looks_ahead(); }
  /// The next tick starts the proxy from `outside` again.
  void reset() noexcept {
    fresh_ = true;
    contact_ = Contact{};
  }

  /// The proxy in the device frame [m] (`outside` before the first tick).
  [[nodiscard]] glm::dvec3 proxy() const noexcept { return fresh_ ? outside_ : proxy_.proxy() + shift_; }
  [[nodiscard]] const Contact& last_contact() const noexcept { return contact_; }

 private:
  ProxyConstraint<S> proxy_;
  glm::dvec3 shift_;
  glm::dvec3 outside_;
  bool fresh_{true};
  Contact contact_{};
};

}  // namespace hapticfield::view
