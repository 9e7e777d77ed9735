// Tests of the surfaces (surface/): the analytic shapes against their
// closed forms, MeshBvh against a brute-force scan of the same triangles,
// and the proxy (ProxyConstraint) on planes, meshes and spheres.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/surface.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;

namespace {

Probe probe_at(glm::dvec3 position, glm::dvec3 velocity = glm::dvec3{0.0}) {
  Probe p;
  p.position = position;
  p.velocity = velocity;
  return p;
}

/// The nearest point of a triangle by minimising over its face and edges
/// (an independent closed form: the face by projection, each edge by the
/// clamped parameter).
glm::dvec3 brute_closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                                     const glm::dvec3& c) {
  const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
  const glm::dvec3 q = p - glm::dot(p - a, n) * n;
  const auto inside = [&](const glm::dvec3& x, const glm::dvec3& y) {
    return glm::dot(glm::cross(y - x, q - x), n) >= 0.0;
  };
  if (inside(a, b) && inside(b, c) && inside(c, a)) return q;
  const auto on_edge = [&](const glm::dvec3& x, const glm::dvec3& y) {
    const double s = std::clamp(glm::dot(p - x, y - x) / glm::dot(y - x, y - x), 0.0, 1.0);
    return x + s * (y - x);
  };
  glm::dvec3 best = on_edge(a, b);
  for (const glm::dvec3 e : {on_edge(b, c), on_edge(c, a)})
    if (glm::length(e - p) < glm::length(best - p)) best = e;
  return best;
}

double brute_distance(const TriangleMesh& m, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles)
    best = std::fmin(
        best, glm::length(brute_closest_on_triangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]) - p));
  return best;
}

}  // namespace

// --- analytic shapes ---------------------------------------------------------------

TEST_CASE("a plane shape answers closest and first_hit with the closed forms") {
  const PlaneShape plane(PlaneShapeConfig{{0.0, 0.0, 0.01}, {0.0, 0.0, 1.0}, 0.01});
  const Hit c = plane.closest({0.02, -0.03, 0.013}, 1.0);
  REQUIRE(c.found());
  CHECK_THAT(c.distance, WithinAbs(0.003, 1e-15));
  CHECK(c.point == glm::dvec3{0.02, -0.03, 0.01});
  CHECK_THAT(c.uv.x, WithinAbs(0.02, 1e-15));
  CHECK_THAT(c.uv.y, WithinAbs(-0.03, 1e-15));
  CHECK_FALSE(plane.closest({0.0, 0.0, 0.5}, 0.1).found());
  const Hit h = plane.first_hit({0.0, 0.0, 0.03}, {0.0, 0.0, -0.01});
  REQUIRE(h.found());
  CHECK_THAT(h.t, WithinAbs(0.5, 1e-15));
  CHECK_FALSE(plane.first_hit({0.0, 0.0, -0.01}, {0.0, 0.0, 0.03}).found());  // from behind: passes
}

// --- MeshBvh -----------------------------------------------------------------------

TEST_CASE("MeshBvh closest agrees with a brute-force scan on a wavy sheet") {
  const TriangleMesh m = test::wavy_sheet(0.1, 24, 0.005, 0.03);
  const MeshBvh bvh = MeshBvh::build(m);
  CHECK(bvh.triangle_count() == m.triangles.size());
  CHECK(bvh.depth() <= bvh_max_depth);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (int i = 0; i < 300; ++i) {
    const glm::dvec3 p{u(rng), u(rng), u(rng) * 0.3};
    const BvhHit h = bvh.closest(p, 1.0);
    REQUIRE(h.found());
    CHECK_THAT(h.distance, WithinAbs(brute_distance(m, p), 1e-12));
  }
}

// --- the proxy ---------------------------------------------------------------------

TEST_CASE("the proxy on an analytic plane gives Fc = k depth n and stays on the surface") {
  ProxyConstraint proxy(PlaneShape(PlaneShapeConfig{}), ProxyConfig{1000.0});
  CHECK_FALSE(proxy.contact(probe_at({0.01, 0.0, 0.01})).touching);  // starts in free space
  const Contact c = proxy.contact(probe_at({0.01, 0.0, -0.002}));
  REQUIRE(c.touching);
  CHECK_THAT(c.depth, WithinAbs(0.002, 1e-9));
  CHECK_THAT(c.force.z, WithinAbs(2.0, 1e-6));
  CHECK_THAT(c.force.x, WithinAbs(0.0, 1e-9));
  CHECK_THAT(proxy.proxy().z, WithinAbs(0.0, 1e-7));
}
