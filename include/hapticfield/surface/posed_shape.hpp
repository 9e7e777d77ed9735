#pragma once
/// @file posed_shape.hpp
/// Placing a shape: a rigid pose (a rotation and a translation [m]) and
/// Posed<S>, any Shape moved by one.
///
/// A Pose maps the shape's own frame to the world (device) frame:
///   world = rotation * local + translation.
/// Posed<S> answers every query in the world frame: the query's points go
/// into the shape's frame, the inner shape answers, and every point and
/// vector of the Hit (point, normal, face_normal, tangent, bitangent) comes
/// back rotated; distances, t, uv, size, primitive and material are
/// unchanged (a rigid motion keeps lengths). The proxy's tolerances stay
/// relative to the primitive's size, so a posed shape feels like the shape.
///
/// Every query of the inner shape is forwarded in the same way, by
/// PosedQueries (shared with Moving<S>): the plain forms, the QueryStats*
/// forms, sweep_sphere's primitive hint, on_primitive() and the traits,
/// each only where the inner shape has it (so the proxy sees the same
/// optional queries through the wrapper). Another query is one more member
/// of PosedQueries written like on_primitive(): points through local(), the
/// answer through world().

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/surface/shape.hpp"

namespace hapticfield {

/// A rigid transform: world = rotation * local + translation. The rotation's
/// columns are the shape's x, y and z axes in the world frame.
struct Pose {
  glm::dmat3 rotation{1.0};     ///< proper orthonormal (det +1)
  glm::dvec3 translation{0.0};  ///< where the shape's origin goes [m]

  /// How far a rotation may be from orthonormal (each entry of R^T R - I,
  /// and |det R - 1|) and a quaternion's norm from 1 before it is refused.
  static constexpr double tolerance = 1e-6;

  /// A pose from a unit quaternion (w, x, y, z), scalar first. A quaternion
  /// within `tolerance` of unit length is normalised.
  /// @throws std::invalid_argument for a non-finite or non-unit quaternion or
  ///         a non-finite translation.
  [[nodiscard]] static Pose from_quaternion(double w, double x, double y, double z,
                                            const glm::dvec3& translation = glm::dvec3{0.0}) {
    const double norm = std::sqrt(w * w + x * x + y * y + z * z);
    if (!std::isfinite(norm) || !(std::fabs(norm - 1.0) <= tolerance))
      throw std::invalid_argument("Pose: the quaternion (w, x, y, z) must be finite and of unit length, its norm is " +
                                  std::to_string(norm));
    w /= norm, x /= norm, y /= norm, z /= norm;
    Pose p;
    // columns of the rotation matrix of q (glm::dmat3 is column-major: p.rotation[c][r])
    p.rotation[0] = {1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)};
    p.rotation[1] = {2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)};
    p.rotation[2] = {2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)};
    p.translation = translation;
    p.validate();
    return p;
  }

  /// A pose turning by `radians` about `axis` (any length > 0, right-handed),
  /// then moving by translation [m].
  /// @throws std::invalid_argument for a zero or non-finite axis or angle.
  [[nodiscard]] static Pose from_axis_angle(const glm::dvec3& axis, double radians,
                                            const glm::dvec3& translation = glm::dvec3{0.0}) {
    const double length = glm::length(axis);
    if (!(length > 0.0) || !std::isfinite(length) || !std::isfinite(radians))
      throw std::invalid_argument("Pose: the rotation axis must be finite and not zero, the angle finite");
    const glm::dvec3 a = axis / length;
    const double s = std::sin(0.5 * radians);
    return from_quaternion(std::cos(0.5 * radians), s * a.x, s * a.y, s * a.z, translation);
  }

  /// A pose from a rotation matrix given row by row (rows[r][c]) within
  /// `tolerance` of a proper rotation; it is made orthonormal (Gram-Schmidt on
  /// its columns) so that the transform is rigid to rounding.
  /// @throws std::invalid_argument as validate().
  [[nodiscard]] static Pose from_rows(const std::array<std::array<double, 3>, 3>& rows,
                                      const glm::dvec3& translation = glm::dvec3{0.0}) {
    Pose p;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        p.rotation[c][r] = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
    p.translation = translation;
    p.validate();
    glm::dvec3 x = glm::normalize(p.rotation[0]);
    glm::dvec3 y = p.rotation[1] - glm::dot(p.rotation[1], x) * x;
    y = glm::normalize(y);
    p.rotation = glm::dmat3{x, y, glm::cross(x, y)};
    return p;
  }

  /// @throws std::invalid_argument for a non-finite translation, or a
  ///         rotation that is not finite, not orthonormal or a reflection.
  void validate() const {
    if (!is_finite(translation)) throw std::invalid_argument("Pose: the translation must be finite [m]");
    for (int c = 0; c < 3; ++c)
      if (!is_finite(rotation[c])) throw std::invalid_argument("Pose: the rotation must be finite");
    double worst = 0.0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        worst = std::fmax(worst, std::fabs(glm::dot(rotation[i], rotation[j]) - (i == j ? 1.0 : 0.0)));
    if (!(worst <= tolerance))
      throw std::invalid_argument("Pose: the rotation must be orthonormal (R^T R = I within 1e-6; off by " +
                                  std::to_string(worst) + ")");
    const double det = glm::dot(rotation[0], glm::cross(rotation[1], rotation[2]));
    if (!(std::fabs(det - 1.0) <= tolerance))
      throw std::invalid_argument("Pose: the rotation must be proper (det +1), not a reflection (det " +
                                  std::to_string(det) + ")");
  }

  /// A point of the shape's frame in the world frame [m].
  [[nodiscard]] glm::dvec3 point_to_world(const glm::dvec3& p) const noexcept { return rotation * p + translation; }
  /// A point of the world frame in the shape's frame [m].
  [[nodiscard]] glm::dvec3 point_to_local(const glm::dvec3& p) const noexcept {
    return (p - translation) * rotation;  // R^T (p - t): a row vector times R
  }
  /// A direction of the shape's frame in the world frame.
  [[nodiscard]] glm::dvec3 vector_to_world(const glm::dvec3& v) const noexcept { return rotation * v; }
  /// A direction of the world frame in the shape's frame.
  [[nodiscard]] glm::dvec3 vector_to_local(const glm::dvec3& v) const noexcept { return v * rotation; }
  /// A hit of a shape placed by this pose, in the world frame (nothing
  /// found: as it is, so a blocked segment stays blocked).
  [[nodiscard]] Hit hit_to_world(Hit h) const noexcept {
    if (!h.found()) return h;
    h.point = point_to_world(h.point);
    h.normal = vector_to_world(h.normal);
    h.face_normal = vector_to_world(h.face_normal);
    h.tangent = vector_to_world(h.tangent);
    h.bitangent = vector_to_world(h.bitangent);
    return h;
  }
  /// True for the identity (no rotation, no translation).
  [[nodiscard]] bool is_identity() const noexcept {
    return rotation == glm::dmat3{1.0} && translation == glm::dvec3{0.0};
  }
};

/// Every query of an inner shape S, answered in the world frame of a
/// placed shape (CRTP: Placed is Posed<S> or Moving<S>, whose shape() is the
/// inner shape and pose() the pose it is placed by now). The query's points
/// go into the shape's frame, the inner shape answers, and the Hit comes
/// back through Pose::hit_to_world. Each query exists only where the inner
/// shape has it, so the proxy sees the same optional queries through the
/// wrapper: the QueryStats* forms, sweep_sphere (with the primitive hint,
/// the cache and the slide plane MeshShape takes), on_primitive(), flat_primitives and
/// closest_matches_sweep.
template <class Placed, Shape S>
class PosedQueries {
 public:
  /// The proxy may move over one primitive without a sweep when the inner
  /// shape's primitives are flat: a rigid motion keeps them flat.
  static constexpr bool flat_primitives = requires { requires S::flat_primitives; };
  /// closest() and the sweeps see the same surface (the inner shape's say).
  static constexpr bool closest_matches_sweep = !requires { requires !S::closest_matches_sweep; };
  /// The inner shape's (its sweeps keep it in their own frame).
  using SweepCache = SweepCacheOf<S>;

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    return world(inner().closest(local(p), max_distance));
  }
  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance, QueryStats* stats) const noexcept requires
      requires(const S& s) {
    s.closest(p, max_distance, stats);
  }
  { return world(inner().closest(local(p), max_distance, stats)); }
  /// With a ball's cache of the inner shape's sweeps (its own frame).
  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance, QueryStats* stats,
                            const SweepCache* cache) const noexcept requires requires(const S& s) {
    s.closest(p, max_distance, stats, cache);
  }
  { return world(inner().closest(local(p), max_distance, stats, cache)); }

  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    return world(inner().first_hit(local(from), local(to)));
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to, QueryStats* stats) const noexcept requires
      requires(const S& s) {
    s.first_hit(from, to, stats);
  }
  { return world(inner().first_hit(local(from), local(to), stats)); }

  /// A ball of `radius` [m] swept from -> to, where the inner shape sweeps one.
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius) const noexcept requires
      requires(const S& s) {
    s.sweep_sphere(from, to, radius);
  }
  { return world(inner().sweep_sphere(local(from), local(to), radius)); }
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius,
                                 QueryStats* stats) const noexcept requires requires(const S& s) {
    s.sweep_sphere(from, to, radius, stats);
  }
  { return world(inner().sweep_sphere(local(from), local(to), radius, stats)); }
  /// With the primitive the ball likely meets first (a primitive's index is
  /// the same in every frame).
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius, QueryStats* stats,
                                 std::uint32_t hint) const noexcept requires requires(const S& s) {
    s.sweep_sphere(from, to, radius, stats, hint);
  }
  { return world(inner().sweep_sphere(local(from), local(to), radius, stats, hint)); }
  /// With the caller's cache of the inner shape's sweeps (in its own frame,
  /// so a new pose leaves it valid).
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius, QueryStats* stats,
                                 std::uint32_t hint, SweepCache* cache) const noexcept requires requires(const S& s) {
    s.sweep_sphere(from, to, radius, stats, hint, cache);
  }
  { return world(inner().sweep_sphere(local(from), local(to), radius, stats, hint, cache)); }
  /// And the normal of a plane the move runs along, where the inner
  /// shape takes one (MeshShape::sweep_sphere's `slide`), turned into its
  /// frame.
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius, QueryStats* stats,
                                 std::uint32_t hint, SweepCache* cache, const glm::dvec3* slide) const noexcept requires
      requires(const S& s) {
    s.sweep_sphere(from, to, radius, stats, hint, cache, slide);
  }
  {
    const glm::dvec3 along = slide ? static_cast<const Placed&>(*this).pose().vector_to_local(*slide) : glm::dvec3{0.0};
    return world(inner().sweep_sphere(local(from), local(to), radius, stats, hint, cache, slide ? &along : nullptr));
  }

  /// The point of one primitive nearest to p, where the inner shape answers
  /// for one primitive.
  [[nodiscard]] Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p,
                                 double max_distance) const noexcept requires requires(const S& s) {
    s.on_primitive(primitive, p, max_distance);
  }
  { return world(inner().on_primitive(primitive, local(p), max_distance)); }

 private:
  [[nodiscard]] const S& inner() const noexcept { return static_cast<const Placed&>(*this).shape(); }
  /// A query point in the shape's frame.
  [[nodiscard]] glm::dvec3 local(const glm::dvec3& p) const noexcept {
    return static_cast<const Placed&>(*this).pose().point_to_local(p);
  }
  /// A hit of the inner shape in the world frame.
  [[nodiscard]] Hit world(const Hit& h) const noexcept {
    return static_cast<const Placed&>(*this).pose().hit_to_world(h);
  }
};

/// Shape S placed in the world by a Pose. Queries (PosedQueries) are const
/// noexcept and allocate nothing (a few multiply-adds around the inner
/// query).
template <Shape S>
class Posed : public PosedQueries<Posed<S>, S> {
 public:
  /// As pure as the shape it places (PureQueries).
  static constexpr bool pure_queries = PureQueries<S>;
  /// @throws std::invalid_argument for an invalid pose (Pose::validate()).
  Posed(S shape, const Pose& pose) : shape_(std::move(shape)), pose_(pose) { pose_.validate(); }

  [[nodiscard]] const S& shape() const noexcept { return shape_; }
  [[nodiscard]] const Pose& pose() const noexcept { return pose_; }

 private:
  S shape_;
  Pose pose_;
};

static_assert(Shape<Posed<PlaneShape>>);
static_assert(Shape<Posed<SphereShape>>);

}  // namespace hapticfield
