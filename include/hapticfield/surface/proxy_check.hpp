#pragma once
/// @file proxy_check.hpp
/// The proxy checked against a brute-force oracle, for tests and debugging
/// (never on the servo path: building a checker allocates, and a check
/// scans every triangle near a path piece with a plain test, not the tree).
///
/// The invariant checked: the proxy never passes through the surface. Each
/// straight piece of the path it took in a tick (ProxyConstraint::last_path)
/// must not enter a triangle from its front and leave behind it: start more
/// than `margin` in front of the triangle's plane, end more than `margin`
/// behind it, and cross the plane inside the triangle by more than
/// `interior` (barycentric, relative: a crossing on an edge or a vertex is
/// a tie, which MeshBvh's tie rule decides). The margin is relative to the
/// triangle's longest edge, like the proxy's own offset.
///
///   MeshChecker checker(mesh);                 // a uniform grid over the triangles
///   CheckedProxy checked(ProxyConstraint(MeshShape(mesh), {}), mesh);
///   checked.contact(probe);                    // as the proxy, plus the check
///   checked.violations();                      // pieces that crossed the surface

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield {

/// One straight piece of a path that passed through a triangle from its
/// front.
struct PathCrossing {
  int piece{-1};                         ///< the piece: points[piece] -> points[piece + 1]; -1: none
  std::uint32_t triangle{no_primitive};  ///< the triangle crossed (mesh index)
  double t{0.0};                         ///< where along the piece [0, 1]
  glm::dvec3 from{0.0}, to{0.0};         ///< the piece [m]
  [[nodiscard]] bool found() const noexcept { return piece >= 0; }
};

struct MeshCheckerConfig {
  double margin{1e-9};                  ///< how far past a plane counts as crossing it, relative to the triangle [-]
  double interior{2.0 * bvh_tie_band};  ///< how far inside the triangle the crossing must be (barycentric) [-]
};

/// The mesh in a uniform grid of cells (about two triangles a cell), so a
/// short piece is tested against the triangles near it only; each test is
/// the plain plane-and-barycentric one, independent of MeshBvh.
class MeshChecker {
 public:
  /// @throws std::invalid_argument for an invalid mesh or margins.
  explicit MeshChecker(const TriangleMesh& mesh, const MeshCheckerConfig& config = {}) : config_(config) {
    mesh.validate();
    if (!(config.margin >= 0.0) || !(config.interior >= 0.0) || !(config.interior < 1.0 / 3.0))
      throw std::invalid_argument("MeshChecker: margin >= 0 and 0 <= interior < 1/3");
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      const auto& t = mesh.triangles[i];
      const glm::dvec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
      const glm::dvec3 n = glm::cross(b - a, c - a);
      const double size = std::fmax(glm::length(b - a), std::fmax(glm::length(c - b), glm::length(a - c)));
      if (!(glm::length(n) > 1e-12 * size * size)) continue;  // no area: no face to cross
      triangles_.push_back(Face{a, b, c, glm::normalize(n), size, static_cast<std::uint32_t>(i)});
      lo_ = glm::min(lo_, glm::min(a, glm::min(b, c)));
      hi_ = glm::max(hi_, glm::max(a, glm::max(b, c)));
    }
    if (triangles_.empty()) return;
    const glm::dvec3 extent = glm::max(hi_ - lo_, glm::dvec3{1e-9});
    const double volume = extent.x * extent.y * extent.z;
    const double cell = std::cbrt(volume * 2.0 / static_cast<double>(triangles_.size()));
    for (int k = 0; k < 3; ++k)
      cells_[static_cast<std::size_t>(k)] =
          std::clamp(static_cast<int>(std::ceil(extent[k] / std::fmax(cell, 1e-12))), 1, 256);
    cell_size_ = extent / glm::dvec3{cells_[0], cells_[1], cells_[2]};
    start_.assign(static_cast<std::size_t>(cells_[0]) * cells_[1] * cells_[2] + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {  // count, then fill
      std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
      if (pass == 1) items_.resize(start_.back());
      for (std::uint32_t f = 0; f < triangles_.size(); ++f) {
        const Face& face = triangles_[f];
        const auto [lo, hi] =
            range(glm::min(face.a, glm::min(face.b, face.c)), glm::max(face.a, glm::max(face.b, face.c)));
        for (int z = lo[2]; z <= hi[2]; ++z)
          for (int y = lo[1]; y <= hi[1]; ++y)
            for (int x = lo[0]; x <= hi[0]; ++x) {
              const std::size_t at = index(x, y, z);
              if (pass == 0)
                ++start_[at + 1];
              else
                items_[fill[at]++] = f;
            }
      }
      if (pass == 0)
        for (std::size_t i = 1; i < start_.size(); ++i)
          start_[i] += start_[i - 1];
    }
  }

  /// The first triangle the segment a -> b passes through from its front
  /// (piece and path fields left for the caller).
  [[nodiscard]] PathCrossing crossing(const glm::dvec3& a, const glm::dvec3& b) const noexcept {
    PathCrossing out;
    if (triangles_.empty() || !is_finite(a) || !is_finite(b)) return out;
    double best = std::numeric_limits<double>::infinity();
    near(glm::min(a, b), glm::max(a, b), [&](const Face& f) {
      const double t = crosses(f, a, b);
      if (t < best) {
        best = t;
        out.triangle = f.id;
        out.t = t;
        out.piece = 0;
      }
    });
    out.from = a;
    out.to = b;
    return out;
  }

  /// The first piece of a proxy's path that passes through the surface.
  [[nodiscard]] PathCrossing check(const ProxyPath& path) const noexcept {
    for (int i = 0; i + 1 < path.count; ++i) {
      PathCrossing c = crossing(path.points[static_cast<std::size_t>(i)], path.points[static_cast<std::size_t>(i + 1)]);
      if (c.found()) {
        c.piece = i;
        return c;
      }
    }
    return PathCrossing{};
  }

  /// The distance from p to the nearest triangle within `within` [m]
  /// (infinity when none is): the oracle for a ball-shaped tool, whose
  /// centre must stay its radius away from the mesh. Faces are one-sided
  /// (as for the proxy): a point behind a face's plane, over its inside,
  /// is not near that face (its edges and corners still count).
  [[nodiscard]] double distance(const glm::dvec3& p, double within) const noexcept {
    double best = std::numeric_limits<double>::infinity();
    if (triangles_.empty() || !is_finite(p)) return best;
    near(p - glm::dvec3{within}, p + glm::dvec3{within},
         [&](const Face& f) { best = std::fmin(best, one_sided(f, p)); });
    return best <= within ? best : std::numeric_limits<double>::infinity();
  }

  /// For a ball of radius r whose centre moves from a to b: the smallest
  /// distance [m], over points every r / 8 along the move, to a triangle
  /// whose reach (r) the ball entered from outside and from the front, or
  /// infinity when it entered none. Triangles are one-sided, as the ball's
  /// sweep is (ball_sweep.hpp): a ball that starts within r of a triangle,
  /// or first comes within r of it behind its plane or crossing it (from
  /// inside the solid, or behind an open or overlapping part), is not held
  /// to it.
  [[nodiscard]] double entered(const glm::dvec3& a, const glm::dvec3& b, double r) const noexcept {
    double best = std::numeric_limits<double>::infinity();
    if (triangles_.empty() || !is_finite(a) || !is_finite(b)) return best;
    const double clear = r * (1.0 - 1e-6);
    const int samples = 1 + static_cast<int>(glm::length(b - a) / (r / 8));
    near(glm::min(a, b) - glm::dvec3{r}, glm::max(a, b) + glm::dvec3{r}, [&](const Face& f) {
      if (!(two_sided(f, a) >= clear)) return;
      for (int w = 1; w <= samples; ++w) {
        const glm::dvec3 x = a + (static_cast<double>(w) / samples) * (b - a);
        const double d = two_sided(f, x);
        if (!(d < clear)) continue;
        // from the front: the centre in front of the plane on both sides of
        // the entry (the last sample outside and the first inside)
        const glm::dvec3 before = a + (static_cast<double>(w - 1) / samples) * (b - a);
        if (glm::dot(x - f.a, f.n) >= 0.0 && glm::dot(before - f.a, f.n) >= 0.0) best = std::fmin(best, d);
        return;
      }
    });
    return best;
  }

  [[nodiscard]] std::size_t triangle_count() const noexcept { return triangles_.size(); }

 private:
  struct Face {
    glm::dvec3 a, b, c, n;
    double size;
    std::uint32_t id;
  };

  /// The distance from p to the face [m], one-sided: infinity behind its
  /// plane over its inside (its edges and corners count from any side).
  [[nodiscard]] static double two_sided(const Face& f, const glm::dvec3& p) noexcept {
    double b1 = 0.0, b2 = 0.0;
    return glm::length(detail::closest_on_triangle(p, f.a, f.b - f.a, f.c - f.a, b1, b2) - p);
  }

  [[nodiscard]] static double one_sided(const Face& f, const glm::dvec3& p) noexcept {
    double b1 = 0.0, b2 = 0.0;
    const glm::dvec3 q = detail::closest_on_triangle(p, f.a, f.b - f.a, f.c - f.a, b1, b2);
    const bool inside = b1 > 0.0 && b2 > 0.0 && b1 + b2 < 1.0;
    if (inside && glm::dot(p - f.a, f.n) < 0.0) return std::numeric_limits<double>::infinity();
    return glm::length(q - p);
  }

  /// The parameter in [0, 1] where a -> b crosses the face from its front
  /// (see the file comment), or infinity.
  [[nodiscard]] double crosses(const Face& f, const glm::dvec3& a, const glm::dvec3& b) const noexcept {
    const double margin = config_.margin * f.size;
    const double ha = glm::dot(a - f.a, f.n), hb = glm::dot(b - f.a, f.n);
    if (!(ha > margin) || !(hb < -margin)) return std::numeric_limits<double>::infinity();
    const double t = ha / (ha - hb);
    const glm::dvec3 p = a + t * (b - a);
    // barycentric weights of p from signed areas
    const glm::dvec3 e0 = f.b - f.a, e1 = f.c - f.a, q = p - f.a;
    const double d00 = glm::dot(e0, e0), d01 = glm::dot(e0, e1), d11 = glm::dot(e1, e1);
    const double d20 = glm::dot(q, e0), d21 = glm::dot(q, e1);
    const double det = d00 * d11 - d01 * d01;
    const double w1 = (d11 * d20 - d01 * d21) / det, w2 = (d00 * d21 - d01 * d20) / det;
    const double w0 = 1.0 - w1 - w2;
    const double in = config_.interior;
    return w0 > in && w1 > in && w2 > in ? t : std::numeric_limits<double>::infinity();
  }

  /// Calls visit(face) for every triangle in a cell the box [lo, hi] meets
  /// (a triangle in several cells more than once).
  template <class Visit>
  void near(const glm::dvec3& lo, const glm::dvec3& hi, Visit&& visit) const noexcept {
    const auto [from, to] = range(lo, hi);
    for (int z = from[2]; z <= to[2]; ++z)
      for (int y = from[1]; y <= to[1]; ++y)
        for (int x = from[0]; x <= to[0]; ++x) {
          const std::size_t at = index(x, y, z);
          for (std::uint32_t i = start_[at]; i < start_[at + 1]; ++i)
            visit(triangles_[items_[i]]);
        }
  }

  [[nodiscard]] std::pair<std::array<int, 3>, std::array<int, 3>> range(const glm::dvec3& lo,
                                                                        const glm::dvec3& hi) const noexcept {
    std::array<int, 3> a{}, b{};
    for (int k = 0; k < 3; ++k) {
      const auto axis = static_cast<std::size_t>(k);
      const double slack = 1e-9 * (std::fabs(lo[k]) + std::fabs(hi[k])) + 1e-12;
      a[axis] = std::clamp(static_cast<int>(std::floor((lo[k] - slack - lo_[k]) / cell_size_[k])), 0, cells_[axis] - 1);
      b[axis] = std::clamp(static_cast<int>(std::floor((hi[k] + slack - lo_[k]) / cell_size_[k])), 0, cells_[axis] - 1);
    }
    return {a, b};
  }

  [[nodiscard]] std::size_t index(int x, int y, int z) const noexcept {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(cells_[1]) + static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(cells_[0]) +
           static_cast<std::size_t>(x);
  }

  MeshCheckerConfig config_;
  std::vector<Face> triangles_;
  glm::dvec3 lo_{std::numeric_limits<double>::max()}, hi_{-std::numeric_limits<double>::max()};
  std::array<int, 3> cells_{1, 1, 1};
  glm::dvec3 cell_size_{1.0};
  std::vector<std::uint32_t> start_;  ///< cell c's triangles: items_[start_[c] .. start_[c + 1])
  std::vector<std::uint32_t> items_;
};

/// A proxy that checks every tick's path against a MeshChecker of the same
/// mesh (in the shape's frame): a Constraint like the proxy, for tests and
/// debugging scenes. Counts the ticks whose path crossed the surface and
/// keeps the first crossing.
template <Shape S>
class CheckedProxy {
 public:
  CheckedProxy(ProxyConstraint<S> proxy, const TriangleMesh& mesh, const MeshCheckerConfig& config = {})
      : proxy_(std::move(proxy)), checker_(mesh, config) {}

  [[nodiscard]] Contact contact(const Probe& probe) noexcept {
    const Contact c = proxy_.contact(probe);
    ++ticks_;
    const PathCrossing crossing = checker_.check(proxy_.last_path());
    if (crossing.found()) {
      if (violations_ == 0) {
        first_ = crossing;
        first_tick_ = ticks_ - 1;
      }
      ++violations_;
    }
    return c;
  }
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept { return contact(probe).force; }
  void reset() noexcept { proxy_.reset(); }

  [[nodiscard]] const ProxyConstraint<S>& proxy() const noexcept { return proxy_; }
  [[nodiscard]] const MeshChecker& checker() const noexcept { return checker_; }
  /// Ticks checked, ticks whose path crossed the surface, the first crossing and its tick (0-based).
  [[nodiscard]] std::uint64_t ticks() const noexcept { return ticks_; }
  [[nodiscard]] std::uint64_t violations() const noexcept { return violations_; }
  [[nodiscard]] const PathCrossing& first_violation() const noexcept { return first_; }
  [[nodiscard]] std::uint64_t first_violation_tick() const noexcept { return first_tick_; }

 private:
  ProxyConstraint<S> proxy_;
  MeshChecker checker_;
  std::uint64_t ticks_{0}, violations_{0}, first_tick_{0};
  PathCrossing first_{};
};

}  // namespace hapticfield
