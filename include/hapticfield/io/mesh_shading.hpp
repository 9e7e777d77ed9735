#pragma once
/// @file mesh_shading.hpp
/// A mesh read from a file made a MeshShape the same way in feel_shape,
/// servo_demo, the 3D viewer and Python: one force-shading default, the
/// same refusal of a mesh with nothing to touch, the same words for what
/// was done, and the box it spans once placed by a Pose.
///
/// The default (MeshShading::smooth): the file's own vertex normals where
/// it has them (an author's split vertices keep their creases); where it
/// has none (every STL, many OBJ and glTF files), vertex normals from the
/// faces around each vertex, area-weighted (with_vertex_normals). The proxy
/// then pushes along the interpolated normal (force shading), so a
/// tessellated curved surface feels round. MeshShading::faceted feels the
/// bare triangles instead: each pushes along its face normal (the choice
/// for a welded CAD part with sharp edges, whose corners smoothing would
/// round). docs/surfaces.md, "Force shading: one default", says why.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/posed_shape.hpp"

namespace hapticfield::io {

enum class MeshShading {
  smooth,   ///< default: the file's vertex normals, else vertex normals from the faces (force shading)
  faceted,  ///< face normals only: flat facets
};

/// What a mesh was made into, for the tools' and Python's reports.
struct MeshShapeReport {
  std::size_t triangles{0};  ///< in the file
  std::size_t touchable{0};  ///< with an area (the proxy skips the others)
  std::string normals;       ///< the normals the proxy pushes along, in words
};

/// The mesh `loaded` made a MeshShape with `shading` (loaded.mesh is moved
/// into it: read it back through MeshShape::mesh()); the warnings of
/// `loaded` are rewritten to say what the shape does (a file without vertex
/// normals: computed from the faces, or face normals used).
/// @param name  the file, for the error
/// @param huge_pages  MeshShapeConfig::huge_pages (the tree and arrays on
///        2 MB pages where the kernel allows)
/// @throws FileError naming the file when no triangle has an area (an empty
///         mesh never gets here: the readers refuse it).
/// @throws std::invalid_argument for a zero node budget.
[[nodiscard]] inline MeshShape mesh_shape_from(LoadedMesh& loaded, const std::string& name,
                                               MeshShading shading = MeshShading::smooth,
                                               std::uint32_t max_nodes = bvh_default_max_nodes,
                                               MeshShapeReport* report = nullptr, bool huge_pages = true) {
  const bool file_normals = loaded.mesh.has_normals();
  const bool shade = shading == MeshShading::smooth;
  MeshShapeReport r;
  r.triangles = loaded.mesh.triangles.size();
  r.normals = !shade         ? "face normals (flat facets)"
              : file_normals ? "the file's vertex normals (force shading)"
                             : "vertex normals from the faces (force shading)";
  for (MeshWarning& w : loaded.warnings)
    if (w.kind == MeshWarningKind::no_normals)
      w.message = shade ? "no vertex normals in the file: computed from the faces around each vertex (force shading)"
                        : "no vertex normals in the file: the surface uses face normals";
  TriangleMesh mesh = shade && !file_normals ? with_vertex_normals(std::move(loaded.mesh)) : std::move(loaded.mesh);
  MeshShape shape(std::move(mesh), MeshShapeConfig{shade, max_nodes, huge_pages});
  r.touchable = shape.bvh().triangle_count();
  if (r.touchable == 0)
    throw FileError("cannot use '" + name + "': " +
                    (r.triangles == 1 ? std::string("its one triangle has")
                                      : "all " + std::to_string(r.triangles) + " triangles have") +
                    " zero area (nothing to touch)");
  if (report) *report = std::move(r);
  return shape;
}

/// An axis-aligned box [m].
struct Bounds {
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};
  void add(const glm::dvec3& p) noexcept {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
};

/// The box of a mesh's vertices once placed by `pose` (exact).
[[nodiscard]] inline Bounds placed_bounds(const TriangleMesh& mesh, const Pose& pose = {}) {
  Bounds b;
  for (const glm::dvec3& p : mesh.positions)
    b.add(pose.point_to_world(p));
  return b;
}

/// The box around the eight corners of the box [lo, hi] once placed by
/// `pose` (exact without rotation, else a box around the shape).
[[nodiscard]] inline Bounds placed_bounds(const glm::dvec3& lo, const glm::dvec3& hi, const Pose& pose = {}) {
  Bounds b;
  for (int k = 0; k < 8; ++k)
    b.add(pose.point_to_world({(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z}));
  return b;
}

}  // namespace hapticfield::io
