#pragma once
/// @file mesh_bvh.hpp
/// MeshBvh: a bounding volume hierarchy over a TriangleMesh, built once and
/// queried every tick.
///
/// Build (allocates, may throw): binned surface-area heuristic over the
/// triangles' centroids, 16 bins on each axis (Wald, "On fast construction
/// of SAH-based bounding volume hierarchies", IEEE RT 2007), leaves of at
/// most 4 triangles. The depth is capped at bvh_max_depth: once the SAH
/// could run past it, nodes are split at the median triangle, which halves
/// them, so a fixed traversal stack of bvh_max_depth entries always
/// suffices. Triangles with no area (the height of the triangle below 1e-12
/// of its longest edge) or non-finite corners are left out: they have no
/// normal and are never hit.
///
/// Layout: the root, then the other nodes as sibling pairs, one 64-byte
/// cache line each, depth first; the triangles (corner, two edges, double)
/// in leaf order, so a leaf's triangles are contiguous. Beside them, for a
/// ball's sweep: each triangle's plane and bounding circle (TriangleBounds)
/// and each node's slab (NodeBounds), a cache line each.
///
/// Queries (const, noexcept, no allocation): first_hit(from, to), the
/// first front-facing triangle a segment crosses (Moller & Trumbore, "Fast,
/// minimum storage ray/triangle intersection", JGT 1997, with a barycentric
/// tolerance of 1e-9, relative to the triangle, so a segment through a
/// shared edge or vertex meets one of its triangles, and the tie rule below),
/// and closest(p, r), the
/// nearest point within r (the Voronoi-region closest point on a triangle,
/// Ericson, "Real-Time Collision Detection", 2005, section 5.1.5; a node
/// small against r is also passed by through its slab, NodeBounds, when
/// every point of it is farther than the nearest found: a ball's reach takes
/// in the boxes of the smooth surface under it; two triangles at the very
/// same distance go to the lower mesh index, whatever the order they are
/// visited in), and
/// sweep_sphere(from, to, r), a ball's first contact. Each
/// query visits at most `max_nodes` nodes (its budget); past that it stops
/// and says so (BvhHit::complete = false). A query first skips its trunk:
/// the levels where its box meets one child's box only (cheap float tests),
/// answering as from the root. A ball's sweep may also go through the
/// caller's Neighbourhood, the leaves around where it swept last, kept from
/// sweep to sweep: it then tests those leaves alone (their boxes all at
/// once, kept in the Neighbourhood axis by axis), with the same answer
/// (a tie in t goes to the seed, else to the lowest mesh index, however the
/// triangles are visited); so may a closest() whose reach lies inside the
/// region. A ball's sweep told the plane it slides along
/// passes by, without their full test, the triangles wholly out of its reach
/// behind that plane: the face under a sliding ball, and the surface curving
/// away below it.
///
/// Ties (a segment that meets a triangle on its boundary: within
/// bvh_tie_band of an edge or a vertex, relative to the triangle). The solid
/// is closed: its boundary is not inside it, so a segment that touches the
/// surface at an edge or a vertex while running along (or away from) the
/// face on the other side does not enter it. At a convex edge shared with
/// one neighbour, and at a vertex whose closed fan of triangles has only
/// convex edges, the solid is locally the intersection of the faces' half
/// spaces, and the segment enters it only when it goes behind every one of
/// them: a segment that moves away from one of them (by more than
/// bvh_tie_angle) is no hit, and one that runs along one of them (within
/// bvh_tie_angle) is reported as a hit on that face, the face it slides on.
/// Concave edges, saddle vertices, open fans and non-manifold edges keep the
/// plain rule (a hit on the triangle met). Triangles are neighbours when they
/// share an edge of two welded vertices (equal positions) in opposite
/// directions, and no third triangle uses that edge.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/always_inline.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/rt/huge_pages.hpp"
#include "hapticfield/surface/ball_sweep.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield {

namespace detail {

/// The point of the triangle (a, a + e1, a + e2) nearest to p, by the
/// Voronoi region of p (a vertex, an edge or the face; Ericson 2005,
/// 5.1.5); b1, b2 receive its barycentric weights of vertices 1 and 2.
[[nodiscard]] inline glm::dvec3 closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& e1,
                                                    const glm::dvec3& e2, double& b1, double& b2) noexcept {
  const glm::dvec3 ap = p - a;
  const double d1 = glm::dot(e1, ap), d2 = glm::dot(e2, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {  // vertex a
    b1 = b2 = 0.0;
    return a;
  }
  const glm::dvec3 bp = ap - e1;
  const double d3 = glm::dot(e1, bp), d4 = glm::dot(e2, bp);
  if (d3 >= 0.0 && d4 <= d3) {  // vertex b
    b1 = 1.0;
    b2 = 0.0;
    return a + e1;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge ab
    b1 = d1 / (d1 - d3);
    b2 = 0.0;
    return a + b1 * e1;
  }
  const glm::dvec3 cp = ap - e2;
  const double d5 = glm::dot(e1, cp), d6 = glm::dot(e2, cp);
  if (d6 >= 0.0 && d5 <= d6) {  // vertex c
    b1 = 0.0;
    b2 = 1.0;
    return a + e2;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge ac
    b1 = 0.0;
    b2 = d2 / (d2 - d6);
    return a + b2 * e2;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {  // edge bc
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    b1 = 1.0 - w;
    b2 = w;
    return a + e1 + w * (e2 - e1);
  }
  const double denominator = 1.0 / (va + vb + vc);  // inside the face
  b1 = vb * denominator;
  b2 = vc * denominator;
  return a + b1 * e1 + b2 * e2;
}

/// The squared distance [m^2] from `middle` to the nearest point of the
/// path of a centre moving from + t d, t in [0, t_max], both projected on
/// the plane through middle along the unit `normal` (h0: from's height over
/// it, dn: d's component along it): how near a ball's cut with that plane
/// comes to a bounding circle about middle.
[[nodiscard]] inline double projected_gap2(const glm::dvec3& from, const glm::dvec3& d, const glm::dvec3& normal,
                                           const glm::dvec3& middle, double h0, double dn, double t_max) noexcept {
  const glm::dvec3 to_middle = middle - from + h0 * normal;  // from the centre's projection
  const glm::dvec3 slide = d - dn * normal;                  // the projected move
  const double slide2 = glm::dot(slide, slide);
  const double along = slide2 > 0.0 ? larger(0.0, smaller(t_max, glm::dot(to_middle, slide) / slide2)) : 0.0;
  const glm::dvec3 gap = to_middle - along * slide;
  return glm::dot(gap, gap);
}

}  // namespace detail

/// Deepest a MeshBvh gets (root at depth 1): the size of the fixed
/// traversal stack.
inline constexpr std::size_t bvh_max_depth = 64;
/// Most triangles in a leaf.
inline constexpr std::uint32_t bvh_max_leaf = 4;
/// Default node budget of one query: a few microseconds at worst.
inline constexpr std::uint32_t bvh_default_max_nodes = 4096;
/// Most leaves a MeshBvh::Neighbourhood holds (a ball's region whose
/// leaves do not fit is swept through the tree).
inline constexpr std::size_t bvh_neighbourhood_leaves = 128;
/// A MeshBvh::Neighbourhood reaches this far past the sweep that gathers
/// it, relative to the ball's radius (0.4: a 0.5 mm ball's region reaches
/// 0.2 mm further, some 10 ticks of a hand's slide at 20 mm/s).
inline constexpr double bvh_neighbourhood_reach = 0.4;
/// A ball's sweep up to this long, relative to its radius, that leaves its
/// Neighbourhood's region gathers a new one around it; a longer sweep walks
/// the tree (whose nearest-first order finds its contact sooner). 1: a
/// 0.5 mm ball's slip of up to 0.5 mm in a tick, where its static friction
/// lets go, stays in a region (the tree walk it took instead cost more
/// than the gather and the region's leaves).
inline constexpr double bvh_neighbourhood_sweep = 1.0;

/// A box a query can reach (float, rounded outward, with an allowance for
/// the rounding of the traversal's own tests): a node box that misses it
/// holds nothing the query meets, and the query's own tests reject it.
struct BvhBox {
  std::array<float, 3> lo{}, hi{};
  BvhBox() = default;
  /// [low, high] [m]; `length` [m], a segment's, widens the allowance.
  BvhBox(const glm::dvec3& low, const glm::dvec3& high, double length = 0.0) noexcept {
    // the traversal's rounding (1e-9 relative), and float's: 2.4e-7 of the
    // largest coordinate is more than half a float step there, so rounding
    // to the nearest float still leaves the box around [low, high]
    const double allowance = (1e-9 + 2.4e-7) * (largest_component(low) + largest_component(high) + length) + 1e-37;
    for (int k = 0; k < 3; ++k) {
      const auto axis = static_cast<std::size_t>(k);
      lo[axis] = static_cast<float>(low[k] - allowance);
      hi[axis] = static_cast<float>(high[k] + allowance);
    }
  }
  /// True when `inner` lies wholly inside this box.
  [[nodiscard]] bool holds(const BvhBox& inner) const noexcept {
    for (std::size_t k = 0; k < 3; ++k)
      if (!(inner.lo[k] >= lo[k] && inner.hi[k] <= hi[k])) return false;
    return true;
  }
};

/// A hit within this barycentric distance of an edge (relative to the
/// triangle) is on the edge: the tie rule decides it (see the file comment).
inline constexpr double bvh_tie_band = 1e-7;
/// A segment within this angle of a face's plane runs along it [rad].
inline constexpr double bvh_tie_angle = 1e-9;
/// Most triangles walked around a vertex by the tie rule; a larger fan
/// keeps the plain rule.
inline constexpr int bvh_max_fan = 64;

/// One node (32 bytes): its box (float, rounded outward) and either its
/// children (an inner node: a BvhNodePair) or its triangles (a leaf).
struct BvhNode {
  std::array<float, 3> lo{};  ///< box minimum [m]
  std::uint32_t index{0};     ///< inner: its children's BvhNodePair; leaf: first triangle in MeshBvh order
  std::array<float, 3> hi{};  ///< box maximum [m]
  std::uint32_t count{0};     ///< 0: inner node; else the leaf's triangle count
};

/// Two sibling nodes in one 64-byte cache line, each field side by side
/// ([0]: left child, [1]: right child), so that a traversal step tests both
/// children's boxes with one memory access and the same arithmetic on both.
/// Pairs are stored depth first (a pair, then its left child's subtree,
/// then its right child's).
struct alignas(64) BvhNodePair {
  std::array<std::array<float, 2>, 3> lo{};  ///< lo[axis][child]: box minima [m]
  std::array<std::array<float, 2>, 3> hi{};  ///< hi[axis][child]: box maxima [m]
  std::array<std::uint32_t, 2> index{};      ///< as BvhNode::index
  std::array<std::uint32_t, 2> count{};      ///< as BvhNode::count
  [[nodiscard]] BvhNode child(std::size_t side) const noexcept {
    return BvhNode{
        {lo[0][side], lo[1][side], lo[2][side]}, index[side], {hi[0][side], hi[1][side], hi[2][side]}, count[side]};
  }
};

/// A low-level query answer: the triangle (mesh index), the point and its
/// barycentric coordinates (weights of vertices 1 and 2; vertex 0 gets
/// 1 - b1 - b2).
struct BvhHit {
  std::uint32_t triangle{no_primitive};                      ///< index into TriangleMesh::triangles; no_primitive: none
  glm::dvec3 point{0.0};                                     ///< [m]
  double b1{0.0};                                            ///< barycentric weight of vertex 1
  double b2{0.0};                                            ///< barycentric weight of vertex 2
  double t{1.0};                                             ///< first_hit: fraction of the segment [0, 1]
  double distance{std::numeric_limits<double>::infinity()};  ///< closest: distance to the query point [m]
  glm::dvec3 contact_point{0.0};  ///< sweep_sphere: the touched point of the mesh [m] (point: the centre)
  bool complete{true};            ///< false: the node budget ran out
  [[nodiscard]] bool found() const noexcept { return triangle != no_primitive; }
};

struct MeshBvhConfig {
  std::uint32_t max_nodes{bvh_default_max_nodes};  ///< node budget of one query
  /// The tree's arrays on 2 MB pages where the kernel allows
  /// (rt/huge_pages.hpp): a tick's first pass over a part of a large mesh
  /// then misses the TLB far less (docs/surfaces.md).
  bool huge_pages{true};
};

class MeshBvh {
 public:
  MeshBvh() = default;
  /// A copy's arrays are reserved afresh, on 2 MB pages when the config
  /// asks for them (a vector's own copy would drop the hint).
  MeshBvh(const MeshBvh& other) : root_(other.root_), depth_(other.depth_), config_(other.config_) {
    copy_array(pairs_, other.pairs_);
    copy_array(triangles_, other.triangles_);
    copy_array(adjacency_, other.adjacency_);
    copy_array(bounds_, other.bounds_);
    copy_array(node_bounds_, other.node_bounds_);
  }
  MeshBvh& operator=(const MeshBvh& other) {
    if (this != &other) *this = MeshBvh(other);
    return *this;
  }
  MeshBvh(MeshBvh&&) noexcept = default;
  MeshBvh& operator=(MeshBvh&&) noexcept = default;
  ~MeshBvh() = default;

  /// What a query needs to pass a triangle by without its full test: its
  /// plane (unit normal, through the centroid) and its bounding circle
  /// (one cache line a triangle, kept beside the triangles in slot order).
  /// A sliver (height under 1e-3 of its longest edge, whose computed normal
  /// is too rough for the test) is never passed by: its slack is infinite.
  struct alignas(64) TriangleBounds {
    glm::dvec3 normal{0.0};  ///< unit, toward the front
    glm::dvec3 middle{0.0};  ///< the centroid, on the plane [m]
    double reach{0.0};       ///< the farthest corner from the centroid [m]
    double slack{0.0};       ///< the test's allowance for rounding against the full test's [m]

    /// False only when a ball of radius r whose centre moves from + t d,
    /// t in [0, t_max], cannot touch the triangle (sweep_ball_triangle's own
    /// first tests): it stays r or more in front of the plane or wholly
    /// behind it, or its cut with the plane (a disk of radius
    /// sqrt(r^2 - h^2) at its least height h in front) never reaches the
    /// bounding circle.
    [[nodiscard]] bool may_touch(const glm::dvec3& from, const glm::dvec3& d, double r,
                                 double t_max) const noexcept HAPTICFIELD_ALWAYS_INLINE {
      const double h0 = glm::dot(normal, from - middle);  // [m]
      const double dn = glm::dot(normal, d);              // [m] per unit t
      const double h1 = h0 + t_max * dn;
      if ((h0 > r + slack && h1 > r + slack) || (h0 < -slack && h1 < -slack)) return false;
      const double low = h0 > 0.0 && h1 > 0.0 ? detail::smaller(h0, h1) : 0.0;  // [m]
      const double disk2 = r * r - low * low;                                   // the cut's radius, squared [m^2]
      const double within = std::sqrt(detail::larger(0.0, disk2)) + reach + 2.0 * slack;  // [m]
      return detail::projected_gap2(from, d, normal, middle, h0, dn, t_max) <= within * within;
    }
  };

  /// What a ball's sweep needs to pass a whole node by (its subtree)
  /// without visiting it: a slab, every corner of the node's triangles
  /// within `thickness` of the plane through `middle` along `normal` (their
  /// area-weighted mean normal), and within `reach` of `middle`. Where the
  /// surface under a ball is smooth, the nodes beside the one it rests on
  /// are thin slabs the ball stays clear of; their boxes alone would let
  /// it in (one cache line a node, kept beside the node pairs).
  struct alignas(64) NodeBounds {
    glm::dvec3 normal{0.0, 0.0, 1.0};                           ///< unit
    glm::dvec3 middle{0.0};                                     ///< [m]
    double reach{std::numeric_limits<double>::infinity()};      ///< [m]
    double thickness{std::numeric_limits<double>::infinity()};  ///< half the slab's, with the rounding allowance [m]

    /// False only when a ball of radius r whose centre moves from + t d,
    /// t in [0, t_max], meets no point of the slab within reach of middle:
    /// it stays more than r beyond either face of the slab, or the disks it
    /// cuts from the slab (radius sqrt(r^2 - h^2) at its least height h
    /// beyond it) stay farther than reach from middle.
    [[nodiscard]] bool may_touch(const glm::dvec3& from, const glm::dvec3& d, double r,
                                 double t_max) const noexcept HAPTICFIELD_ALWAYS_INLINE {
      const double h0 = glm::dot(normal, from - middle);  // [m]
      const double dn = glm::dot(normal, d);              // [m] per unit t
      const double h1 = h0 + t_max * dn;
      const double above = detail::smaller(h0, h1) - thickness;  // beyond the front face [m]
      const double below = -detail::larger(h0, h1) - thickness;  // beyond the back face [m]
      if (above > r || below > r) return false;
      const double low = detail::larger(0.0, detail::larger(above, below));  // [m]
      const double disk2 = (r - low) * (r + low);  // the cut's radius, squared [m^2] (no cancellation)
      // (the full test takes the cut's radius as sqrt(r^2 - h^2), off by up to sqrt(eps) r at a graze)
      const double within = std::sqrt(detail::larger(0.0, disk2)) + reach + 4e-8 * r;  // [m]
      return detail::projected_gap2(from, d, normal, middle, h0, dn, t_max) <= within * within;
    }

    /// At most the squared distance from p to the slab's triangles [m^2]:
    /// they lie in the flat cylinder `thickness` to either side of the
    /// plane and `reach` across from middle.
    [[nodiscard]] double distance2_below(const glm::dvec3& p) const noexcept HAPTICFIELD_ALWAYS_INLINE {
      const glm::dvec3 off = p - middle;
      const double h = glm::dot(normal, off);  // [m]
      const glm::dvec3 across = off - h * normal;
      const double beyond = detail::larger(0.0, std::fabs(h) - thickness);                    // [m]
      const double aside = detail::larger(0.0, std::sqrt(glm::dot(across, across)) - reach);  // [m]
      return beyond * beyond + aside * aside;
    }
  };

  /// Builds the hierarchy over `mesh` (validated first).
  /// @throws std::invalid_argument for an invalid mesh or a zero budget.
  [[nodiscard]] static MeshBvh build(const TriangleMesh& mesh, const MeshBvhConfig& config = {}) {
    mesh.validate();
    if (config.max_nodes == 0) throw std::invalid_argument("MeshBvh: max_nodes must be > 0");
    MeshBvh bvh;
    bvh.config_ = config;
    Builder builder(mesh, bvh);
    builder.run();
    return bvh;
  }

  /// The first front-facing triangle met going from `from` to `to`
  /// (not found: the segment is free). stats, when given, receives the
  /// work done.
  [[nodiscard]] BvhHit first_hit(const glm::dvec3& from, const glm::dvec3& to,
                                 QueryStats* stats = nullptr) const noexcept {
    return traverse<false>(from, to, 0.0, stats,
                           [this](std::uint32_t i, const glm::dvec3& a, const glm::dvec3& d, double& best_t,
                                  BvhHit& best) noexcept { intersect(i, a, d, best_t, best); });
  }

  /// A ball's region of the tree, kept by the caller between sweeps
  /// (MeshBvh::sweep_sphere's `near`; a proxy keeps one from tick to tick):
  /// the leaves whose boxes meet a box around the sweep that gathered it,
  /// bvh_neighbourhood_reach radii past it, in tree order. A sweep
  /// whose box lies inside tests those leaves alone (each one's box, then
  /// its slab and its triangles) instead of walking the tree down to them.
  /// A region with more leaves than it holds is remembered as such, and
  /// sweeps inside it walk the tree. Fixed size, no allocation. It names
  /// the tree and the refit it was gathered from: used with another tree (a
  /// copy, one built apart) or after a refit, it is gathered again.
  struct Neighbourhood {
    BvhBox box;                                                    ///< the region gathered
    const BvhNodePair* tree{nullptr};                              ///< the tree's pairs it was gathered from
    std::uint64_t refits{0};                                       ///< that tree's refit count then
    bool gathered{false};                                          ///< box holds a region
    bool fits{false};                                              ///< its leaves fit in `leaves`
    std::uint32_t count{0};                                        ///< leaves held
    std::array<std::uint32_t, bvh_neighbourhood_leaves> leaves{};  ///< 2 pair + side of each leaf (its NodeBounds)
    /// Each leaf's box, axis by axis (lo[axis][k]: leaf k's minimum), so a
    /// sweep tests every leaf's at once [m]
    std::array<std::array<float, bvh_neighbourhood_leaves>, 3> lo{}, hi{};
  };

  /// The first contact of a ball of `radius` [m] whose centre moves from
  /// `from` to `to` with the mesh (a swept sphere against the triangles'
  /// Minkowski sum: the face, offset by the radius on its front, the edges'
  /// cylinders and the corners' balls). BvhHit::point is the centre at
  /// contact; contact_point and normal (unit, from the touched point to the
  /// centre) say where it touches. A ball that already overlaps a feature
  /// and moves toward it touches at t = 0. A face is met from its front
  /// only; an edge or a corner from any side. radius > 0 and finite.
  ///
  /// `seed`, when found, is a contact already known on this move (one
  /// triangle's, e.g. the one the ball touched last tick, from
  /// sweep_ball_triangle): the traversal starts from its t, so it skips
  /// every box the ball cannot reach before it. The answer is the seed's
  /// unless a triangle is met strictly earlier.
  ///
  /// A tie (two triangles met at the very same t) goes to the seed, else
  /// to the lower mesh index, so the answer does not hang on the order the
  /// triangles are visited in.
  ///
  /// `near`, when given, is the caller's Neighbourhood: a short sweep
  /// inside its region tests the region's leaves alone, one outside it
  /// gathers a new region first; the answer is the same.
  ///
  /// `slide`, when given, is the normal of a plane the move runs along (a
  /// plane the ball slides on; any length but 0): the ball never comes
  /// within r of a point more than r behind the plane through the move's
  /// lower end, so a triangle wholly behind that (the face under a ball
  /// that slides over it, and the surface curving away below) is passed by
  /// without its full test. Any normal gives the same answer; it saves work
  /// where the surface under the move lies behind it.
  [[nodiscard]] BvhHit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius,
                                    QueryStats* stats = nullptr, const BvhHit& seed = BvhHit{},
                                    Neighbourhood* near = nullptr, const glm::dvec3* slide = nullptr) const noexcept {
    if (!(radius > 0.0) || !std::isfinite(radius)) {
      if (stats) *stats = QueryStats{};
      return BvhHit{};
    }
    const std::uint32_t seeded = usable(seed) ? seed.triangle : no_primitive;
    BallLeaf leaf{this, radius, seeded};
    if (const double length = slide ? glm::length(*slide) : 0.0; length > 0.0 && std::isfinite(length)) {
      // less a few rounding units of the coordinates, so that only a triangle
      // clearly out of reach is passed by (the full test's own rounding, and
      // that of a corner's level as out_of_reach() computes it, from the
      // triangle's first corner and its edges: as large as the mesh's
      // coordinates, which may be far larger than the ball's)
      const double coordinate =
          detail::larger(detail::larger(largest_component(from), largest_component(to)), largest_coordinate());  // [m]
      const double rounding = 32.0 * std::numeric_limits<double>::epsilon() * (coordinate + radius);
      leaf.slides = true;
      leaf.slide = *slide / length;
      leaf.behind = detail::smaller(glm::dot(leaf.slide, from), glm::dot(leaf.slide, to)) - radius - rounding;
    }
    if (near == nullptr) return traverse<true>(from, to, radius, stats, leaf, seed);
    QueryStats work;
    BvhHit best;
    if (sweep_near(from, to, radius, seed, leaf, *near, best, work)) {
      if (stats) *stats = work;
      return best;
    }
    best = traverse<true>(from, to, radius, stats, leaf, seed);
    if (stats) {  // and a gather that did not serve
      stats->nodes += work.nodes;
      stats->primitives += work.primitives;
    }
    return best;
  }

  /// The swept ball (centre from + t d, radius r) against the triangle a,
  /// a + e1, a + e2 (mesh index `id`): when it touches before best_t, best_t
  /// and best (triangle, t, the touched point and its barycentric weights)
  /// take that contact and the answer is true. What sweep_sphere() does at
  /// every triangle; a seed for it is made the same way. `circle_tested`:
  /// as sweep_ball_triangle's (the triangle's TriangleBounds passed).
  static bool touch_triangle(const glm::dvec3& a, const glm::dvec3& e1, const glm::dvec3& e2, std::uint32_t id,
                             const glm::dvec3& from, const glm::dvec3& d, double r, double& best_t, BvhHit& best,
                             bool circle_tested = false) noexcept {
    glm::dvec3 contact{0.0};
    if (!detail::sweep_ball_triangle(a, e1, e2, from, d, r, best_t, contact, circle_tested)) return false;
    best.triangle = id;
    best.t = best_t;
    (void)detail::closest_on_triangle(contact, a, e1, e2, best.b1, best.b2);  // the touched point's weights
    best.contact_point = contact;
    return true;
  }

  /// The point of the mesh nearest to p if one is within max_distance [m]
  /// (not found: none); of two at the very same distance, the lower mesh
  /// index's. stats, when given, receives the work done.
  ///
  /// `near`, when given, is a ball's Neighbourhood (sweep_sphere's): when p's
  /// reach (max_distance, finite) lies inside its region, the region's
  /// leaves alone are tested, the nearest box first, and the answer is the
  /// tree's; else the tree answers. It is read, never gathered.
  [[nodiscard]] BvhHit closest(const glm::dvec3& p, double max_distance, QueryStats* stats = nullptr,
                               const Neighbourhood* near = nullptr) const noexcept {
    BvhHit best;
    QueryStats work;
    if (stats) *stats = work;
    if (triangles_.empty() || !is_finite(p) || !(max_distance >= 0.0)) return best;
    double best_d2 = std::isfinite(max_distance) ? max_distance * max_distance : std::numeric_limits<double>::max();
    if (near == nullptr || !closest_near(p, max_distance, *near, best, best_d2, work))
      closest_tree(p, max_distance, best, best_d2, work);
    if (best.found()) best.distance = std::sqrt(best_d2);
    if (stats) *stats = work;
    return best;
  }

  /// Refits the tree to `mesh` after its vertices moved: every triangle's
  /// corner and edges, then every node's box, bottom up (a node's box
  /// bounds its children's; the pairs are stored depth first, so children
  /// come after their parent and one backward pass suffices), rounded
  /// outward as at build. The topology is the tree's: `mesh` is the mesh it
  /// was built from (same triangles, same vertex count), its positions moved
  /// (the refitting of Wald, Boulos & Shirley, "Ray tracing deformable
  /// scenes using dynamic bounding volume hierarchies", ACM TOG 26(1),
  /// 2007). No allocation; time linear in the triangles. The queries answer
  /// as on a tree built over the moved mesh, while the motion keeps every
  /// triangle's area (a triangle left out at build stays out, one that loses
  /// its area keeps its slot) and moves vertices of equal positions alike
  /// (the tie rule's welds stay). Boxes overlap more after large motions:
  /// queries visit more nodes than on a rebuilt tree; and the nodes' slabs
  /// (NodeBounds) are dropped, so a ball's sweeps visit every node its box
  /// test lets in, as they do on a tree without them.
  /// @throws std::invalid_argument for a mesh without the tree's triangles
  ///         (too few, an index out of range) or with a non-finite position;
  ///         the tree is unchanged then.
  void refit(const TriangleMesh& mesh) {
    // checked first, in memory order: the tree is unchanged on bad input
    for (const Triangle& tri : triangles_)
      if (tri.id >= mesh.triangles.size())
        throw std::invalid_argument("MeshBvh::refit: the mesh has fewer triangles than the tree");
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (const std::uint32_t k : mesh.triangles[t])
        if (k >= mesh.positions.size())
          throw std::invalid_argument("MeshBvh::refit: triangle " + std::to_string(t) + " uses a vertex out of range");
    for (const glm::dvec3& p : mesh.positions)
      if (!is_finite(p)) throw std::invalid_argument("MeshBvh::refit: a vertex is not finite");
    ++refits_;
    for (Triangle& tri : triangles_) {
      const TriangleIndices& t = mesh.triangles[tri.id];
      const glm::dvec3 a = mesh.positions[t[0]];
      tri.a = a;
      tri.e1 = mesh.positions[t[1]] - a;
      tri.e2 = mesh.positions[t[2]] - a;
    }
    bound_all();
    // a node's box: its triangles' corners as the queries see them (a leaf,
    // contiguous in tree order) or its children's boxes
    const auto box = [&](std::uint32_t index, std::uint32_t count, std::array<float, 3>& lo,
                         std::array<float, 3>& hi) noexcept {
      if (count == 0) {
        const BvhNodePair& children = pairs_[index];
        for (std::size_t k = 0; k < 3; ++k) {
          lo[k] = std::min(children.lo[k][0], children.lo[k][1]);
          hi[k] = std::max(children.hi[k][0], children.hi[k][1]);
        }
        return;
      }
      glm::dvec3 low{std::numeric_limits<double>::max()}, high{-std::numeric_limits<double>::max()};
      for (std::uint32_t i = index; i < index + count; ++i) {
        const Triangle& tri = triangles_[i];
        for (const glm::dvec3& corner : {tri.a, tri.a + tri.e1, tri.a + tri.e2}) {
          low = glm::min(low, corner);
          high = glm::max(high, corner);
        }
      }
      for (int k = 0; k < 3; ++k) {  // float, rounded outward
        const auto axis = static_cast<std::size_t>(k);
        lo[axis] = static_cast<float>(low[k]);
        hi[axis] = static_cast<float>(high[k]);
        if (static_cast<double>(lo[axis]) > low[k])
          lo[axis] = std::nextafter(lo[axis], -std::numeric_limits<float>::infinity());
        if (static_cast<double>(hi[axis]) < high[k])
          hi[axis] = std::nextafter(hi[axis], std::numeric_limits<float>::infinity());
      }
    };
    for (std::size_t p = pairs_.size(); p-- > 0;) {
      BvhNodePair& pair = pairs_[p];
      for (std::size_t side = 0; side < 2; ++side) {
        std::array<float, 3> lo{}, hi{};
        box(pair.index[side], pair.count[side], lo, hi);
        for (std::size_t k = 0; k < 3; ++k) {
          pair.lo[k][side] = lo[k];
          pair.hi[k][side] = hi[k];
        }
      }
    }
    if (!triangles_.empty()) box(root_.index, root_.count, root_.lo, root_.hi);
    // the nodes' slabs are the build's: dropped (no memory freed), so a
    // refit tree's ball sweeps visit every node its boxes let in
    node_bounds_.clear();
  }

  /// Nodes in the tree (the root and the pairs below it; 0: empty).
  [[nodiscard]] std::size_t node_count() const noexcept { return triangles_.empty() ? 0 : 1 + 2 * pairs_.size(); }
  /// Triangles in the tree (the mesh's, less those with no area).
  [[nodiscard]] std::size_t triangle_count() const noexcept { return triangles_.size(); }
  /// Deepest leaf (root: 1), <= bvh_max_depth.
  [[nodiscard]] std::size_t depth() const noexcept { return depth_; }
  [[nodiscard]] const MeshBvhConfig& config() const noexcept { return config_; }
  /// The root node (its box bounds every triangle in the tree).
  [[nodiscard]] const BvhNode& root() const noexcept { return root_; }
  /// The inner nodes' children, depth first (BvhNode::index of an inner node).
  [[nodiscard]] const std::vector<BvhNodePair>& pairs() const noexcept { return pairs_; }

 private:
  /// The segment queries' traversal: boxes grown by `grow` [m] (Grown), each
  /// leaf's triangles handed to leaf(slot, from, d, best_t, best), which
  /// keeps the nearest hit with t in [0, best_t).
  template <bool Grown, class Leaf>
  [[nodiscard]] BvhHit traverse(const glm::dvec3& from, const glm::dvec3& to, double grow, QueryStats* stats,
                                Leaf&& leaf, const BvhHit& seed = BvhHit{}) const noexcept {
    BvhHit best;
    QueryStats work;
    if (stats) *stats = work;
    const glm::dvec3 d = to - from;
    if (triangles_.empty() || !is_finite(from) || !is_finite(d)) return best;
    // a seed's contact ends the move early: nothing past its t is wanted
    double best_t = 1.0;
    if (usable(seed)) {
      best = seed;
      best_t = seed.t;
    }
    const Slabs<Grown> slabs(from, d, grow);
    // Grown: a box within `grow` of some point of the segment up to best_t
    // is within grow + best_t |d| / 2 of that part's middle (Euclidean; the
    // slabs test the box grown on each axis, whose corners reach farther)
    const glm::dvec3 middle = from + (0.5 * best_t) * d;
    const double reach = grow + 0.5 * best_t * std::sqrt(glm::dot(d, d));
    const double reach2 = reach * reach * (1.0 + 1e-12);
    const bool no_slabs = node_bounds_.empty();  // (a refit tree has no NodeBounds: its boxes alone decide)
    Stack stack;
    std::uint32_t index = root_.index, count = root_.count;  // the node being visited
    double entry = 0.0;
    if (!slabs.cross(root_, best_t, entry)) return best;
    // the box the segment's points up to best_t span, grown (the slabs
    // accept no node box that misses it)
    const glm::dvec3 end = from + best_t * d;
    bool reachable =
        descend(BvhBox(glm::min(from, end) - glm::dvec3{grow}, glm::max(from, end) + glm::dvec3{grow}, glm::length(d)),
                index, count, work);
    while (reachable) {
      if (++work.nodes > config_.max_nodes) {
        best = out_of_budget();
        break;
      }
      if (count > 0) {
        for (std::uint32_t i = index; i < index + count; ++i) {
          ++work.primitives;
          leaf(i, from, d, best_t, best);
        }
      } else {
        const BvhNodePair& pair = pairs_[index];
        std::array<double, 2> t{};
        std::array<bool, 2> hit = slabs.cross(pair, best_t, t);
        if constexpr (Grown) {
          const std::array<double, 2> d2 = box_distance2(pair, middle);
          for (std::size_t c = 0; c < 2; ++c)
            hit[c] = hit[c] && d2[c] <= reach2 &&
                     (no_slabs || !worth_slab(pair, c, grow) ||
                      node_bounds_[2 * index + c].may_touch(from, d, grow, best_t));
        }
        if (hit[0] && hit[1]) {
          const std::size_t near = t[1] < t[0] ? 1 : 0, far = 1 - near;
          stack.push(Pending{pair.index[far], pair.count[far], t[far]});
          index = pair.index[near];
          count = pair.count[near];
          continue;
        }
        if (hit[0] || hit[1]) {
          const std::size_t side = hit[0] ? 0 : 1;
          index = pair.index[side];
          count = pair.count[side];
          continue;
        }
      }
      // pop, skipping boxes the best hit so far has made too far (the box
      // test again: its entry no longer before the segment's end)
      if (!stack.pop(index, count, [best_t](double key) { return Slabs<Grown>::within(key, best_t); })) break;
    }
    if (best.found()) best.point = from + best.t * d;
    if (stats) *stats = work;
    return best;
  }

  /// The query's trunk, skipped: from the node (index, count) down, while
  /// the query's box meets only one child's box, into that child (the
  /// other's subtree holds nothing the query meets, and its tests would
  /// reject it). The traversal then starts where the box meets both
  /// children, or at a leaf, and visits below it the nodes it would have
  /// visited from the root, in the same order, so it answers the same; only
  /// the trunk's full tests are saved (the first levels of a small query on
  /// a large mesh). Each step counts as a node visited. False: the box meets
  /// neither child's box (nothing is reachable).
  bool descend(const BvhBox& box, std::uint32_t& index, std::uint32_t& count, QueryStats& work) const noexcept {
    while (count == 0) {
      const BvhNodePair& pair = pairs_[index];
      const std::array<bool, 2> meets{box_meets(pair, 0, box), box_meets(pair, 1, box)};
      if (meets[0] == meets[1]) return meets[0];  // both: the traversal starts here; neither: nothing to meet
      ++work.nodes;
      const std::size_t side = meets[0] ? 0 : 1;
      index = pair.index[side];
      count = pair.count[side];
    }
    return true;
  }

  /// A seed (sweep_sphere) that counts: found, at a t within the move.
  [[nodiscard]] static bool usable(const BvhHit& seed) noexcept {
    return seed.found() && seed.t >= 0.0 && seed.t <= 1.0;
  }

  /// A segment query's answer once its node budget has run out: nothing
  /// found, and not complete (t = 0: the segment is not known free).
  [[nodiscard]] static BvhHit out_of_budget() noexcept {
    BvhHit h;
    h.t = 0.0;
    h.complete = false;
    return h;
  }

  /// A triangle as the queries want it: corner a, edges e1 = b - a,
  /// e2 = c - a, and its index in the mesh.
  struct Triangle {
    glm::dvec3 a{0.0}, e1{0.0}, e2{0.0};
    std::uint32_t id{0};
  };

  /// A node put on the traversal stack, with the key it was tested with:
  /// first_hit, the entry parameter of the segment into its box; closest,
  /// the squared distance to its box [m^2].
  struct Pending {
    std::uint32_t index, count;  ///< the node's (BvhNode)
    double key;
  };

  /// The nodes a query has still to visit, nearest last: bvh_max_depth
  /// deep, which the build's depth cap makes enough.
  struct Stack {
    std::array<Pending, bvh_max_depth> pending;  // filled before read: no initialisation needed
    std::size_t top{0};

    void push(const Pending& p) noexcept { pending[top++] = p; }
    /// The last node pushed whose key `keep` still accepts, into index and
    /// count (those it rejects are dropped); false when none is left.
    template <class Keep>
    bool pop(std::uint32_t& index, std::uint32_t& count, Keep&& keep) noexcept {
      while (top > 0) {
        const Pending& candidate = pending[--top];
        if (keep(candidate.key)) {
          index = candidate.index;
          count = candidate.count;
          return true;
        }
      }
      return false;
    }
  };

  /// The segment from + t d, t in [0, t_max], against node boxes (slabs),
  /// with the reciprocals of d computed once per query. An axis along which
  /// the segment does not move limits nothing when `from` lies within the
  /// box's extent on it and rejects the box otherwise (no 0 * inf = NaN
  /// slab); that test's branch goes the same way for the whole query.
  template <bool Grown>
  class Slabs {
   public:
    Slabs(const glm::dvec3& from, const glm::dvec3& d, double grow) noexcept : from_(from), grow_(grow) {
      for (int k = 0; k < 3; ++k) {
        inv_[k] = 1.0 / d[k];
        still_[static_cast<std::size_t>(k)] = !std::isfinite(inv_[k]);
      }
    }

    /// True when the segment meets the box before t_max; entry receives
    /// the entry parameter.
    bool cross(const BvhNode& n, double t_max, double& entry) const noexcept {
      double t0 = 0.0, t1 = t_max;
      for (int k = 0; k < 3; ++k) {
        auto lo = static_cast<double>(n.lo[static_cast<std::size_t>(k)]);
        auto hi = static_cast<double>(n.hi[static_cast<std::size_t>(k)]);
        if constexpr (Grown) {
          lo -= grow_;
          hi += grow_;
        }
        if (still_[static_cast<std::size_t>(k)]) {
          if (from_[k] < lo || from_[k] > hi) return false;
          continue;
        }
        const double a = (lo - from_[k]) * inv_[k];
        const double b = (hi - from_[k]) * inv_[k];
        // plain comparisons (std::fmin / fmax are library calls here): no NaN can occur
        t0 = detail::larger(t0, detail::smaller(a, b));
        t1 = detail::smaller(t1, detail::larger(a, b));
      }
      entry = t0;
      return within(t0, t1);
    }

    /// Both children of a pair at once (same arithmetic on both, which the
    /// compiler may do in one vector register); t receives the entries.
    std::array<bool, 2> cross(const BvhNodePair& pair, double t_max, std::array<double, 2>& t) const noexcept {
      std::array<double, 2> t0{0.0, 0.0}, t1{t_max, t_max};
      std::array<bool, 2> outside{false, false};
      for (std::size_t k = 0; k < 3; ++k) {
        for (std::size_t c = 0; c < 2; ++c) {
          auto lo = static_cast<double>(pair.lo[k][c]);
          auto hi = static_cast<double>(pair.hi[k][c]);
          if constexpr (Grown) {
            lo -= grow_;
            hi += grow_;
          }
          if (still_[k]) {
            outside[c] = outside[c] || from_[static_cast<int>(k)] < lo || from_[static_cast<int>(k)] > hi;
            continue;
          }
          const double a = (lo - from_[static_cast<int>(k)]) * inv_[static_cast<int>(k)];
          const double b = (hi - from_[static_cast<int>(k)]) * inv_[static_cast<int>(k)];
          t0[c] = detail::larger(t0[c], detail::smaller(a, b));
          t1[c] = detail::smaller(t1[c], detail::larger(a, b));
        }
      }
      t = t0;
      return {!outside[0] && within(t0[0], t1[0]), !outside[1] && within(t0[1], t1[1])};
    }

    /// The box test's last step: entry t0 no later than exit t1 (with a
    /// rounding allowance). A box met before t_max is still met before a
    /// smaller t_max' exactly when within(entry, t_max').
    static bool within(double t0, double t1) noexcept { return t0 <= t1 * (1.0 + 1e-12) + 1e-300; }

   private:
    glm::dvec3 from_;
    double grow_;  ///< [m] added to every box on each side (Grown)
    glm::dvec3 inv_{0.0};
    std::array<bool, 3> still_{};
  };

  /// True when a ball of radius r is worth testing against a child's
  /// NodeBounds besides its box: a leaf (the test stands for its
  /// triangles'), or a node less than 4 r across (a larger one's slab is
  /// seldom thin enough to pass the ball by; on bench_surface's sheet its
  /// test costs the 0.5 mm ball more than it saves).
  [[nodiscard]] static bool worth_slab(const BvhNodePair& pair, std::size_t side, double r) noexcept {
    if (pair.count[side] > 0) return true;
    const float across = std::max({pair.hi[0][side] - pair.lo[0][side], pair.hi[1][side] - pair.lo[1][side],
                                   pair.hi[2][side] - pair.lo[2][side]});
    return static_cast<double>(across) < 4.0 * r;
  }

  /// Every node's NodeBounds (node_bounds_[2 p + side]: pair p's child),
  /// bottom up (children are stored after their parent): a leaf's from its
  /// triangles as the queries see them, an inner node's from its children's
  /// (merge()). Linear time, no allocation.
  void bound_nodes() noexcept {
    for (std::size_t p = pairs_.size(); p-- > 0;)
      for (std::size_t side = 0; side < 2; ++side) {
        const std::uint32_t index = pairs_[p].index[side], count = pairs_[p].count[side];
        node_bounds_[2 * p + side] =
            count > 0 ? bound_slots(index, index + count) : merge(node_bounds_[2 * index], node_bounds_[2 * index + 1]);
      }
  }

  /// Bounds holding both children's: about a mean of their normals (each
  /// weighted by its reach squared, for its area), each child's slab and
  /// disk bounded in that frame (a point of a child's is within its
  /// thickness along its normal and its reach across it, so within
  /// |h| + thickness cos + reach sin along the new normal, at angle acos(cos)
  /// to the child's, and within the offset of the middles across it plus
  /// reach + thickness sin across it).
  [[nodiscard]] static NodeBounds merge(const NodeBounds& a, const NodeBounds& b) noexcept {
    NodeBounds out;
    if (!std::isfinite(a.reach + a.thickness + b.reach + b.thickness)) return out;  // never passed by
    const double wa = a.reach * a.reach + 1e-300, wb = b.reach * b.reach + 1e-300;
    const glm::dvec3 sum = wa * a.normal + wb * b.normal;
    const double length = glm::length(sum);
    if (!(length > 0.0) || !std::isfinite(length)) return out;
    out.normal = sum / length;
    out.middle = (wa * a.middle + wb * b.middle) / (wa + wb);
    double thickness = 0.0, reach = 0.0, coordinate = 0.0;
    for (const NodeBounds* child : {&a, &b}) {
      const double cosine = detail::smaller(1.0, std::fabs(glm::dot(out.normal, child->normal)));
      // (from the cross product: sqrt(1 - cos^2) loses angles under about 1e-8 rad)
      const double sine = detail::smaller(1.0, glm::length(glm::cross(out.normal, child->normal)));
      const glm::dvec3 offset = child->middle - out.middle;
      const double h = glm::dot(offset, out.normal);
      thickness = detail::larger(thickness, std::fabs(h) + child->thickness * cosine + child->reach * sine);
      reach = detail::larger(reach, glm::length(offset - h * out.normal) + child->reach + child->thickness * sine);
      coordinate = detail::larger(coordinate, largest_component(child->middle));
    }
    const double slack = 1e-9 * (coordinate + reach + thickness);  // rounding [m]
    out.reach = reach + slack;
    out.thickness = thickness + slack;
    return out;
  }

  /// The NodeBounds of the triangles in slots [begin, end).
  [[nodiscard]] NodeBounds bound_slots(std::uint32_t begin, std::uint32_t end) const noexcept {
    NodeBounds out;
    glm::dvec3 area{0.0}, sum{0.0};
    double tilt = 0.0;  // how far a triangle's computed normal leans off its corners' plane [m]
    for (std::uint32_t i = begin; i < end; ++i) {
      const Triangle& tri = triangles_[i];
      const glm::dvec3 cross = glm::cross(tri.e1, tri.e2);
      area += cross;
      sum += 3.0 * tri.a + tri.e1 + tri.e2;
      // the full test (sweep_ball_triangle) puts a face contact on the plane of the triangle's computed
      // normal, off its corners' plane by up to |e . n| for an edge e: far off for a sliver
      const double area2 = glm::length(cross);
      if (area2 > 0.0)
        tilt = detail::larger(tilt, detail::larger(std::fabs(glm::dot(tri.e1, cross / area2)),
                                                   std::fabs(glm::dot(tri.e2, cross / area2))));
    }
    const double length = glm::length(area);
    if (!(length > 0.0) || !std::isfinite(length)) return out;  // never passed by
    out.normal = area / length;
    out.middle = sum / (3.0 * static_cast<double>(end - begin));
    double thickness = 0.0, reach2 = 0.0, coordinate = 0.0;
    for (std::uint32_t i = begin; i < end; ++i) {
      const Triangle& tri = triangles_[i];
      for (const glm::dvec3& corner : {tri.a, tri.a + tri.e1, tri.a + tri.e2}) {
        const glm::dvec3 r = corner - out.middle;
        const double h = glm::dot(r, out.normal);
        thickness = detail::larger(thickness, std::fabs(h));
        const glm::dvec3 across = r - h * out.normal;
        reach2 = detail::larger(reach2, glm::dot(across, across));
        coordinate = detail::larger(coordinate, largest_component(corner));
      }
    }
    // rounding, relative to the coordinates and the node's size, and the normals' lean
    const double slack = 1e-9 * (coordinate + std::sqrt(reach2) + thickness) + 2.0 * tilt;
    out.reach = std::sqrt(reach2) + slack;
    out.thickness = thickness + slack;
    return out;
  }

  /// Every triangle's TriangleBounds, from the triangles as the queries see them.
  void bound_all() noexcept {
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      const Triangle& tri = triangles_[i];
      const glm::dvec3 b = tri.a + tri.e1, c = tri.a + tri.e2;
      const glm::dvec3 cross = glm::cross(tri.e1, tri.e2);
      const double area2 = glm::length(cross);  // twice the area [m^2]
      TriangleBounds& out = bounds_[i];
      out.normal = area2 > 0.0 ? cross / area2 : glm::dvec3{0.0};
      out.middle = (tri.a + b + c) / 3.0;
      out.reach = std::sqrt(detail::larger(
          glm::dot(tri.a - out.middle, tri.a - out.middle),
          detail::larger(glm::dot(b - out.middle, b - out.middle), glm::dot(c - out.middle, c - out.middle))));
      const double coordinate = largest_component(out.middle);
      // rounding, relative to the coordinates and the triangle; a sliver's
      // normal is off by about eps |e|^2 / area2, too much to rely on
      const double longest2 =
          detail::larger(glm::dot(tri.e1, tri.e1), detail::larger(glm::dot(tri.e2, tri.e2), glm::dot(c - b, c - b)));
      out.slack = area2 > 1e-3 * longest2 ? 1e-9 * (coordinate + out.reach) : std::numeric_limits<double>::infinity();
    }
  }

  /// Squared distances from p to both boxes of a pair [m^2].
  static std::array<double, 2> box_distance2(const BvhNodePair& pair, const glm::dvec3& p) noexcept {
    std::array<double, 2> d2{0.0, 0.0};
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t c = 0; c < 2; ++c) {
        const double below = static_cast<double>(pair.lo[k][c]) - p[static_cast<int>(k)];
        const double above = p[static_cast<int>(k)] - static_cast<double>(pair.hi[k][c]);
        const double out = detail::larger(0.0, detail::larger(below, above));
        d2[c] += out * out;
      }
    return d2;
  }

  static double box_distance2(const BvhNode& n, const glm::dvec3& p) noexcept {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double below = static_cast<double>(n.lo[k]) - p[k];
      const double above = p[k] - static_cast<double>(n.hi[k]);
      const double out = detail::larger(0.0, detail::larger(below, above));
      d2 += out * out;
    }
    return d2;
  }

  /// Moller-Trumbore against a front-facing triangle (d opposes e1 x e2),
  /// keeping the nearest hit with t in [0, best_t); a hit on the triangle's
  /// boundary goes through the tie rule (tie()).
  void intersect(std::uint32_t slot, const glm::dvec3& from, const glm::dvec3& d, double& best_t,
                 BvhHit& best) const noexcept {
    constexpr double tolerance = 1e-9;  // barycentric, relative to the triangle
    const Triangle& tri = triangles_[slot];
    const glm::dvec3 pvec = glm::cross(d, tri.e2);
    const double det = glm::dot(tri.e1, pvec);  // = -d . (e1 x e2): > 0 for a front face
    if (!(det > 0.0)) return;
    const glm::dvec3 tvec = from - tri.a;
    const double u = glm::dot(tvec, pvec);
    if (u < -tolerance * det || u > (1.0 + tolerance) * det) return;
    const glm::dvec3 qvec = glm::cross(tvec, tri.e1);
    const double v = glm::dot(d, qvec);
    if (v < -tolerance * det || u + v > (1.0 + tolerance) * det) return;
    double t = glm::dot(tri.e2, qvec) / det;
    if (!(t >= 0.0)) {  // a start behind the plane by rounding only (on the face, or on the boundary) counts as on it
      const double behind2 = t * t * glm::dot(d, d);  // [m^2]
      const double band = bvh_tie_band * bvh_tie_band * std::fmax(glm::dot(tri.e1, tri.e1), glm::dot(tri.e2, tri.e2));
      if (!(behind2 <= band)) return;
      t = 0.0;
    }
    if (!(t < best_t)) return;
    double b1 = u / det, b2 = v / det;
    std::uint32_t hit = slot;
    if (b1 < bvh_tie_band || b2 < bvh_tie_band || 1.0 - b1 - b2 < bvh_tie_band) {
      hit = tie(slot, b1, b2, from, d);
      if (hit == no_primitive) return;  // touches the boundary without entering
      if (hit != slot) {                // runs along the face on the other side: the hit is on it
        const Triangle& on = triangles_[hit];
        (void)detail::closest_on_triangle(from + t * d, on.a, on.e1, on.e2, b1, b2);
      }
    }
    best_t = t;
    best.triangle = triangles_[hit].id;
    best.t = t;
    best.b1 = b1;
    best.b2 = b2;
  }

  /// sweep_sphere()'s test of one leaf's triangle, as the traversals call
  /// it (always inlined there: it is their innermost step).
  struct BallLeaf {
    const MeshBvh* bvh;
    double radius;          ///< [m]
    std::uint32_t seeded;   ///< the seed's mesh index (no_primitive: none)
    bool slides{false};     ///< the move runs along `slide` (sweep_sphere's)
    glm::dvec3 slide{0.0};  ///< unit: sweep_sphere's, normalised
    double behind{0.0};     ///< points q with slide . q below this are out of the ball's reach [m]
    void operator()(std::uint32_t slot, const glm::dvec3& from, const glm::dvec3& d, double& best_t,
                    BvhHit& best) const noexcept HAPTICFIELD_ALWAYS_INLINE {
      bvh->touch(slot, from, d, *this, best_t, best);
    }
  };

  /// The largest coordinate of the mesh, in magnitude: of its root box [m].
  [[nodiscard]] double largest_coordinate() const noexcept {
    double largest = 0.0;
    for (std::size_t k = 0; k < 3; ++k)
      largest = detail::larger(largest, detail::larger(std::fabs(static_cast<double>(root_.lo[k])),
                                                       std::fabs(static_cast<double>(root_.hi[k]))));
    return largest;
  }

  /// True when the triangle lies wholly behind the plane a sliding ball
  /// cannot reach past (BallLeaf::behind): its corners all below it.
  [[nodiscard]] static bool out_of_reach(const Triangle& tri, const BallLeaf& ball) noexcept HAPTICFIELD_ALWAYS_INLINE {
    const double a = glm::dot(ball.slide, tri.a);  // [m]
    const double rise = detail::larger(0.0, detail::larger(glm::dot(ball.slide, tri.e1), glm::dot(ball.slide, tri.e2)));
    return a + rise < ball.behind;
  }

  /// The swept ball (centre from + t d, radius r) against one triangle:
  /// the earliest contact with its face (front only), its edges or its
  /// corners, kept when t < best_t, or when t = best_t and the triangle's
  /// mesh index is lower than best's, unless best is the seed (mesh index
  /// `seeded`) (sweep_sphere()).
  void touch(std::uint32_t slot, const glm::dvec3& from, const glm::dvec3& d, const BallLeaf& ball, double& best_t,
             BvhHit& best) const noexcept HAPTICFIELD_ALWAYS_INLINE {
    const Triangle& tri = triangles_[slot];
    const double r = ball.radius;
    // a tie may take best: asked a little past best_t, whose own tests count
    // a ball that just touches there as clear (sweep_ball_triangle answers
    // the same whatever it is asked with, when it meets the triangle sooner)
    if (!(best.found() && tri.id < best.triangle && best.triangle != ball.seeded)) {
      // behind the slide plane (three dot products), then its plane and circle
      if (!(ball.slides && out_of_reach(tri, ball)) && bounds_[slot].may_touch(from, d, r, best_t))
        (void)touch_triangle(tri.a, tri.e1, tri.e2, tri.id, from, d, r, best_t, best, true);
      return;
    }
    double t = detail::smaller(1.0, best_t + 1e-9 * (best_t + 1e-3));
    if ((ball.slides && out_of_reach(tri, ball)) || !bounds_[slot].may_touch(from, d, r, t)) return;
    BvhHit candidate;
    if (touch_triangle(tri.a, tri.e1, tri.e2, tri.id, from, d, r, t, candidate, true) && t <= best_t) {
      best_t = t;
      best = candidate;
    }
  }

  /// sweep_sphere() through `near` (false: the tree must answer): the
  /// sweep's box, grown by the radius, inside near's region whose leaves
  /// fit, or a short sweep (no longer than bvh_neighbourhood_sweep radii up
  /// to its seed's t) that gathers a new region first. The leaves are
  /// tested in tree order, each by its box, its slab and its triangles
  /// (`leaf`), so the answer is the tree's.
  template <class Leaf>
  bool sweep_near(const glm::dvec3& from, const glm::dvec3& to, double radius, const BvhHit& seed, Leaf&& leaf,
                  Neighbourhood& near, BvhHit& best, QueryStats& work) const noexcept {
    const glm::dvec3 d = to - from;
    if (triangles_.empty() || root_.count > 0 || !is_finite(from) || !is_finite(d)) return false;
    double best_t = 1.0;
    best = BvhHit{};
    if (usable(seed)) {
      best = seed;
      best_t = seed.t;
    }
    const glm::dvec3 end = from + best_t * d;
    const double length = glm::length(d);
    const glm::dvec3 grown{radius};
    const BvhBox box(glm::min(from, end) - grown, glm::max(from, end) + grown, length);
    if (!near.gathered || near.tree != pairs_.data() || near.refits != refits_ || !near.box.holds(box)) {
      const double reach = bvh_neighbourhood_reach * radius;  // [m]
      // a long sweep: the tree's order finds its contact sooner
      if (!(best_t * length <= bvh_neighbourhood_sweep * radius)) return false;
      gather(BvhBox(glm::min(from, end) - grown - glm::dvec3{reach}, glm::max(from, end) + grown + glm::dvec3{reach},
                    length),
             near, work);
      // too many leaves (a ball large against the triangles): the tree
      // answers the sweeps around, and the next try waits until the ball
      // has gone 8 regions' reach away, so the trying costs little
      if (!near.fits)
        near.box = BvhBox(glm::min(from, end) - grown - glm::dvec3{8.0 * reach},
                          glm::max(from, end) + grown + glm::dvec3{8.0 * reach}, length);
    }
    if (!near.fits) return false;
    // every leaf counts as a node visited
    work.nodes += near.count;
    if (work.nodes > config_.max_nodes) {
      best = out_of_budget();
      return true;
    }
    // the leaves' boxes against the sweep's, all at once (each test a 0 or
    // a 1, and'ed without a branch, so that the loop runs several leaves at
    // a time)
    static_assert(bvh_neighbourhood_leaves % 8 == 0);
    alignas(8) std::array<std::uint8_t, bvh_neighbourhood_leaves> meets;  // filled for [0, count) before read
    const auto bit = [](bool b) noexcept { return static_cast<unsigned>(b); };
    for (std::size_t k = 0; k < near.count; ++k)
      meets[k] = static_cast<std::uint8_t>(bit(near.lo[0][k] <= box.hi[0]) & bit(near.hi[0][k] >= box.lo[0]) &
                                           bit(near.lo[1][k] <= box.hi[1]) & bit(near.hi[1][k] >= box.lo[1]) &
                                           bit(near.lo[2][k] <= box.hi[2]) & bit(near.hi[2][k] >= box.lo[2]));
    for (std::size_t k = near.count; k % 8 != 0; ++k)
      meets[k] = 0;
    // the leaves met, in order: eight answers read at once, and only the
    // ones met visited (no branch a leaf missed, which no predictor foresees)
    constexpr bool little = std::endian::native == std::endian::little;
    const bool no_slabs = node_bounds_.empty();
    for (std::size_t first = 0; first < near.count; first += 8) {
      std::uint64_t eight = 0;  // meets[first, first + 8), in memory order
      std::memcpy(&eight, &meets[first], sizeof eight);
      while (eight != 0) {
        const int bit_at = little ? std::countr_zero(eight) : 63 - std::countl_zero(eight);  // the first one met
        eight &= ~(std::uint64_t{1} << bit_at);
        const std::uint32_t node = near.leaves[first + static_cast<std::size_t>(little ? bit_at / 8 : 7 - bit_at / 8)];
        if (!no_slabs && !node_bounds_[node].may_touch(from, d, radius, best_t)) continue;
        const BvhNodePair& pair = pairs_[node / 2];
        const std::size_t side = node % 2;
        for (std::uint32_t i = pair.index[side]; i < pair.index[side] + pair.count[side]; ++i) {
          ++work.primitives;
          leaf(i, from, d, best_t, best);
        }
      }
    }
    if (best.found()) best.point = from + best.t * d;
    return true;
  }

  /// closest()'s test of one triangle: its point nearest to p taken when
  /// nearer than best_d2 [m^2], or as near and of a lower mesh index (so
  /// the answer does not hang on the order the triangles are visited in).
  static void keep_nearer(const Triangle& tri, const glm::dvec3& p, BvhHit& best,
                          double& best_d2) noexcept HAPTICFIELD_ALWAYS_INLINE {
    double b1 = 0.0, b2 = 0.0;
    const glm::dvec3 q = detail::closest_on_triangle(p, tri.a, tri.e1, tri.e2, b1, b2);
    const glm::dvec3 r = q - p;
    const double d2 = glm::dot(r, r);  // [m^2]
    // (none found yet: best.triangle is no_primitive, above any index)
    if (d2 < best_d2 || (d2 == best_d2 && tri.id < best.triangle)) {
      best_d2 = d2;
      best.triangle = tri.id;
      best.point = q;
      best.b1 = b1;
      best.b2 = b2;
    }
  }

  /// closest()'s walk of the tree from its root: the nearest triangle to p
  /// within best_d2 [m^2] into best (best_d2 shrinks as nearer ones turn up).
  void closest_tree(const glm::dvec3& p, double max_distance, BvhHit& best, double& best_d2,
                    QueryStats& work) const noexcept {
    Stack stack;
    std::uint32_t index = root_.index, count = root_.count;  // the node being visited
    if (!(box_distance2(root_, p) <= best_d2)) return;
    // (a box more than max_distance away on one axis is farther than that)
    const glm::dvec3 around{std::isfinite(max_distance) ? max_distance : std::numeric_limits<double>::infinity()};
    bool reachable = descend(BvhBox(p - around, p + around), index, count, work);
    const double reach = std::sqrt(best_d2);  // [m]
    const bool slabs = !node_bounds_.empty() && std::isfinite(max_distance);
    while (reachable) {
      if (++work.nodes > config_.max_nodes) {
        best.complete = false;
        break;
      }
      if (count > 0) {
        for (std::uint32_t i = index; i < index + count; ++i) {
          ++work.primitives;
          keep_nearer(triangles_[i], p, best, best_d2);
        }
      } else {
        const BvhNodePair& pair = pairs_[index];
        std::array<double, 2> d2 = box_distance2(pair, p);
        // a small node's slab: nearer bounds for a ball's query, whose reach
        // takes in the boxes of the smooth surface around it
        if (slabs)
          for (std::size_t c = 0; c < 2; ++c)
            if (d2[c] <= best_d2 && worth_slab(pair, c, reach))
              d2[c] = detail::larger(d2[c], node_bounds_[2 * std::size_t{index} + c].distance2_below(p));
        const std::size_t near = d2[1] < d2[0] ? 1 : 0, far = 1 - near;
        if (d2[near] <= best_d2) {
          if (d2[far] <= best_d2) stack.push(Pending{pair.index[far], pair.count[far], d2[far]});
          index = pair.index[near];
          count = pair.count[near];
          continue;
        }
      }
      // pop, skipping boxes farther than the best point so far
      if (!stack.pop(index, count, [best_d2](double key) { return key <= best_d2; })) break;
    }
  }

  /// closest() through `near` (false: the tree must answer): p's reach,
  /// max_distance around it, inside near's region whose leaves fit, so
  /// every leaf that reach meets is held. The leaf whose box is nearest is
  /// tested first, then every other whose box, and slab, is within the
  /// nearest distance found so far; each held leaf counts as a node, as in
  /// sweep_near().
  bool closest_near(const glm::dvec3& p, double max_distance, const Neighbourhood& near, BvhHit& best, double& best_d2,
                    QueryStats& work) const noexcept {
    if (!near.gathered || !near.fits || near.tree != pairs_.data() || near.refits != refits_ ||
        !std::isfinite(max_distance))
      return false;
    const glm::dvec3 around{max_distance};
    if (!near.box.holds(BvhBox(p - around, p + around))) return false;
    if (work.nodes + near.count > config_.max_nodes) return false;  // the tree's walk may fit its budget
    work.nodes += near.count;
    std::array<double, bvh_neighbourhood_leaves> box_d2;  // [m^2], filled for [0, count) before read
    std::size_t nearest = 0;
    for (std::size_t k = 0; k < near.count; ++k) {
      const BvhNode leaf{
          {near.lo[0][k], near.lo[1][k], near.lo[2][k]}, 0, {near.hi[0][k], near.hi[1][k], near.hi[2][k]}, 0};
      box_d2[k] = box_distance2(leaf, p);
      if (box_d2[k] < box_d2[nearest]) nearest = k;
    }
    const bool slabs = !node_bounds_.empty();
    const auto visit = [&](std::size_t k) noexcept {
      if (!(box_d2[k] <= best_d2)) return;
      const std::uint32_t node = near.leaves[k];
      if (slabs && !(node_bounds_[node].distance2_below(p) <= best_d2)) return;
      const BvhNodePair& pair = pairs_[node / 2];
      const std::size_t side = node % 2;
      for (std::uint32_t i = pair.index[side]; i < pair.index[side] + pair.count[side]; ++i) {
        ++work.primitives;
        keep_nearer(triangles_[i], p, best, best_d2);
      }
    };
    if (near.count > 0) visit(nearest);
    for (std::size_t k = 0; k < near.count; ++k)
      if (k != nearest) visit(k);
    return true;
  }

  /// Fills `near` with the leaves whose boxes meet `box`, depth first
  /// (each pair visited counts as a node); near.fits is false when they do
  /// not fit.
  void gather(const BvhBox& box, Neighbourhood& near, QueryStats& work) const noexcept {
    near.box = box;
    near.tree = pairs_.data();
    near.refits = refits_;
    near.gathered = true;
    near.fits = false;
    near.count = 0;
    // children still to visit (2 pair + side), the next on top; a depth
    // first walk leaves at most two a level
    std::array<std::uint32_t, 2 * bvh_max_depth> stack;  // filled before read
    std::size_t top = 0;
    if (box_meets(root_, box)) {
      const auto visit = [&](std::uint32_t p) noexcept {
        ++work.nodes;
        for (std::size_t c = 2; c-- > 0;)  // the right child under the left
          if (box_meets(pairs_[p], c, box)) stack[top++] = static_cast<std::uint32_t>(2 * p + c);
      };
      visit(root_.index);
      while (top > 0) {
        const std::uint32_t node = stack[--top];
        const BvhNodePair& pair = pairs_[node / 2];
        const std::size_t side = node % 2;
        if (pair.count[side] == 0) {
          visit(pair.index[side]);
        } else {
          if (near.count == near.leaves.size()) return;  // too many: not kept
          for (std::size_t k = 0; k < 3; ++k) {
            near.lo[k][near.count] = pair.lo[k][side];
            near.hi[k][near.count] = pair.hi[k][side];
          }
          near.leaves[near.count++] = node;
        }
      }
    }
    near.fits = true;
  }

  /// True when a node's box meets `box` (the root's, or a pair's child's).
  [[nodiscard]] static bool box_meets(const BvhNode& n, const BvhBox& box) noexcept {
    for (std::size_t k = 0; k < 3; ++k)
      if (!(n.lo[k] <= box.hi[k] && n.hi[k] >= box.lo[k])) return false;
    return true;
  }
  [[nodiscard]] static bool box_meets(const BvhNodePair& pair, std::size_t side, const BvhBox& box) noexcept {
    return pair.lo[0][side] <= box.hi[0] && pair.hi[0][side] >= box.lo[0] && pair.lo[1][side] <= box.hi[1] &&
           pair.hi[1][side] >= box.lo[1] && pair.lo[2][side] <= box.hi[2] && pair.hi[2][side] >= box.lo[2];
  }

  /// The tie rule (file comment) for a segment along d that meets the
  /// triangle in `slot` at barycentric (1 - b1 - b2, b1, b2) within
  /// bvh_tie_band of its boundary: the slot it hits (this one, or the face
  /// it runs along), or no_primitive when it does not enter the solid.
  [[nodiscard]] std::uint32_t tie(std::uint32_t slot, double b1, double b2, const glm::dvec3& from,
                                  const glm::dvec3& d) const noexcept {
    if (adjacency_.size() != triangles_.size()) return slot;
    const std::array<double, 3> b{1.0 - b1 - b2, b1, b2};
    int small = 0, large = 0;
    for (int k = 0; k < 3; ++k) {
      if (b[static_cast<std::size_t>(k)] < bvh_tie_band)
        ++small;
      else
        large = k;
    }
    const double length = glm::length(d);
    if (!(length > 0.0)) return slot;
    const glm::dvec3 along = d / length;
    // the faces whose half spaces bound the solid here (convex only)
    std::array<std::uint32_t, bvh_max_fan> faces{};
    int count = 0;
    if (small == 1) {
      // edge j runs from vertex j to j + 1, opposite vertex j + 2
      int edge = 0;
      for (int k = 0; k < 3; ++k)
        if (b[static_cast<std::size_t>(k)] < bvh_tie_band) edge = (k + 1) % 3;
      const std::uint32_t other = adjacency_[slot].neighbour[static_cast<std::size_t>(edge)];
      if (other == no_primitive || concave(slot, other)) return slot;
      faces[0] = slot;
      faces[1] = other;
      count = 2;
    } else if (small == 2) {
      count = fan(slot, adjacency_[slot].vertex[static_cast<std::size_t>(large)], faces);
      if (count == 0) return slot;
    } else {
      return slot;
    }
    // convex here: the segment enters only behind every face
    double most = -std::numeric_limits<double>::infinity();
    std::uint32_t along_face = slot;
    bool ends_outside = false;  // the segment's end in front of a face it moves away from
    for (int i = 0; i < count; ++i) {
      const Triangle& f = triangles_[faces[static_cast<std::size_t>(i)]];
      const glm::dvec3 n = glm::cross(f.e1, f.e2);
      const double s = glm::dot(along, n) / glm::length(n);  // sine of the angle to the face's plane
      // (within the tie band of its plane counts as on it)
      const double band = bvh_tie_band * std::sqrt(std::fmax(glm::dot(f.e1, f.e1), glm::dot(f.e2, f.e2)));
      if (s > bvh_tie_angle && glm::dot(from + d - f.a, n) / glm::length(n) >= -band) ends_outside = true;
      if (s > most) {
        most = s;
        along_face = faces[static_cast<std::size_t>(i)];
      }
    }
    if (most < -bvh_tie_angle) return slot;  // behind every face: enters
    // moves away from a face and ends in front of it: the segment only
    // touched the boundary (it never stops inside the solid)
    if (most > bvh_tie_angle) return ends_outside ? no_primitive : slot;
    return along_face;  // runs along it
  }

  /// True when the edge between two neighbours is concave: the far corner
  /// of `other` lies in front of the plane of `slot` (by more than rounding:
  /// a flat edge, 1e-9 of the triangle's size or less, is not).
  [[nodiscard]] bool concave(std::uint32_t slot, std::uint32_t other) const noexcept {
    const Triangle& a = triangles_[slot];
    const Triangle& o = triangles_[other];
    const glm::dvec3 n = glm::normalize(glm::cross(a.e1, a.e2));
    const std::array<glm::dvec3, 3> corners{o.a, o.a + o.e1, o.a + o.e2};
    double far = 0.0;  // the corner farthest from the plane either way [m]
    for (const glm::dvec3& c : corners) {
      const double h = glm::dot(c - a.a, n);
      if (std::fabs(h) > std::fabs(far)) far = h;
    }
    const double size = std::sqrt(std::fmax(glm::dot(o.e1, o.e1), glm::dot(o.e2, o.e2)));
    return far > 1e-9 * size;
  }

  /// The closed fan of triangles around welded vertex `vertex` of `slot`,
  /// into faces; 0 when it is open, larger than bvh_max_fan, or has a
  /// concave edge (the plain rule applies then).
  int fan(std::uint32_t slot, std::uint32_t vertex, std::array<std::uint32_t, bvh_max_fan>& faces) const noexcept {
    std::uint32_t current = slot;
    int count = 0;
    for (;;) {
      if (count == bvh_max_fan) return 0;
      faces[static_cast<std::size_t>(count++)] = current;
      const Adjacency& at = adjacency_[current];
      int k = 0;
      while (k < 3 && at.vertex[static_cast<std::size_t>(k)] != vertex)
        ++k;
      if (k == 3) return 0;
      const std::uint32_t next = at.neighbour[static_cast<std::size_t>(k)];  // across the edge from the vertex on
      if (next == no_primitive || concave(current, next)) return 0;
      if (next == slot) return count;
      current = next;
    }
  }

  /// Build-time state: per-triangle boxes and centroids, the order being
  /// built, the recursion.
  class Builder {
   public:
    Builder(const TriangleMesh& mesh, MeshBvh& out) : mesh_(mesh), out_(out) {}

    void run() {
      const std::size_t n = mesh_.triangles.size();
      order_.reserve(n);
      lo_.reserve(n);
      hi_.reserve(n);
      centre_.reserve(n);
      for (std::size_t i = 0; i < n; ++i) {
        const auto& t = mesh_.triangles[i];
        const glm::dvec3 a = mesh_.positions[t[0]], b = mesh_.positions[t[1]], c = mesh_.positions[t[2]];
        const double longest = std::fmax(glm::length(b - a), std::fmax(glm::length(c - b), glm::length(a - c)));
        const double area2 = glm::length(glm::cross(b - a, c - a));                   // twice the area [m^2]
        if (!(area2 > 1e-12 * longest * longest) || !std::isfinite(area2)) continue;  // no area: never hit
        order_.push_back(static_cast<std::uint32_t>(i));
        lo_.push_back(glm::min(a, glm::min(b, c)));
        hi_.push_back(glm::max(a, glm::max(b, c)));
        centre_.push_back((a + b + c) / 3.0);
      }
      if (order_.empty()) return;
      out_.reserve_array(out_.pairs_, order_.size());  // at most n - 1 inner nodes: never reallocated while building
      split(root_ref, 0, static_cast<std::uint32_t>(order_.size()), 1);
      out_.reserve_array(out_.triangles_, order_.size());
      for (const std::uint32_t i : order_) {
        const auto& t = mesh_.triangles[i];
        const glm::dvec3 a = mesh_.positions[t[0]];
        out_.triangles_.push_back(Triangle{a, mesh_.positions[t[1]] - a, mesh_.positions[t[2]] - a, i});
      }
      out_.reserve_array(out_.bounds_, out_.triangles_.size());
      out_.bounds_.resize(out_.triangles_.size());
      out_.bound_all();
      out_.reserve_array(out_.node_bounds_, 2 * out_.pairs_.size());
      out_.node_bounds_.resize(2 * out_.pairs_.size());
      out_.bound_nodes();
      connect();
    }

   private:
    /// Welds the vertices by position and pairs the triangles across their
    /// edges (MeshBvh::Adjacency, the tie rule's data).
    void connect() {
      const std::size_t n = out_.triangles_.size();
      // welded ids: vertices sorted by position, equal positions one id
      std::vector<std::uint32_t> by_position(mesh_.positions.size());
      for (std::uint32_t i = 0; i < by_position.size(); ++i)
        by_position[i] = i;
      const auto key = [&](std::uint32_t i) {
        const glm::dvec3& p = mesh_.positions[i];
        return std::array<double, 3>{p.x + 0.0, p.y + 0.0, p.z + 0.0};  // + 0.0: -0 and +0 weld
      };
      std::sort(by_position.begin(), by_position.end(),
                [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
      std::vector<std::uint32_t> weld(mesh_.positions.size());
      std::uint32_t id = 0;
      for (std::size_t i = 0; i < by_position.size(); ++i) {
        if (i > 0 && key(by_position[i]) != key(by_position[i - 1])) ++id;
        weld[by_position[i]] = id;
      }
      out_.reserve_array(out_.adjacency_, n);
      out_.adjacency_.assign(n, Adjacency{});
      struct Edge {
        std::uint64_t key;   ///< lower welded id << 32 | higher
        std::uint32_t slot;  ///< triangle, tree order
        std::uint8_t edge;   ///< 0..2
        bool forward;        ///< runs from the lower id to the higher
      };
      std::vector<Edge> edges;
      edges.reserve(3 * n);
      for (std::uint32_t slot = 0; slot < n; ++slot) {
        const auto& t = mesh_.triangles[out_.triangles_[slot].id];
        for (std::size_t k = 0; k < 3; ++k)
          out_.adjacency_[slot].vertex[k] = weld[t[k]];
        for (std::uint8_t e = 0; e < 3; ++e) {
          const std::uint32_t from = weld[t[e]], to = weld[t[(e + 1) % 3]];
          if (from == to) continue;
          const std::uint64_t lo = std::min(from, to), hi = std::max(from, to);
          edges.push_back(Edge{lo << 32 | hi, slot, e, from < to});
        }
      }
      std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) { return a.key < b.key; });
      for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j].key == edges[i].key)
          ++j;
        // a manifold edge: two triangles, opposite directions
        if (j - i == 2 && edges[i].forward != edges[i + 1].forward && edges[i].slot != edges[i + 1].slot) {
          out_.adjacency_[edges[i].slot].neighbour[edges[i].edge] = edges[i + 1].slot;
          out_.adjacency_[edges[i + 1].slot].neighbour[edges[i + 1].edge] = edges[i].slot;
        }
        i = j;
      }
    }

    struct Bounds {
      glm::dvec3 lo{std::numeric_limits<double>::max()};
      glm::dvec3 hi{-std::numeric_limits<double>::max()};
      void grow(const glm::dvec3& a, const glm::dvec3& b) noexcept {
        lo = glm::min(lo, a);
        hi = glm::max(hi, b);
      }
      void grow(const Bounds& o) noexcept { grow(o.lo, o.hi); }
      [[nodiscard]] double half_area() const noexcept {
        if (lo.x > hi.x) return 0.0;
        const glm::dvec3 e = hi - lo;
        return e.x * e.y + e.y * e.z + e.z * e.x;
      }
    };

    static constexpr int bins = 16;

    static std::size_t ceil_log2(std::size_t n) noexcept {
      std::size_t k = 0;
      while ((std::size_t{1} << k) < n)
        ++k;
      return k;
    }

    /// A node being built: root_ref, or 2 pair + side.
    static constexpr std::uint32_t root_ref = std::numeric_limits<std::uint32_t>::max();

    void set_node(std::uint32_t ref, std::uint32_t index, std::uint32_t count) noexcept {
      if (ref == root_ref) {
        out_.root_.index = index;
        out_.root_.count = count;
      } else {
        out_.pairs_[ref / 2].index[ref % 2] = index;
        out_.pairs_[ref / 2].count[ref % 2] = count;
      }
    }

    void set_box(std::uint32_t ref, const Bounds& b) {
      for (int k = 0; k < 3; ++k) {
        float lo = static_cast<float>(b.lo[k]);
        float hi = static_cast<float>(b.hi[k]);
        if (static_cast<double>(lo) > b.lo[k]) lo = std::nextafter(lo, -std::numeric_limits<float>::infinity());
        if (static_cast<double>(hi) < b.hi[k]) hi = std::nextafter(hi, std::numeric_limits<float>::infinity());
        const auto axis = static_cast<std::size_t>(k);
        if (ref == root_ref) {
          out_.root_.lo[axis] = lo;
          out_.root_.hi[axis] = hi;
        } else {
          out_.pairs_[ref / 2].lo[axis][ref % 2] = lo;
          out_.pairs_[ref / 2].hi[axis][ref % 2] = hi;
        }
      }
    }

    void split(std::uint32_t node, std::uint32_t begin, std::uint32_t end, std::size_t depth) {
      out_.depth_ = std::max(out_.depth_, depth);
      Bounds box, centres;
      for (std::uint32_t i = begin; i < end; ++i) {
        box.grow(lo_[i], hi_[i]);
        centres.grow(centre_[i], centre_[i]);
      }
      set_box(node, box);
      const std::uint32_t count = end - begin;
      if (count <= bvh_max_leaf) {
        set_node(node, begin, count);
        return;
      }
      std::uint32_t middle = begin;
      if (depth + ceil_log2(count) + 1 < bvh_max_depth) middle = sah_split(begin, end, centres);
      if (middle == begin || middle == end) middle = median_split(begin, end, centres);
      const auto pair = static_cast<std::uint32_t>(out_.pairs_.size());
      out_.pairs_.emplace_back();
      set_node(node, pair, 0);
      split(2 * pair, begin, middle, depth + 1);
      split(2 * pair + 1, middle, end, depth + 1);
    }

    /// Binned SAH on all three axes; returns the partition point, or begin
    /// when no split beats the others (all centroids at one point).
    std::uint32_t sah_split(std::uint32_t begin, std::uint32_t end, const Bounds& centres) {
      double best_cost = std::numeric_limits<double>::max();
      int best_axis = -1, best_bin = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double lo = centres.lo[axis], extent = centres.hi[axis] - centres.lo[axis];
        if (!(extent > 0.0)) continue;
        const double scale = bins / extent;
        std::array<Bounds, bins> bin_box{};
        std::array<std::uint32_t, bins> bin_count{};
        for (std::uint32_t i = begin; i < end; ++i) {
          const int b = std::min(bins - 1, static_cast<int>((centre_[i][axis] - lo) * scale));
          bin_box[static_cast<std::size_t>(b)].grow(lo_[i], hi_[i]);
          ++bin_count[static_cast<std::size_t>(b)];
        }
        std::array<double, bins> right_cost{};
        Bounds acc;
        std::uint32_t acc_count = 0;
        for (int b = bins - 1; b > 0; --b) {
          acc.grow(bin_box[static_cast<std::size_t>(b)]);
          acc_count += bin_count[static_cast<std::size_t>(b)];
          right_cost[static_cast<std::size_t>(b)] = acc.half_area() * acc_count;
        }
        acc = Bounds{};
        acc_count = 0;
        for (int b = 0; b < bins - 1; ++b) {
          acc.grow(bin_box[static_cast<std::size_t>(b)]);
          acc_count += bin_count[static_cast<std::size_t>(b)];
          const double cost = acc.half_area() * acc_count + right_cost[static_cast<std::size_t>(b + 1)];
          if (acc_count > 0 && acc_count < end - begin && cost < best_cost) {
            best_cost = cost;
            best_axis = axis;
            best_bin = b;
          }
        }
      }
      if (best_axis < 0) return begin;
      const double lo = centres.lo[best_axis];
      const double scale = bins / (centres.hi[best_axis] - lo);
      return partition(begin, end, [&](std::uint32_t i) {
        return std::min(bins - 1, static_cast<int>((centre_[i][best_axis] - lo) * scale)) <= best_bin;
      });
    }

    /// Splits at the median triangle along the longest centroid axis
    /// (halves the node whatever the geometry: bounds the depth).
    std::uint32_t median_split(std::uint32_t begin, std::uint32_t end, const Bounds& centres) {
      const glm::dvec3 e = centres.hi - centres.lo;
      const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
      const std::uint32_t middle = begin + (end - begin) / 2;
      std::vector<std::uint32_t> idx(end - begin);
      for (std::uint32_t i = 0; i < end - begin; ++i)
        idx[i] = begin + i;
      std::nth_element(idx.begin(), idx.begin() + (middle - begin), idx.end(),
                       [&](std::uint32_t a, std::uint32_t b) { return centre_[a][axis] < centre_[b][axis]; });
      permute(begin, idx);
      return middle;
    }

    template <class Left>
    std::uint32_t partition(std::uint32_t begin, std::uint32_t end, Left&& left) {
      std::uint32_t i = begin, j = end;
      while (i < j) {
        if (left(i)) {
          ++i;
        } else {
          --j;
          swap_items(i, j);
        }
      }
      return i;
    }

    void swap_items(std::uint32_t a, std::uint32_t b) noexcept {
      std::swap(order_[a], order_[b]);
      std::swap(lo_[a], lo_[b]);
      std::swap(hi_[a], hi_[b]);
      std::swap(centre_[a], centre_[b]);
    }

    /// Reorders items [begin, begin + idx.size()) so that slot k holds the
    /// item that was at idx[k].
    void permute(std::uint32_t begin, const std::vector<std::uint32_t>& idx) {
      const std::size_t n = idx.size();
      std::vector<std::uint32_t> order(n);
      std::vector<glm::dvec3> lo(n), hi(n), centre(n);
      for (std::size_t k = 0; k < n; ++k) {
        order[k] = order_[idx[k]];
        lo[k] = lo_[idx[k]];
        hi[k] = hi_[idx[k]];
        centre[k] = centre_[idx[k]];
      }
      std::copy(order.begin(), order.end(), order_.begin() + begin);
      std::copy(lo.begin(), lo.end(), lo_.begin() + begin);
      std::copy(hi.begin(), hi.end(), hi_.begin() + begin);
      std::copy(centre.begin(), centre.end(), centre_.begin() + begin);
    }

    const TriangleMesh& mesh_;
    MeshBvh& out_;
    std::vector<std::uint32_t> order_;
    std::vector<glm::dvec3> lo_, hi_, centre_;
  };

  /// Each triangle's neighbours (in tree order) across its edges (edge j
  /// from vertex j to j + 1; no_primitive: none) and its welded vertices.
  struct Adjacency {
    std::array<std::uint32_t, 3> neighbour{no_primitive, no_primitive, no_primitive};
    std::array<std::uint32_t, 3> vertex{};
  };

  /// Room for n elements in one of the arrays a tick reads, on 2 MB pages
  /// unless the config says otherwise.
  template <class T>
  void reserve_array(std::vector<T>& v, std::size_t n) const {
    if (config_.huge_pages)
      reserve_on_huge_pages(v, n);
    else
      v.reserve(n);
  }

  /// `from`'s elements into the empty `to`, where reserve_array() puts them.
  template <class T>
  void copy_array(std::vector<T>& to, const std::vector<T>& from) const {
    reserve_array(to, from.size());
    to.assign(from.begin(), from.end());
  }

  BvhNode root_{};
  std::vector<BvhNodePair> pairs_;
  std::vector<Triangle> triangles_;
  std::vector<Adjacency> adjacency_;     ///< parallel to triangles_
  std::vector<TriangleBounds> bounds_;   ///< parallel to triangles_
  std::vector<NodeBounds> node_bounds_;  ///< two a pair: node_bounds_[2 p + side], pair p's child
  std::size_t depth_{0};
  MeshBvhConfig config_{};
  std::uint64_t refits_{0};  ///< refit() calls (a Neighbourhood gathered before one is gathered again)
};

}  // namespace hapticfield
