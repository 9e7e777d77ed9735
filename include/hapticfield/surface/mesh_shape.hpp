#pragma once
/// @file mesh_shape.hpp
/// MeshShape: a TriangleMesh and its MeshBvh as a Shape for the proxy.
///
/// What a hit reports: the face normal of the triangle; the shaded normal,
/// the barycentric blend of the vertex normals, renormalised (force
/// shading, Morgenbesser & Srinivasan, "Force shading for haptic shape
/// perception", ASME DSC 1996), when the mesh has vertex normals, else the
/// face normal (also where the blend is zero or turns away from the face);
/// uv blended the same way with the tangent frame of the triangle's uv
/// map; the triangle's index and material; its longest edge as its size.
///
/// Meshes as they come: open meshes and non-manifold edges need nothing
/// special (each triangle is a one-sided surface, felt from the side its
/// normal points to: the back of an open sheet lets the proxy through);
/// triangles with no area are left out. Copies share the built data, which
/// never changes while shared (publish a new shape through LiveField;
/// refit() moves the vertices of an unshared one: surface/deforming_mesh.hpp).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/rt/huge_pages.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield {

struct MeshShapeConfig {
  bool shade_normals{true};                        ///< use the mesh's vertex normals (force shading) when it has them
  std::uint32_t max_nodes{bvh_default_max_nodes};  ///< node budget of one query
  /// The tree's and the mesh's arrays on 2 MB pages where the kernel allows
  /// (MeshBvhConfig::huge_pages; the mesh's arrays of 4 MB or more are
  /// copied there once, at construction).
  bool huge_pages{true};
};

class MeshShape {
 public:
  /// Each primitive is a flat, convex triangle (the proxy moves over one
  /// without a sweep).
  static constexpr bool flat_primitives = true;
  /// Its queries only read the tree, shared by copies (PureQueries).
  static constexpr bool pure_queries = true;
  /// What a caller keeps between its ball sweeps (sweep_sphere's `cache`).
  using SweepCache = MeshBvh::Neighbourhood;

  /// Takes the mesh and builds its tree (allocates; may take about a second
  /// per million triangles).
  /// @throws std::invalid_argument for an invalid mesh (TriangleMesh::validate)
  ///         or a zero budget.
  explicit MeshShape(TriangleMesh mesh, const MeshShapeConfig& config = {}) : config_(config) {
    auto data = std::make_shared<Data>();
    data->bvh = MeshBvh::build(mesh, MeshBvhConfig{config.max_nodes, config.huge_pages});
    data->mesh = std::move(mesh);
    if (config.huge_pages) on_huge_pages(data->mesh);
    data_ = std::move(data);
  }

  /// Takes the mesh and a tree over it, built (MeshBvh::build) or refit
  /// (MeshBvh::refit) to this mesh: no build here (a deforming mesh's
  /// frames, surface/deforming_mesh.hpp). The node budget and the page
  /// hint are the tree's: with the hint, the mesh's arrays of 4 MB or more
  /// are copied onto 2 MB pages, as by the constructor above.
  /// @throws std::invalid_argument for an invalid mesh or a tree with more
  ///         triangles than the mesh.
  MeshShape(TriangleMesh mesh, MeshBvh bvh, bool shade_normals = true)
      : config_{shade_normals, bvh.config().max_nodes, bvh.config().huge_pages} {
    mesh.validate();
    if (bvh.triangle_count() > mesh.triangles.size())
      throw std::invalid_argument("MeshShape: the tree has more triangles than the mesh");
    auto data = std::make_shared<Data>();
    data->bvh = std::move(bvh);
    data->mesh = std::move(mesh);
    if (config_.huge_pages) on_huge_pages(data->mesh);
    data_ = std::move(data);
  }

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    return closest(p, max_distance, nullptr);
  }
  /// `cache`, when given, is a ball's region of the tree (sweep_sphere's):
  /// read, never gathered; where p's reach lies inside it, its leaves alone
  /// are tested (MeshBvh::closest). The answer is the same with or without.
  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance, QueryStats* stats,
                            const SweepCache* cache = nullptr) const noexcept {
    const BvhHit h = data_->bvh.closest(p, max_distance, stats, cache);
    Hit out = describe(h);
    out.distance = h.distance;
    return out;
  }

  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    return first_hit(from, to, nullptr);
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to, QueryStats* stats) const noexcept {
    const BvhHit h = data_->bvh.first_hit(from, to, stats);
    Hit out = describe(h);
    out.t = h.t;
    if (h.found()) out.distance = h.t * glm::length(to - from);
    return out;
  }

  /// The first contact of a ball of `radius` [m] whose centre moves from
  /// `from` to `to` (MeshBvh::sweep_sphere): Hit::point is the touched
  /// point of the mesh, face_normal the contact normal (unit, from it to the
  /// centre at contact), normal the shaded normal where the ball touches a
  /// face's inside, else the contact normal; t the fraction of the move.
  ///
  /// `hint`, a triangle the ball is likely to meet first (the one it touched
  /// last tick), is tried before the tree: the traversal then skips what
  /// lies beyond that contact (MeshBvh::sweep_sphere's seed). The answer is
  /// the same whatever the hint, but for which of two triangles met at the
  /// very same t is named.
  ///
  /// `cache`, when given, is the caller's region of the tree, kept between
  /// its sweeps (MeshBvh::Neighbourhood): short sweeps inside it skip the
  /// walk down the tree. The answer is the same with or without it.
  ///
  /// `slide`, when given, is the normal of a plane the move runs along
  /// (MeshBvh::sweep_sphere's): triangles behind the ball's reach below it
  /// are passed by. The answer is the same with or without it.
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius,
                                 QueryStats* stats = nullptr, std::uint32_t hint = no_primitive,
                                 SweepCache* cache = nullptr, const glm::dvec3* slide = nullptr) const noexcept {
    BvhHit seed;
    const TriangleMesh& m = data_->mesh;
    if (hint < m.triangles.size() && radius > 0.0 && std::isfinite(radius)) {
      const TriangleIndices& tri = m.triangles[hint];
      const glm::dvec3 a = m.positions[tri[0]], e1 = m.positions[tri[1]] - a, e2 = m.positions[tri[2]] - a;
      double t = 1.0;
      (void)MeshBvh::touch_triangle(a, e1, e2, hint, from, to - from, radius, t, seed);
    }
    const BvhHit h = data_->bvh.sweep_sphere(from, to, radius, stats, seed, cache, slide);
    Hit out = describe(h);
    out.t = h.t;
    if (!h.found()) return out;
    const glm::dvec3 centre = from + h.t * (to - from);
    const glm::dvec3 towards = centre - h.contact_point;
    const double length = glm::length(towards);
    const glm::dvec3 n = length > 0.0 ? towards / length : out.face_normal;
    if (!(glm::dot(n, out.face_normal) > 1.0 - 1e-12)) out.normal = n;  // an edge or a corner
    out.face_normal = n;
    out.point = h.contact_point;
    out.distance = h.t * glm::length(to - from);
    return out;
  }

  /// The point of one triangle nearest to p, if within max_distance [m]
  /// (no tree traversal: the proxy's check that it is still on a face).
  [[nodiscard]] Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p, double max_distance) const noexcept {
    const TriangleMesh& m = data_->mesh;
    if (primitive >= m.triangles.size() || !is_finite(p)) return Hit{};
    const TriangleIndices& tri = m.triangles[primitive];
    const glm::dvec3 a = m.positions[tri[0]];
    BvhHit h;
    h.point = detail::closest_on_triangle(p, a, m.positions[tri[1]] - a, m.positions[tri[2]] - a, h.b1, h.b2);
    h.distance = glm::length(h.point - p);
    if (!(h.distance <= max_distance)) return Hit{};
    h.triangle = primitive;
    Hit out = describe(h);
    out.distance = h.distance;
    return out;
  }

  /// Moves the vertices of a shape no copy shares (a deforming mesh's frame
  /// on its writer's thread, surface/deforming_mesh.hpp): the positions
  /// [m] and, when given, the vertex normals replaced (one per vertex), the
  /// tree refit (MeshBvh::refit). No allocation; linear time. False, with
  /// nothing changed, when a copy shares this shape's data.
  /// @throws std::invalid_argument for a wrong count or a non-finite value
  ///         (nothing changed).
  bool refit(std::span<const glm::dvec3> positions, std::span<const glm::dvec3> normals = {}) {
    TriangleMesh& m = data_->mesh;
    if (positions.size() != m.positions.size() || (!normals.empty() && normals.size() != m.positions.size()))
      throw std::invalid_argument("MeshShape::refit: one position (and normal, if any) per vertex");
    for (const glm::dvec3& p : positions)
      if (!is_finite(p)) throw std::invalid_argument("MeshShape::refit: a position is not finite");
    for (const glm::dvec3& n : normals)
      if (!is_finite(n)) throw std::invalid_argument("MeshShape::refit: a normal is not finite");
    // shared, or new normals on a mesh without (that would allocate): not here
    if (data_.use_count() != 1 || (!normals.empty() && m.normals.size() != normals.size())) return false;
    std::copy(positions.begin(), positions.end(), m.positions.begin());
    std::copy(normals.begin(), normals.end(), m.normals.begin());
    data_->bvh.refit(m);
    return true;
  }

  [[nodiscard]] const TriangleMesh& mesh() const noexcept { return data_->mesh; }
  [[nodiscard]] const MeshBvh& bvh() const noexcept { return data_->bvh; }
  [[nodiscard]] const MeshShapeConfig& config() const noexcept { return config_; }

 private:
  struct Data {
    TriangleMesh mesh;
    MeshBvh bvh;
  };

  /// The mesh's arrays, which ticks read beside the tree, on 2 MB pages
  /// where the kernel allows (rt/huge_pages.hpp).
  static void on_huge_pages(TriangleMesh& mesh) {
    move_to_huge_pages(mesh.positions);
    move_to_huge_pages(mesh.normals);
    move_to_huge_pages(mesh.uvs);
    move_to_huge_pages(mesh.triangles);
    move_to_huge_pages(mesh.materials);
  }

  [[nodiscard]] Hit describe(const BvhHit& h) const noexcept {
    Hit out;
    out.complete = h.complete;
    if (!h.found()) {
      if (!h.complete) out.t = 0.0;
      return out;
    }
    const TriangleMesh& m = data_->mesh;
    const TriangleIndices& tri = m.triangles[h.triangle];
    const glm::dvec3 a = m.positions[tri[0]], b = m.positions[tri[1]], c = m.positions[tri[2]];
    const glm::dvec3 e1 = b - a, e2 = c - a;
    const double w0 = 1.0 - h.b1 - h.b2;
    out.point = h.point;
    out.face_normal = glm::normalize(glm::cross(e1, e2));
    out.normal = out.face_normal;
    if (config_.shade_normals && m.has_normals()) {
      const glm::dvec3 blend = w0 * m.normals[tri[0]] + h.b1 * m.normals[tri[1]] + h.b2 * m.normals[tri[2]];
      const double length = glm::length(blend);
      if (length > 0.0 && std::isfinite(length) && glm::dot(blend, out.face_normal) > 0.0) out.normal = blend / length;
    }
    if (m.has_uvs()) {
      const glm::dvec2 ua = m.uvs[tri[0]], ub = m.uvs[tri[1]], uc = m.uvs[tri[2]];
      out.uv = w0 * ua + h.b1 * ub + h.b2 * uc;
      // [e1 e2] = [dP/du dP/dv] [duv1 duv2]  ->  dP/du, dP/dv
      const glm::dvec2 d1 = ub - ua, d2 = uc - ua;
      const double det = d1.x * d2.y - d2.x * d1.y;
      if (det != 0.0 && std::isfinite(det)) {
        const glm::dvec3 dpdu = (d2.y * e1 - d1.y * e2) / det;
        const glm::dvec3 dpdv = (d1.x * e2 - d2.x * e1) / det;
        detail::tangent_frame(out.normal, dpdu, dpdv, out.tangent, out.bitangent);
      }
    }
    out.size = std::sqrt(std::fmax(glm::dot(e1, e1), std::fmax(glm::dot(e2, e2), glm::dot(c - b, c - b))));
    out.primitive = h.triangle;
    out.material = m.materials.empty() ? 0u : m.materials[h.triangle];
    return out;
  }

  std::shared_ptr<Data> data_;  ///< shared by copies; changed only by refit(), unshared
  MeshShapeConfig config_;
};

static_assert(Shape<MeshShape>);

/// Vertex normals for force shading of a mesh that has none: each vertex
/// gets the area-weighted mean of the face normals around it (a vertex with
/// no triangle gets +z). Seams with duplicated vertices keep a crease.
/// @throws std::invalid_argument for an invalid mesh.
[[nodiscard]] inline TriangleMesh with_vertex_normals(TriangleMesh mesh) {
  mesh.validate();
  mesh.normals.assign(mesh.positions.size(), glm::dvec3{0.0});
  for (const TriangleIndices& t : mesh.triangles) {
    const glm::dvec3 a = mesh.positions[t[0]];
    const glm::dvec3 n = glm::cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a);  // twice the area
    for (const std::uint32_t k : t)
      mesh.normals[k] += n;
  }
  for (glm::dvec3& n : mesh.normals) {
    const double length = glm::length(n);
    n = length > 0.0 && std::isfinite(length) ? n / length : glm::dvec3{0.0, 0.0, 1.0};
  }
  return mesh;
}

}  // namespace hapticfield
