#pragma once
/// @file shape.hpp
/// The Shape concept: a surface the proxy (surface/proxy.hpp) can stand on,
/// answered by two queries, both on the servo path (const, noexcept, no
/// allocation, a bounded number of steps):
///
///   closest(p, max_distance)  the surface point nearest to p, if one is
///                             within max_distance [m];
///   first_hit(from, to)       the first surface point met going from `from`
///                             to `to` (a swept, continuous test), coming
///                             from the side the surface faces.
///
/// Surfaces are one-sided: a segment that reaches a surface from behind (from
/// inside the solid, or through the back of an open mesh) passes it. Each
/// answer is a Hit: where, the normals, the texture coordinates and their
/// tangent frame, which primitive and its material, and the primitive's
/// size, which sets the scale of the tolerances used on it.
///
/// Also the analytic shapes PlaneShape and SphereShape (closed forms: tests
/// and baselines for the mesh and height-field shapes).

#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// What a shape query found. found() is false when nothing was found (no
/// surface within the distance, or a free segment). complete is false when
/// a query ran out of its step budget: first_hit then reports a blocked
/// segment (t = 0, nothing found) so a caller never moves through what it
/// did not check; closest reports the best point it saw.
struct Hit {
  glm::dvec3 point{0.0};  ///< the surface point [m]
  glm::dvec3 normal{
      0.0};  ///< unit normal toward the user, shaded (interpolated vertex normals) where the shape has them
  glm::dvec3 face_normal{0.0};  ///< unit geometric normal of the primitive toward the user
  glm::dvec3 tangent{0.0};      ///< unit direction of increasing u, in the plane normal to `normal`; zero: no uv
  glm::dvec3 bitangent{0.0};    ///< unit direction of increasing v, in the plane normal to `normal`; zero: no uv
  glm::dvec2 uv{0.0};           ///< texture coordinates of the point [-] (u right, v up)
  double distance{std::numeric_limits<double>::infinity()};  ///< closest: |point - p|; first_hit: |point - from| [m]
  double t{1.0};                          ///< first_hit: fraction of the segment before the hit [0, 1]
  double size{0.0};                       ///< size of the primitive (longest edge or cell side) [m]
  std::uint32_t primitive{no_primitive};  ///< triangle / grid cell id; no_primitive: nothing found
  std::uint32_t material{0};              ///< material index of the primitive
  bool complete{true};                    ///< false: the query ran out of its step budget
  [[nodiscard]] bool found() const noexcept { return primitive != no_primitive; }
};

/// A surface for the proxy: closest() and first_hit() as described in the
/// file comment, both const noexcept.
template <class S>
concept Shape = requires(const S& shape, const glm::dvec3& p, double max_distance) {
  { shape.closest(p, max_distance) }
  noexcept->std::same_as<Hit>;
  { shape.first_hit(p, p) }
  noexcept->std::same_as<Hit>;
};

/// A shape whose queries change nothing but their answers (no counter, log
/// or cache written) and whose copy is cheap and never allocates. A shape
/// opts in with `static constexpr bool pure_queries = true;` (the library's
/// static shapes do): a proxy on it may then run a tick on a scratch copy
/// of itself to look ahead (ProxyConstraint::anticipate).
template <class S>
concept PureQueries = Shape<S> && requires {
  requires S::pure_queries;
} && std::is_nothrow_copy_constructible_v<S>;

/// What a shape's ball sweeps keep for their caller between queries
/// (S::SweepCache: MeshShape's region of its tree), or NoSweepCache.
struct NoSweepCache {};
template <class S>
struct SweepCacheFor {
  using Cache = NoSweepCache;
};
template <class S>
requires requires {
  typename S::SweepCache;
}
struct SweepCacheFor<S> {
  using Cache = typename S::SweepCache;
};
template <class S>
using SweepCacheOf = typename SweepCacheFor<S>::Cache;

/// Counts of one query's work (nodes of a tree, cells of a grid): the bound
/// the tests assert and the benches report.
struct QueryStats {
  std::uint32_t nodes{0};       ///< tree nodes (or grid cells) visited
  std::uint32_t primitives{0};  ///< primitives tested
};

namespace detail {

/// a < b ? a : b, inlined (std::fmin is a library call that also handles
/// NaN; the traversals that use these never see one). On SSE2 it is the
/// minsd instruction, whose answer is the same to the bit: written as a
/// comparison, the compiler turns some of these into a branch on the data
/// (a clamp at 0 that a later step tests again), which no predictor
/// foresees (a fifth of a ball's mispredicted branches on a mesh).
[[nodiscard]] constexpr double smaller(double a, double b) noexcept {
#if defined(__SSE2__)
  if (!std::is_constant_evaluated()) return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(b), _mm_set_sd(a)));
#endif
  return b < a ? b : a;
}
/// a > b ? a : b, inlined (see smaller(); maxsd on SSE2).
[[nodiscard]] constexpr double larger(double a, double b) noexcept {
#if defined(__SSE2__)
  if (!std::is_constant_evaluated()) return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(b), _mm_set_sd(a)));
#endif
  return b > a ? b : a;
}

/// The tangent frame of a surface point from dP/du and dP/dv [m per uv
/// unit], made orthonormal against the unit normal n: t along dP/du in the
/// tangent plane, b = +-(n x t) with the sign of dP/dv (mirrored uvs keep
/// their v direction). Zero vectors when dP/du has no tangential part.
inline void tangent_frame(const glm::dvec3& n, const glm::dvec3& dpdu, const glm::dvec3& dpdv, glm::dvec3& tangent,
                          glm::dvec3& bitangent) noexcept {
  const glm::dvec3 t = dpdu - glm::dot(dpdu, n) * n;
  const double length = glm::length(t);
  if (!(length > 0.0) || !std::isfinite(length)) {
    tangent = bitangent = glm::dvec3{0.0};
    return;
  }
  tangent = t / length;
  bitangent = glm::cross(n, tangent);
  if (glm::dot(bitangent, dpdv) < 0.0) bitangent = -bitangent;
}

inline void check_unit(const char* who, const glm::dvec3& n) {
  const double length = glm::length(n);
  if (!std::isfinite(length) || std::fabs(length - 1.0) > 1e-9)
    throw std::invalid_argument(std::string(who) + ": normal must be a unit vector");
}

}  // namespace detail

struct PlaneShapeConfig {
  glm::dvec3 point{0.0};             ///< a point on the plane, uv (0, 0) [m]
  glm::dvec3 normal{0.0, 0.0, 1.0};  ///< unit normal, out of the solid toward the user
  double size{0.01};                 ///< the length its tolerances scale with [m]
};

/// The solid half-space behind a plane. uv are metres along the plane's
/// surface frame (core/surface_frame.hpp: x and y for the normal +z).
class PlaneShape {
 public:
  static constexpr bool pure_queries = true;  ///< (PureQueries)
  /// @throws std::invalid_argument for a non-finite point, a normal that is
  ///         not unit length or a size that is not finite and > 0.
  explicit PlaneShape(const PlaneShapeConfig& config) : config_(config), frame_(surface_frame(config.normal)) {
    if (!is_finite(config.point)) throw std::invalid_argument("PlaneShape: point must be finite [m]");
    detail::check_unit("PlaneShape", config.normal);
    if (!std::isfinite(config.size) || config.size <= 0.0)
      throw std::invalid_argument("PlaneShape: size must be finite and > 0 [m]");
  }

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    const double height = glm::dot(p - config_.point, config_.normal);  // [m]
    if (!(std::fabs(height) <= max_distance)) return Hit{};
    return hit_at(p - height * config_.normal, std::fabs(height), 1.0);
  }

  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    const double h0 = glm::dot(from - config_.point, config_.normal);
    const double h1 = glm::dot(to - config_.point, config_.normal);
    if (!(h0 >= 0.0) || !(h1 < 0.0)) return Hit{};  // must cross from the front to behind
    const double t = h0 / (h0 - h1);
    const glm::dvec3 point = from + t * (to - from);
    return hit_at(point, t * glm::length(to - from), t);
  }

  /// A ball of `radius` [m] whose centre moves from `from` to `to`: the
  /// plane lifted by the radius, met from its front (Hit::point the touched
  /// point of the plane).
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius) const noexcept {
    const double h0 = glm::dot(from - config_.point, config_.normal) - radius;
    const double h1 = glm::dot(to - config_.point, config_.normal) - radius;
    if (!(h0 >= -radius) || !(h1 < h0) || !(h1 < 0.0)) return Hit{};  // must move into the lifted plane from its front
    const double t = h0 > 0.0 ? h0 / (h0 - h1) : 0.0;
    const glm::dvec3 centre = from + t * (to - from);
    return hit_at(centre - (t > 0.0 ? radius : h0 + radius) * config_.normal, t * glm::length(to - from), t);
  }

  [[nodiscard]] const PlaneShapeConfig& config() const noexcept { return config_; }

 private:
  [[nodiscard]] Hit hit_at(const glm::dvec3& point, double distance, double t) const noexcept {
    Hit h;
    h.point = point;
    h.normal = h.face_normal = config_.normal;
    h.tangent = frame_.tangent1;
    h.bitangent = frame_.tangent2;
    const glm::dvec3 d = point - config_.point;
    h.uv = glm::dvec2{glm::dot(d, frame_.tangent1), glm::dot(d, frame_.tangent2)};
    h.distance = distance;
    h.t = t;
    h.size = config_.size;
    h.primitive = 0;
    return h;
  }

  PlaneShapeConfig config_;
  SurfaceFrame frame_;
};

struct SphereShapeConfig {
  glm::dvec3 centre{0.0};  ///< [m]
  double radius{0.02};     ///< [m]
};

/// A solid ball. uv: u = longitude / 2 pi + 1/2 (about +z, 0.5 on +x, the seam on -x), v =
/// latitude / pi + 1/2 (0 at the -z pole, 1 at +z); the tangent points east,
/// the bitangent north (zero at the poles). Its size is the radius.
class SphereShape {
 public:
  static constexpr bool pure_queries = true;  ///< (PureQueries)
  /// @throws std::invalid_argument for a non-finite centre or a radius that
  ///         is not finite and > 0.
  explicit SphereShape(const SphereShapeConfig& config) : config_(config) {
    if (!is_finite(config.centre)) throw std::invalid_argument("SphereShape: centre must be finite [m]");
    if (!std::isfinite(config.radius) || config.radius <= 0.0)
      throw std::invalid_argument("SphereShape: radius must be finite and > 0 [m]");
  }

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    const glm::dvec3 r = p - config_.centre;
    const double length = glm::length(r);
    const double distance = std::fabs(length - config_.radius);
    if (!(distance <= max_distance)) return Hit{};
    const glm::dvec3 n = length > 0.0 ? r / length : glm::dvec3{0.0, 0.0, 1.0};
    return hit_at(n, distance, 1.0);
  }

  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    // |from + t d - c|^2 = r^2, entering root: t = (-b - sqrt(b^2 - a c0)) / a
    const glm::dvec3 d = to - from;
    const glm::dvec3 f = from - config_.centre;
    const double a = glm::dot(d, d);
    const double b = glm::dot(f, d);
    const double c0 = glm::dot(f, f) - config_.radius * config_.radius;
    if (!(a > 0.0) || !(c0 >= 0.0) || !(b < 0.0)) return Hit{};  // no motion, starts inside, or moves away
    const double disc = b * b - a * c0;
    if (!(disc >= 0.0)) return Hit{};
    const double t = c0 / (-b + std::sqrt(disc));  // = (-b - sqrt(disc)) / a without cancellation
    if (!(t <= 1.0)) return Hit{};
    const glm::dvec3 r = f + t * d;
    const double length = glm::length(r);
    return hit_at(length > 0.0 ? r / length : glm::dvec3{0.0, 0.0, 1.0}, t * std::sqrt(a), t);
  }

  /// A ball of `radius` [m] whose centre moves from `from` to `to`: the
  /// sphere grown by the radius (Hit::point the touched point of the
  /// sphere); a ball already overlapping it and moving in touches at t = 0.
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius) const noexcept {
    const glm::dvec3 d = to - from;
    const glm::dvec3 f = from - config_.centre;
    const double grown = config_.radius + radius;
    const double a = glm::dot(d, d);
    const double b = glm::dot(f, d);
    const double c0 = glm::dot(f, f) - grown * grown;
    if (!(a > 0.0) || !(b < 0.0)) return Hit{};  // no motion, or moving away
    double t = 0.0;
    if (c0 > 0.0) {
      const double disc = b * b - a * c0;
      if (!(disc >= 0.0)) return Hit{};
      t = c0 / (-b + std::sqrt(disc));
      if (!(t <= 1.0)) return Hit{};
    } else if (!(glm::length(f) >= config_.radius)) {
      return Hit{};  // the centre inside the ball itself: from inside the solid
    }
    const glm::dvec3 r = f + t * d;
    const double length = glm::length(r);
    return hit_at(length > 0.0 ? r / length : glm::dvec3{0.0, 0.0, 1.0}, t * std::sqrt(a), t);
  }

  [[nodiscard]] const SphereShapeConfig& config() const noexcept { return config_; }

 private:
  [[nodiscard]] Hit hit_at(const glm::dvec3& n, double distance, double t) const noexcept {
    Hit h;
    h.point = config_.centre + config_.radius * n;
    h.normal = h.face_normal = n;
    const double horizontal = std::hypot(n.x, n.y);
    h.uv = glm::dvec2{std::atan2(n.y, n.x) / (2.0 * std::numbers::pi) + 0.5,
                      std::asin(std::fmax(-1.0, std::fmin(1.0, n.z))) / std::numbers::pi + 0.5};
    if (horizontal > 0.0) {
      h.tangent = glm::dvec3{-n.y / horizontal, n.x / horizontal, 0.0};
      h.bitangent = glm::cross(n, h.tangent);
    }
    h.distance = distance;
    h.t = t;
    h.size = config_.radius;
    h.primitive = 0;
    return h;
  }

  SphereShapeConfig config_;
};

static_assert(Shape<PlaneShape> && Shape<SphereShape>);

}  // namespace hapticfield
