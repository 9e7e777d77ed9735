// Tests of Posed<S> (surface/posed_shape.hpp), each against a closed form: a
// posed plane is the plane with the rotated normal through the moved point,
// a posed box pressed through the proxy pushes along the rotated face normal
// with k x depth, and on random poses and random probes a posed mesh answers
// like the mesh moved vertex by vertex (to 1e-9). The random cases take a
// new seed each run unless Catch's --rng-seed gives one; the seed is printed.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/surface/posed_shape.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using hapticfield::test::probe_at;

namespace {

/// Catch's --rng-seed when given, else a new seed; printed either way.
unsigned run_seed() {
  static const unsigned seed = [] {
    const unsigned s = test::run_seed();
    std::printf("test_posed_shape: random seed %u (repeat with --rng-seed %u)\n", s, s);
    return s;
  }();
  return seed;
}

/// A uniformly random rotation (a random unit quaternion) and a translation within 0.2 m.
Pose random_pose(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  double q[4];
  double n = 0.0;
  do {
    n = 0.0;
    for (double& x : q) {
      x = g(rng);
      n += x * x;
    }
  } while (n < 1e-6);
  n = std::sqrt(n);
  return Pose::from_quaternion(q[0] / n, q[1] / n, q[2] / n, q[3] / n, {u(rng), u(rng), u(rng)});
}

double distance(const glm::dvec3& a, const glm::dvec3& b) {
  return glm::length(a - b);
}

TriangleMesh moved(TriangleMesh mesh, const Pose& pose) {
  for (glm::dvec3& p : mesh.positions)
    p = pose.point_to_world(p);
  for (glm::dvec3& n : mesh.normals)
    n = pose.vector_to_world(n);
  return mesh;
}

}  // namespace

TEST_CASE("Pose: quaternions, axis-angle and matrices agree; bad rotations are refused") {
  const Pose a = Pose::from_axis_angle({0, 0, 1}, std::numbers::pi / 2, {1, 2, 3});
  CHECK(distance(a.vector_to_world({1, 0, 0}), {0, 1, 0}) < 1e-15);
  CHECK(distance(a.point_to_world({1, 0, 0}), {1, 3, 3}) < 1e-15);
  CHECK(distance(a.point_to_local(a.point_to_world({0.3, -0.2, 0.7})), {0.3, -0.2, 0.7}) < 1e-15);
  const Pose m = Pose::from_rows({{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}}, {1, 2, 3});
  for (int c = 0; c < 3; ++c)
    CHECK(distance(m.rotation[c], a.rotation[c]) < 1e-15);
  CHECK(Pose{}.is_identity());
  CHECK_THROWS_AS(Pose::from_quaternion(1.0, 0.1, 0.0, 0.0), std::invalid_argument);  // not unit
  CHECK_THROWS_AS(Pose::from_quaternion(NAN, 0.0, 0.0, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(Pose::from_rows({{{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}), std::invalid_argument);  // a mirror
  CHECK_THROWS_AS(Pose::from_rows({{{2, 0, 0}, {0, 1, 0}, {0, 0, 1}}}), std::invalid_argument);   // a scale
  CHECK_THROWS_AS(Pose::from_axis_angle({0, 0, 0}, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(Pose::from_axis_angle({0, 0, 1}, 1.0, {INFINITY, 0, 0}), std::invalid_argument);
  Pose bad;
  bad.rotation[0][0] = 1.1;
  CHECK_THROWS_AS(Posed<PlaneShape>(PlaneShape(PlaneShapeConfig{}), bad), std::invalid_argument);
}

TEST_CASE("a posed plane is the plane with the rotated normal through the moved point") {
  std::mt19937_64 rng(run_seed());
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  INFO("seed " << run_seed());
  for (int pose_index = 0; pose_index < 50; ++pose_index) {
    const Pose pose = random_pose(rng);
    const PlaneShapeConfig local{{0.01, -0.02, 0.005}, glm::normalize(glm::dvec3{0.3, -0.4, 1.0}), 0.01};
    const Posed<PlaneShape> posed(PlaneShape(local), pose);
    const PlaneShape plane(
        PlaneShapeConfig{pose.point_to_world(local.point), pose.vector_to_world(local.normal), 0.01});
    for (int i = 0; i < 100; ++i) {
      const glm::dvec3 p{u(rng), u(rng), u(rng)}, q{u(rng), u(rng), u(rng)};
      const Hit a = posed.closest(p, 1.0), b = plane.closest(p, 1.0);
      REQUIRE(a.found() == b.found());
      CHECK(distance(a.point, b.point) < 1e-12);
      CHECK(distance(a.normal, b.normal) < 1e-12);
      CHECK(distance(a.face_normal, b.face_normal) < 1e-12);
      CHECK(std::fabs(a.distance - b.distance) < 1e-12);
      // the tangent frame is the local one turned: still orthonormal and normal to n
      CHECK(std::fabs(glm::dot(a.tangent, a.normal)) < 1e-12);
      CHECK(std::fabs(glm::dot(a.bitangent, a.normal)) < 1e-12);
      CHECK(std::fabs(glm::dot(glm::cross(a.tangent, a.bitangent), a.normal) - 1.0) < 1e-12);
      const Hit s = posed.first_hit(p, q), t = plane.first_hit(p, q);
      REQUIRE(s.found() == t.found());
      if (s.found()) {
        CHECK(distance(s.point, t.point) < 1e-12);
        CHECK(std::fabs(s.t - t.t) < 1e-12);
        CHECK(std::fabs(s.distance - t.distance) < 1e-12);
      }
    }
  }
}

TEST_CASE("a posed box pressed through the proxy pushes along the rotated face normal with k x depth") {
  std::mt19937_64 rng(run_seed() + 1);
  INFO("seed " << run_seed());
  constexpr double k = 1500.0, half = 0.01;
  const TriangleMesh box = test::box({-half, -half, -half}, {half, half, half}, 3);
  const glm::dvec3 faces[] = {{0, 0, 1}, {0, 0, -1}, {0, 1, 0}, {0, -1, 0}, {1, 0, 0}, {-1, 0, 0}};
  for (int pose_index = 0; pose_index < 20; ++pose_index) {
    const Pose pose = random_pose(rng);
    for (const glm::dvec3& face : faces) {
      ProxyConstraint proxy(Posed<MeshShape>(MeshShape(box), pose), ProxyConfig{k});
      // a point off the face's centre (not on a triangle edge), above it, then 1..3 mm into it
      const glm::dvec3 along = std::fabs(face.x) > 0.5 ? glm::dvec3{0, 1, 0} : glm::dvec3{1, 0, 0};
      const glm::dvec3 on_face = half * face + 0.0031 * along + 0.0017 * glm::cross(face, along);
      const glm::dvec3 n = pose.vector_to_world(face);
      (void)proxy.contact(probe_at(pose.point_to_world(on_face + 0.002 * face)));
      for (const double depth : {0.001, 0.002, 0.003}) {
        const Contact c = proxy.contact(probe_at(pose.point_to_world(on_face - depth * face)));
        REQUIRE(c.touching);
        CHECK(distance(c.force, k * depth * n) < 1e-9 * k * depth);
        CHECK(distance(c.normal, n) < 1e-12);
        CHECK(std::fabs(c.depth - depth) < 1e-9 * depth + 1e-12);
        // the proxy stays on the face in the world frame (floating 1e-6 of a triangle's size above it)
        CHECK(std::fabs(glm::dot(proxy.proxy() - pose.point_to_world(half * face), n)) < 2e-8);  // 1e-6 x the edge
      }
    }
  }
}

TEST_CASE("random poses: a posed mesh answers like the mesh moved vertex by vertex (1e-9)") {
  std::mt19937_64 rng(run_seed() + 2);
  INFO("seed " << run_seed());
  std::uniform_real_distribution<double> u(-0.04, 0.04);
  const TriangleMesh shapes[] = {test::icosphere(2, 0.02), with_vertex_normals(test::wavy_sheet(0.06, 12, 0.004, 0.03)),
                                 test::box({-0.01, -0.015, -0.005}, {0.012, 0.01, 0.008}, 2)};
  for (const TriangleMesh& mesh : shapes) {
    INFO("mesh of " << mesh.triangles.size() << " triangles");
    for (int pose_index = 0; pose_index < 10; ++pose_index) {
      const Pose pose = random_pose(rng);
      const Posed<MeshShape> posed(MeshShape(mesh), pose);
      const MeshShape moved_mesh(moved(mesh, pose));
      static_assert(Posed<MeshShape>::flat_primitives);
      static_assert(requires(QueryStats * q) { posed.sweep_sphere(glm::dvec3{}, glm::dvec3{}, 1.0, q, 0u); });
      for (int i = 0; i < 200; ++i) {
        const glm::dvec3 p = pose.point_to_world({u(rng), u(rng), u(rng)});
        const glm::dvec3 q = pose.point_to_world({u(rng), u(rng), u(rng)});
        QueryStats stats;
        const Hit a = posed.closest(p, 0.05, &stats), b = moved_mesh.closest(p, 0.05);
        REQUIRE(a.found() == b.found());
        if (a.found()) {
          CHECK(stats.nodes > 0);
          CHECK(std::fabs(a.distance - b.distance) < 1e-9);
          CHECK(distance(a.point, b.point) < 1e-9);
        }
        if (a.found() && a.primitive == b.primitive) {  // else a tie between two faces at the same distance
          CHECK(distance(a.normal, b.normal) < 1e-9);
          CHECK(distance(a.face_normal, b.face_normal) < 1e-9);
          CHECK(distance(a.tangent, b.tangent) < 1e-9);
          CHECK(distance(a.bitangent, b.bitangent) < 1e-9);
          CHECK(std::fabs(a.uv.x - b.uv.x) + std::fabs(a.uv.y - b.uv.y) < 1e-9);
          const Hit o = posed.on_primitive(a.primitive, p, 0.05);
          CHECK(distance(o.point, a.point) < 1e-9);
        }
        const Hit s = posed.first_hit(p, q, &stats), t = moved_mesh.first_hit(p, q);
        REQUIRE(s.found() == t.found());
        if (s.found()) {
          CHECK(std::fabs(s.t - t.t) < 1e-9);
          CHECK(distance(s.point, t.point) < 1e-9);
          if (s.primitive == t.primitive) CHECK(distance(s.normal, t.normal) < 1e-9);
        }
        // a 1 mm ball, with a random primitive hint (the inner mesh's; the
        // same t whatever the hint) and without
        const double r = 0.001;
        const auto hint = static_cast<std::uint32_t>(rng() % mesh.triangles.size());
        const Hit w = posed.sweep_sphere(p, q, r, &stats, hint), v = moved_mesh.sweep_sphere(p, q, r);
        REQUIRE(w.found() == v.found());
        if (w.found()) {
          CHECK(std::fabs(w.t - v.t) < 1e-9);
          if (w.primitive == v.primitive) CHECK(distance(w.point, v.point) < 1e-9);  // else a tie at the same t
        }
        // with the cache and a plane the move slides along (a world
        // direction, turned into the mesh's frame): the posed answer as it was
        MeshShape::SweepCache cache;
        const glm::dvec3 slide = glm::normalize(glm::dvec3{u(rng), u(rng), u(rng)} + glm::dvec3{0.0, 0.0, 1e-3});
        const Hit x = posed.sweep_sphere(p, q, r, &stats, hint, &cache, &slide);
        const Hit y = posed.sweep_sphere(p, q, r, &stats, hint);
        REQUIRE(x.found() == y.found());
        if (x.found()) {
          CHECK(x.t == y.t);
          CHECK(x.primitive == y.primitive);
          CHECK(x.point == y.point);
        }
        // closest through that cache (the region the sweep gathered, in the
        // mesh's frame) near where the sweep began: as without it
        const glm::dvec3 by = p + 0.3 * r * glm::dvec3{u(rng), u(rng), u(rng)} / 0.04;
        const Hit z = posed.closest(by, r, &stats, &cache), zz = posed.closest(by, r);
        REQUIRE(z.found() == zz.found());
        if (z.found()) {
          CHECK(z.primitive == zz.primitive);
          CHECK(z.point == zz.point);
          CHECK(z.distance == zz.distance);
        }
      }
      // the proxy on both, along a random stroke across the shape: the same forces
      ProxyConstraint a(posed, ProxyConfig{1500.0, 0.0, 0.3, 0.2});
      ProxyConstraint b(moved_mesh, ProxyConfig{1500.0, 0.0, 0.3, 0.2});
      glm::dvec3 hip = pose.point_to_world({u(rng), u(rng), 0.05});
      const glm::dvec3 target = pose.point_to_world({u(rng), u(rng), -0.01 + 0.001 * u(rng)});  // no tick on a face
      // a rounding-level difference may tip one proxy into the friction cone's
      // step 0 and the other into the full tick: both are proxies on the
      // surface, and they must agree again within four ticks (what is left
      // of a tip shrinks about 7x a tick: 1.9e-9 m three ticks after one,
      // 2.6e-10 m four after, in one seed in forty)
      int tipped_until = -1;
      int tipped = 0;
      for (int tick = 0; tick <= 400; ++tick) {
        const glm::dvec3 at = hip + (tick / 400.0) * (target - hip);
        const Contact ca = a.contact(probe_at(at)), cb = b.contact(probe_at(at));
        INFO("tick " << tick << " local " << pose.point_to_local(at).x << " " << pose.point_to_local(at).y << " "
                     << pose.point_to_local(at).z << " proxy " << pose.point_to_local(a.proxy()).z << " "
                     << pose.point_to_local(b.proxy()).z);
        REQUIRE(ca.touching == cb.touching);
        if (a.last_tick().held_first != b.last_tick().held_first) {
          tipped_until = tick + 4;
          ++tipped;
        }
        if (tick <= tipped_until) continue;
        // rounding differs between the two frames; friction carries it from tick to tick
        CHECK(distance(ca.force, cb.force) < 1e-6 * (1.0 + glm::length(cb.force)));
        CHECK(distance(a.proxy(), b.proxy()) < 1e-9);
      }
      CHECK(tipped <= 40);  // a tenth of the stroke at most: one that keeps tipping is a real difference
    }
  }
}

TEST_CASE("a posed shape's queries allocate nothing") {
  const Posed<MeshShape> posed(MeshShape(test::icosphere(3, 0.02)), Pose::from_axis_angle({1, 1, 0}, 0.7, {0, 0, 0.1}));
  ProxyConstraint proxy(posed, ProxyConfig{1500.0});
  (void)proxy.contact(probe_at({0.0, 0.0, 0.2}));
  const long n = test::count_allocations([&] {
    for (int i = 0; i < 1000; ++i)
      (void)proxy.contact(probe_at({0.001 * std::sin(i * 0.01), 0.0, 0.13 - 0.0001 * i}));
  });
  if (test::allocations_counted) CHECK(n == 0);
}
