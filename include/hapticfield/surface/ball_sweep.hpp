#pragma once
/// @file ball_sweep.hpp
/// A ball swept along a segment against one triangle: the earliest contact
/// of its centre with the triangle's Minkowski sum with the ball (the face
/// offset by the radius on its front, the edges' cylinders and the corners'
/// balls; Ericson, Real-Time Collision Detection, 2005, 5.5.6). The one
/// primitive test behind MeshBvh::sweep_sphere and
/// HeightFieldShape::sweep_sphere. GLM only, allocation-free.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::detail {

/// The entering time t in [0, 1] of a point f + t d into the ball of radius
/// r about the origin; t = 0 when it starts inside and moves inward.
[[nodiscard]] inline bool ball_entry(const glm::dvec3& f, const glm::dvec3& d, double r, double& t) noexcept {
  const double c = glm::dot(f, f) - r * r;
  const double b = glm::dot(f, d);
  if (!(b < 0.0)) return false;  // not approaching
  if (c <= 0.0) {
    t = 0.0;
    return true;
  }
  const double a = glm::dot(d, d);
  const double disc = b * b - a * c;
  if (!(disc >= 0.0)) return false;
  t = c / (-b + std::sqrt(disc));  // the smaller root, without cancellation
  return t <= 1.0;
}

/// The entering time t in [0, 1] of a point f + t d into the cylinder of
/// radius r about the segment s e, s in [0, 1] (s receives where); t = 0
/// when it starts inside and moves inward.
[[nodiscard]] inline bool cylinder_entry(const glm::dvec3& f, const glm::dvec3& d, const glm::dvec3& e, double r,
                                         double& t, double& s) noexcept {
  const double ee = glm::dot(e, e);
  if (!(ee > 0.0)) return false;
  // components normal to the axis
  const glm::dvec3 fp = f - (glm::dot(f, e) / ee) * e;
  const glm::dvec3 dp = d - (glm::dot(d, e) / ee) * e;
  const double a = glm::dot(dp, dp), b = glm::dot(fp, dp), c = glm::dot(fp, fp) - r * r;
  if (!(b < 0.0)) return false;  // not approaching the axis
  if (c <= 0.0) {
    t = 0.0;
  } else {
    const double disc = b * b - a * c;
    if (!(disc >= 0.0)) return false;
    t = c / (-b + std::sqrt(disc));
    if (!(t <= 1.0)) return false;
  }
  s = glm::dot(f + t * d, e) / ee;
  return s >= 0.0 && s <= 1.0;
}

/// The ball of radius r whose centre moves from + t d (t in [0, t_best))
/// against the triangle a, a + e1, a + e2, met from its front only (the side
/// cross(e1, e2) points to): its face, and its edges and corners where the
/// contact normal (from the touched point to the centre) leans to that side.
/// A convex edge or corner always lies in front of one of the faces that
/// share it, so a closed mesh loses no contact, while a ball inside a solid
/// or under an open sheet leaves through it as a point does. A ball that
/// already overlaps a feature and moves toward it meets it at t = 0. True
/// when it touches before t_best, which then receives the time, and contact
/// the touched point of the triangle. `circle_tested`: the caller has found
/// that the ball's cut with the plane may reach the triangle's bounding
/// circle over [0, t_best] (MeshBvh::TriangleBounds), so that first test of
/// the edges and corners is not made again.
[[nodiscard]] inline bool sweep_ball_triangle(const glm::dvec3& a, const glm::dvec3& e1, const glm::dvec3& e2,
                                              const glm::dvec3& from, const glm::dvec3& d, double r, double& t_best,
                                              glm::dvec3& contact, bool circle_tested = false) noexcept {
  const glm::dvec3 cross = glm::cross(e1, e2);
  // the ball stays r or more on one side of the triangle's plane along the
  // whole move (heights are linear in t): it meets nothing of it
  const double area2 = glm::length(cross);  // twice the area [m^2]
  const double lift = r * area2;            // r |cross| [m^3]
  const double g0 = glm::dot(from - a, cross), g1 = glm::dot(from + t_best * d - a, cross);
  if ((g0 >= lift && g1 >= lift) || (g0 <= -lift && g1 <= -lift)) return false;
  if (!(area2 > 0.0)) return false;
  const glm::dvec3 n = cross / area2;
  bool found = false;
  // the face, offset by r on its front
  const double h0 = glm::dot(from - a, n);  // [m] height of the start
  const double dn = glm::dot(d, n);         // [m] per unit t
  if (dn < 0.0 && h0 >= -r) {
    const double t = h0 > r ? (h0 - r) / -dn : 0.0;
    const glm::dvec3 q = from + t * d - (t > 0.0 ? r : h0) * n;  // the touched point on the plane
    // inside the triangle: the three edge functions' signs (relative tolerance)
    const glm::dvec3 w = q - a;
    const double u = glm::dot(glm::cross(w, e2), cross), v = glm::dot(glm::cross(e1, w), cross);
    const double whole = area2 * area2, slack = 1e-12 * whole;
    if (u >= -slack && v >= -slack && u + v <= whole + slack && (t > 0.0 || h0 >= 0.0)) {
      // the first contact: the edges and corners, in the plane, come no
      // sooner (tried only when there is none inside the face, so the
      // answer does not hang on the t_best it was asked with)
      if (!(t < t_best)) return false;
      t_best = t;
      contact = q;
      found = true;
    }
  }
  // the corners' balls and the edges' cylinders: none is met before a
  // contact inside the face (they lie in its plane); nor while the centre is
  // behind the plane (a feature counts from the front only); nor when the
  // ball's cut with the plane, a disk of radius sqrt(r^2 - h^2) about the
  // centre's projection, never reaches the triangle's bounding circle: over
  // [0, t_best] the disk is at most rho across, at the least height in front
  if (found) return true;
  const double h1 = h0 + t_best * dn;  // [m] the height at t_best
  if (h0 <= 0.0 && h1 <= 0.0) return false;
  const double low = h0 > 0.0 && h1 > 0.0 ? (h1 < h0 ? h1 : h0) : 0.0;  // [m] (no NaN here: inline, not fmin)
  if (!(low < r)) return false;
  const std::array<glm::dvec3, 3> corner{a, a + e1, a + e2};
  if (!circle_tested) {
    const double rho = std::sqrt(r * r - low * low);  // [m]
    const glm::dvec3 middle = (corner[0] + corner[1] + corner[2]) / 3.0;
    double reach2 = 0.0;  // the bounding circle's radius, squared [m^2]
    for (const glm::dvec3& c : corner) {
      const double to_corner2 = glm::dot(c - middle, c - middle);
      if (to_corner2 > reach2) reach2 = to_corner2;
    }
    const glm::dvec3 to_middle = middle - from + h0 * n;  // from the centre's projection, in the plane
    const glm::dvec3 slide = d - dn * n;                  // the projected move
    const double slide2 = glm::dot(slide, slide);
    const double along = std::clamp(glm::dot(to_middle, slide) / (slide2 > 1e-300 ? slide2 : 1e-300), 0.0, t_best);
    const glm::dvec3 gap = to_middle - along * slide;
    const double bound = rho + std::sqrt(reach2);
    if (glm::dot(gap, gap) > bound * bound) return false;
  }
  const auto in_front = [&](double t, const glm::dvec3& q) { return glm::dot(from + t * d - q, cross) > 0.0; };
  for (std::size_t k = 0; k < 3; ++k) {
    double t = 0.0;
    if (ball_entry(from - corner[k], d, r, t) && t < t_best && in_front(t, corner[k])) {
      t_best = t;
      contact = corner[k];
      found = true;
    }
    const glm::dvec3 p = corner[k], e = corner[(k + 1) % 3] - p;
    double s = 0.0;
    if (cylinder_entry(from - p, d, e, r, t, s) && t < t_best && in_front(t, p + s * e)) {
      t_best = t;
      contact = p + s * e;
      found = true;
    }
  }
  return found;
}

}  // namespace hapticfield::detail
