// A finite tool radius: the proxy as a ball (ProxyConfig::radius) swept
// against meshes (faces, edge cylinders, corner balls), height fields (two
// triangles a cell) and the analytic shapes, checked against closed forms,
// and its centre's path checked against a brute-force distance to every
// nearby triangle.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <catch2/catch.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/proxy_check.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"
#include "tree_walk_shape.hpp"

using namespace hapticfield;
using test::probe_at;
using test::run_seed;

namespace {

constexpr double k = 1500.0;  // [N/m]

/// Presses the ball toward `goal` from `start` over `ticks` ticks and holds
/// it there for as many more; returns the last contact.
template <class S>
Contact press(ProxyConstraint<S>& proxy, glm::dvec3 start, glm::dvec3 goal, int ticks = 100) {
  Contact c;
  for (int i = 0; i <= 2 * ticks; ++i) {
    const double f = std::fmin(1.0, static_cast<double>(i) / ticks);
    c = proxy.contact(probe_at(start + f * (goal - start)));
  }
  return c;
}

/// A V groove along y: two faces through the x axis rising at `slope` rad
/// on either side.
TriangleMesh v_groove(double slope, double half_width = 0.02, double length = 0.04) {
  TriangleMesh m;
  const double h = half_width * std::tan(slope);
  test::add_grid(m, {-half_width, -length / 2, h}, {half_width, 0, -h}, {0, length, 0}, 4, 4);  // left, down to x = 0
  test::add_grid(m, {0, -length / 2, 0}, {half_width, 0, h}, {0, length, 0}, 4, 4);             // right, up
  return m;
}

/// Corner k of triangle j of a mesh [m].
glm::dvec3 corner(const TriangleMesh& mesh, std::size_t j, std::size_t k) {
  return mesh.positions[mesh.triangles[j][k]];
}

/// The distance from p to triangle j of a mesh [m].
double distance_to(const TriangleMesh& mesh, std::size_t j, const glm::dvec3& p) {
  const glm::dvec3 a = corner(mesh, j, 0);
  double b1 = 0.0, b2 = 0.0;
  return glm::length(p - detail::closest_on_triangle(p, a, corner(mesh, j, 1) - a, corner(mesh, j, 2) - a, b1, b2));
}

/// A sheet flat but for rounding to float: each height nudged by up to
/// 1e-6 of `size` [m], then rounded to the nearest float.
void round_heights_to_float(TriangleMesh& mesh, double size, std::mt19937& rng,
                            std::uniform_real_distribution<double>& u) {
  for (glm::dvec3& p : mesh.positions)
    p.z = static_cast<double>(static_cast<float>(p.z + size * 1e-6 * u(rng)));
}

/// A random turn: about a random axis, by up to 3 rad either way.
struct Turn {
  glm::dvec3 axis{0.0, 0.0, 1.0};
  double angle{0.0};  ///< [rad]
};
Turn random_turn(std::mt19937& rng, std::uniform_real_distribution<double>& u) {
  Turn turn;
  turn.axis = glm::normalize(glm::dvec3{u(rng), u(rng), u(rng)} + glm::dvec3{0.0, 0.0, 1e-3});
  turn.angle = 3.0 * u(rng);
  return turn;
}

/// The mesh turned (Rodrigues' formula), then moved by `shift` [m].
void turn_and_move(TriangleMesh& mesh, const Turn& turn, const glm::dvec3& shift) {
  const double c = std::cos(turn.angle), s = std::sin(turn.angle);
  for (glm::dvec3& p : mesh.positions)
    p = p * c + glm::cross(turn.axis, p) * s + turn.axis * glm::dot(turn.axis, p) * (1.0 - c) + shift;
}

/// Two answers of the same sweep asked two ways: the same, bit for bit.
void require_same_hit(const BvhHit& asked, const BvhHit& reference) {
  REQUIRE(asked.found() == reference.found());
  REQUIRE(asked.complete == reference.complete);
  if (!reference.found()) return;
  REQUIRE(asked.triangle == reference.triangle);
  REQUIRE(asked.t == reference.t);
  REQUIRE(asked.contact_point == reference.contact_point);
}

}  // namespace

TEST_CASE("a ball on a plane rests its radius above it, Fc = k (r - height of the HIP)", "[radius]") {
  for (const double r : {0.0005, 0.002, 0.005}) {
    INFO("r " << r);
    ProxyConstraint mesh(MeshShape(test::flat_sheet(0.1, 8)), ProxyConfig{.stiffness = k, .radius = r});
    ProxyConstraint plane(PlaneShape(PlaneShapeConfig{}), ProxyConfig{.stiffness = k, .radius = r});
    for (const double hip : {0.5 * r, 0.0, -0.002}) {
      const glm::dvec3 goal{0.004, -0.003, hip};
      const Contact a = press(mesh, {0.0, 0.0, 0.01}, goal);
      const Contact b = press(plane, {0.0, 0.0, 0.01}, goal);
      for (const auto* c : {&a, &b}) {
        REQUIRE(c->touching);
        CHECK(c->force.z == Approx(k * (r - hip)).epsilon(1e-5));
        CHECK(std::fabs(c->force.x) + std::fabs(c->force.y) < 1e-9);
      }
      CHECK(mesh.proxy().z == Approx(r).margin(1e-7));  // r and the proxy's offset (1e-6 of a face)
      CHECK(plane.proxy().z == Approx(r).margin(1e-7));
      mesh.reset();
      plane.reset();
    }
  }
}

TEST_CASE("a ball in a V groove rests where both faces touch it: r / cos(slope) above the groove's line", "[radius]") {
  for (const double slope : {0.3, 0.6, 1.0}) {
    const double r = 0.002;
    ProxyConstraint proxy(MeshShape(v_groove(slope)), ProxyConfig{.stiffness = k, .radius = r});
    const Contact c = press(proxy, {0.0, 0.0, 0.02}, {0.0, 0.001, -0.003});
    INFO("slope " << slope);
    REQUIRE(c.touching);
    CHECK(proxy.proxy().x == Approx(0.0).margin(1e-6));
    CHECK(proxy.proxy().z == Approx(r / std::cos(slope)).epsilon(1e-4));
    CHECK(proxy.last_tick().planes == 2);
    // the force: k (centre - HIP), straight up
    CHECK(c.force.z == Approx(k * (r / std::cos(slope) + 0.003)).epsilon(1e-4));
  }
}

TEST_CASE("a ball on a cube's edge: its centre follows the arc of radius r about the edge", "[radius]") {
  // the edge along y at x = z = 0 of the box x < 0, z < 0; the HIP circles
  // it at r / 2, from over the top to beside the side
  const double r = 0.003;
  ProxyConstraint proxy(MeshShape(test::box({-0.02, -0.02, -0.02}, {0.0, 0.02, 0.0}, 2)),
                        ProxyConfig{.stiffness = k, .radius = r});
  (void)proxy.contact(probe_at({-0.001, 0.0, 0.01}));
  int checked = 0;
  for (int i = 0; i <= 2000; ++i) {
    const double phi = std::numbers::pi / 2 * std::fmin(1.0, i / 1500.0);  // 0: above the top, pi / 2: beside the side
    const glm::dvec3 around{std::sin(phi), 0.0, std::cos(phi)};
    const glm::dvec3 hip = i < 100 ? glm::dvec3{-0.001, 0.0, 0.01 - 1e-4 * i} : 0.5 * r * around;
    const Contact c = proxy.contact(probe_at(hip));
    if (i < 200 || !c.touching) continue;
    const glm::dvec3 centre = proxy.proxy();
    const double off = std::hypot(centre.x, centre.z);
    INFO("tick " << i << " phi " << phi);
    CHECK(off == Approx(r).epsilon(1e-4));                             // on the arc
    CHECK(glm::length(c.force) == Approx(k * 0.5 * r).epsilon(1e-3));  // k times the depth below it
    if (phi > 0.05 && phi < 1.5) CHECK(std::atan2(centre.x, centre.z) == Approx(phi).margin(2e-3));
    ++checked;
  }
  CHECK(checked > 1500);
}

TEST_CASE("a crack narrower than 2 r is not entered; a wider one is", "[radius]") {
  const double r = 0.002;
  for (const double gap : {0.003, 0.0039, 0.0041, 0.006}) {
    TriangleMesh m = test::box({-0.03, -0.02, -0.02}, {-gap / 2, 0.02, 0.0}, 2);
    const TriangleMesh right = test::box({gap / 2, -0.02, -0.02}, {0.03, 0.02, 0.0}, 2);
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), right.positions.begin(), right.positions.end());
    m.uvs.insert(m.uvs.end(), right.uvs.begin(), right.uvs.end());
    for (auto t : right.triangles)
      m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    ProxyConstraint proxy(MeshShape(m), ProxyConfig{.stiffness = k, .radius = r});
    (void)press(proxy, {0.0, 0.0, 0.01}, {0.0, 0.0, -0.01});
    INFO("gap " << gap);
    if (gap < 2 * r) {
      // resting on both rims: the centre sqrt(r^2 - (gap / 2)^2) above the top
      CHECK(proxy.proxy().z == Approx(std::sqrt(r * r - gap * gap / 4)).epsilon(1e-3));
      CHECK(proxy.touching());
    } else {
      CHECK(proxy.proxy().z < -0.009);  // fell in (free, or on the crack's floor: none here)
    }
  }
}

TEST_CASE("a ball on the analytic sphere rests at R + r from its centre", "[radius]") {
  const double R = 0.03, r = 0.004;
  ProxyConstraint proxy(SphereShape(SphereShapeConfig{{0.0, 0.0, 0.0}, R}), ProxyConfig{.stiffness = k, .radius = r});
  const Contact c = press(proxy, {0.0, 0.0, 0.05}, {0.001, 0.0, R});
  REQUIRE(c.touching);
  CHECK(glm::length(proxy.proxy()) == Approx(R + r).epsilon(1e-5));
  CHECK(glm::length(c.force) == Approx(k * (R + r - glm::length(glm::dvec3{0.001, 0.0, R}))).epsilon(1e-3));
}

TEST_CASE("the ball's centre never comes nearer than r to a mesh: slides on random closed meshes at 26 mm/s and 2 m/s",
          "[radius][invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g;
  for (const double r : {0.0005, 0.002}) {
    TriangleMesh m = test::icosphere(3, 0.03);
    m.normals.clear();
    for (auto& p : m.positions)
      p *= 0.8 + 0.4 * u(rng);
    const MeshChecker checker(m);
    ProxyConstraint proxy(MeshShape(m), ProxyConfig{.stiffness = k, .radius = r});
    double nearest = std::numeric_limits<double>::infinity();
    long touching = 0;
    for (int s = 0; s < 200; ++s) {
      const glm::dvec3 dir = glm::normalize(glm::dvec3{g(rng), g(rng), g(rng)});
      glm::dvec3 side = glm::normalize(glm::cross(dir, glm::dvec3{g(rng), g(rng), g(rng)}));
      const double speed = s % 2 ? 2.0 : 0.026;
      proxy.reset();
      for (int j = 0; j < 150; ++j) {
        // in from 6 cm out to 2 mm under the mean radius, then sideways
        const double in = std::fmin(1.0, j / 30.0);
        const glm::dvec3 hip = (0.06 - 0.032 * in) * dir + std::fmax(0, j - 30) * 1e-3 * speed * side;
        const Contact c = proxy.contact(probe_at(hip, speed * side));
        touching += c.touching;
        const ProxyPath& path = proxy.last_path();
        for (int q = 0; q + 1 < path.count; ++q) {  // every piece, sampled every r / 8
          const glm::dvec3 a = path.points[static_cast<std::size_t>(q)],
                           b = path.points[static_cast<std::size_t>(q + 1)];
          const int samples = 1 + static_cast<int>(glm::length(b - a) / (r / 8));
          for (int w = 0; w <= samples; ++w)
            nearest = std::fmin(nearest, checker.distance(a + (static_cast<double>(w) / samples) * (b - a), 2 * r));
        }
      }
    }
    INFO("r " << r << ": nearest " << nearest << " m over " << touching << " touching ticks");
    CHECK(touching > 2000);
    CHECK(nearest >= r * (1.0 - 1e-6));
  }
}

TEST_CASE("a ball's tick allocates nothing; radius 0 is the point proxy; bad radii and shapes are refused",
          "[radius]") {
  ProxyConstraint proxy(MeshShape(test::icosphere(3, 0.03)), ProxyConfig{.stiffness = k, .radius = 0.002});
  long allocations = 0;
  for (int i = 0; i < 200; ++i)
    allocations += test::count_allocations([&] {
      (void)proxy.contact(probe_at({0.001 * std::sin(i * 0.1), 0.0, 0.04 - 1e-4 * i}));
    });
  if (test::allocations_counted) CHECK(allocations == 0);
  // radius 0: the same ticks as a proxy built without the field
  ProxyConstraint point(MeshShape(test::icosphere(2, 0.03)), ProxyConfig{.stiffness = k});
  ProxyConstraint zero(MeshShape(test::icosphere(2, 0.03)), ProxyConfig{.stiffness = k, .radius = 0.0});
  for (int i = 0; i < 300; ++i) {
    const glm::dvec3 hip{0.004 * std::sin(i * 0.05), 0.003 * std::cos(i * 0.07), 0.035 - 5e-5 * i};
    CHECK(point.contact(probe_at(hip)).force == zero.contact(probe_at(hip)).force);
  }
  CHECK_THROWS_AS(ProxyConstraint(PlaneShape(PlaneShapeConfig{}), ProxyConfig{.radius = -1e-3}), std::invalid_argument);
  CHECK_THROWS_AS(ProxyConstraint(PlaneShape(PlaneShapeConfig{}), ProxyConfig{.radius = 0.06}), std::invalid_argument);
  CHECK_THROWS_AS(ProxyConstraint(PlaneShape(PlaneShapeConfig{}), ProxyConfig{.radius = std::nan("")}),
                  std::invalid_argument);
  // a height field takes a ball too
  const HeightFieldShape field(3, 3, 0.01, 0.01, std::vector<double>(9, 0.0));
  CHECK_NOTHROW(ProxyConstraint(field, ProxyConfig{.radius = 0.001}));
}

namespace {

/// Heights h(x, y) sampled on an n x n grid of `spacing` [m].
template <class F>
HeightFieldShape sampled(int n, double spacing, F h) {
  std::vector<double> heights(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      heights[static_cast<std::size_t>(j) * n + i] = h(i * spacing, j * spacing);
  return HeightFieldShape(n, n, spacing, spacing, heights);
}

/// The two triangles per cell a ball sees on `field` (the diagonal from
/// (i, j) to (i + 1, j + 1)), as a mesh: the oracle's surface.
TriangleMesh triangulated(const HeightFieldShape& field) {
  TriangleMesh m;
  const std::uint32_t w = field.width(), h = field.height();
  for (std::uint32_t j = 0; j < h; ++j)
    for (std::uint32_t i = 0; i < w; ++i) {
      const double x = i * field.spacing().x, y = j * field.spacing().y;
      // the sample itself: the bilinear height at a sample is the sample
      m.positions.push_back(
          {x, y,
           field.height_at(std::fmin(x, (w - 1) * field.spacing().x), std::fmin(y, (h - 1) * field.spacing().y))});
    }
  for (std::uint32_t j = 0; j + 1 < h; ++j)
    for (std::uint32_t i = 0; i + 1 < w; ++i) {
      const std::uint32_t a = j * w + i, b = a + 1, c = a + w, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

}  // namespace

TEST_CASE(
    "a ball on a height field: r above a flat field and a ramp, r / cos(slope) over a groove, a narrow trench "
    "not entered",
    "[radius][height]") {
  const double r = 0.002;
  SECTION("flat and ramp: the centre r from the plane, Fc = k (r - the HIP's distance)") {
    for (const double slope : {0.0, 0.3, 0.7}) {
      ProxyConstraint proxy(sampled(41, 0.001, [&](double x, double) { return std::tan(slope) * (x - 0.02); }),
                            ProxyConfig{.stiffness = k, .radius = r});
      const glm::dvec3 n{-std::sin(slope), 0.0, std::cos(slope)};  // the ramp's normal
      const glm::dvec3 on{0.02, 0.021, 0.0};                       // a point of the ramp
      const Contact c = press(proxy, on + 0.02 * n, on - 0.001 * n);
      INFO("slope " << slope);
      REQUIRE(c.touching);
      CHECK(glm::dot(proxy.proxy() - on, n) == Approx(r).epsilon(1e-4));
      CHECK(glm::length(c.force) == Approx(k * (r + 0.001)).epsilon(1e-3));
      CHECK(glm::dot(c.force, n) == Approx(glm::length(c.force)).epsilon(1e-6));
    }
  }
  SECTION("a V groove along y at x = 20 mm: the centre r / cos(slope) above its line") {
    for (const double slope : {0.3, 0.6, 1.0}) {
      ProxyConstraint proxy(sampled(41, 0.001, [&](double x, double) { return std::tan(slope) * std::fabs(x - 0.02); }),
                            ProxyConfig{.stiffness = k, .radius = r});
      const Contact c = press(proxy, {0.02, 0.02, 0.02}, {0.02, 0.0205, -0.003});
      INFO("slope " << slope);
      REQUIRE(c.touching);
      CHECK(proxy.proxy().x == Approx(0.02).margin(1e-6));
      CHECK(proxy.proxy().z == Approx(r / std::cos(slope)).epsilon(1e-4));
    }
  }
  SECTION(
      "a trench one sample wide (rims 2 mm apart, 10 mm deep): a 2 mm ball rests on both rims, a 0.5 mm one "
      "falls to where both walls touch it") {
    const double s = 0.001, depth = 0.01;
    const auto trench = [&](double x, double) { return std::fabs(x - 0.02) < 0.5 * s ? -depth : 0.0; };
    ProxyConstraint wide(sampled(41, s, trench), ProxyConfig{.stiffness = k, .radius = r});
    (void)press(wide, {0.02, 0.02, 0.01}, {0.02, 0.02, -0.02});
    CHECK(wide.touching());
    CHECK(wide.proxy().z == Approx(std::sqrt(r * r - s * s)).epsilon(1e-3));
    const double small = 0.0005, wall = std::atan(depth / s);  // the walls' angle from the horizontal
    ProxyConstraint narrow(sampled(41, s, trench), ProxyConfig{.stiffness = k, .radius = small});
    (void)press(narrow, {0.02, 0.02, 0.01}, {0.02, 0.02, -0.02});
    CHECK(narrow.touching());
    CHECK(narrow.proxy().z == Approx(-depth + small / std::cos(wall)).epsilon(1e-3));
  }
}

TEST_CASE(
    "a ball on a height field meets what a brute-force sweep over its triangles meets; its centre never comes "
    "nearer than r to them while sliding",
    "[radius][height][invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g;
  // a rough field: 1 mm cells, bumps of +-0.6 mm and a few 3 mm cliffs
  const int n = 33;
  const double spacing = 0.001;
  std::vector<double> heights(static_cast<std::size_t>(n) * n);
  for (double& h : heights)
    h = 0.0006 * (2.0 * u(rng) - 1.0) + (u(rng) < 0.03 ? 0.003 : 0.0);
  const HeightFieldShape field(n, n, spacing, spacing, heights);
  const TriangleMesh mesh = triangulated(field);
  const MeshShape oracle(mesh);
  const double extent = (n - 1) * spacing;
  for (const double r : {0.0005, 0.002}) {
    INFO("r " << r);
    // the query against the brute force: random segments above and through the field
    int met = 0;
    for (int q = 0; q < 3000; ++q) {
      const glm::dvec3 from{extent * u(rng), extent * u(rng), 0.006 + 0.01 * u(rng)};  // above every bump and cliff
      const glm::dvec3 to = from + 0.01 * glm::dvec3{g(rng), g(rng), g(rng) - 1.0};
      const Hit a = field.sweep_sphere(from, to, r), b = oracle.sweep_sphere(from, to, r);
      INFO("query " << q);
      REQUIRE(a.found() == b.found());
      if (!a.found()) continue;
      ++met;
      CHECK(a.t == Approx(b.t).margin(1e-9));
      CHECK(glm::length(a.point - b.point) <= 1e-9 + 1e-6 * r);
    }
    CHECK(met > 1000);
    // slides: the centre's path, every piece, against the distance to the triangles
    const MeshChecker checker(mesh);
    ProxyConstraint proxy(field, ProxyConfig{.stiffness = k, .radius = r});
    double nearest = std::numeric_limits<double>::infinity();
    long touching = 0;
    for (int sl = 0; sl < 100; ++sl) {
      const double speed = sl % 2 ? 2.0 : 0.026;
      const double angle = 2.0 * std::numbers::pi * u(rng);
      const glm::dvec3 side{std::cos(angle), std::sin(angle), 0.0};
      const glm::dvec3 start{0.008 + 0.016 * u(rng), 0.008 + 0.016 * u(rng), 0.012};
      proxy.reset();
      // a ball that has gone past the field's open border may come back
      // under the sheet (it has no underside to stop it): from then on, that
      // slide's distances say nothing of the surface's front
      bool past_border = false;
      for (int j = 0; j < 150; ++j) {
        const double in = std::fmin(1.0, j / 30.0);  // down to 1 mm under the mean level, then sideways
        const glm::dvec3 hip = start - glm::dvec3{0.0, 0.0, 0.013 * in} + std::fmax(0, j - 30) * 1e-3 * speed * side;
        const Contact c = proxy.contact(probe_at(hip, speed * side));
        touching += c.touching;
        const ProxyPath& path = proxy.last_path();
        for (int q = 0; q + 1 < path.count; ++q) {
          const glm::dvec3 a = path.points[static_cast<std::size_t>(q)],
                           b = path.points[static_cast<std::size_t>(q + 1)];
          const int samples = 1 + static_cast<int>(glm::length(b - a) / (r / 8));
          for (int w = 0; w <= samples; ++w) {
            const glm::dvec3 p = a + (static_cast<double>(w) / samples) * (b - a);
            if (p.x < 0.0 || p.y < 0.0 || p.x > extent || p.y > extent) past_border = true;  // off the field
            if (past_border) continue;
            nearest = std::fmin(nearest, checker.distance(p, 2 * r));
          }
        }
      }
    }
    INFO("nearest " << nearest << " m over " << touching << " touching ticks");
    CHECK(touching > 2000);
    CHECK(nearest >= r * (1.0 - 1e-6));
  }
}

TEST_CASE(
    "a ball that begins in the surface is free until clear of it; it leaves a solid and an open sheet from "
    "behind as a point does",
    "[radius]") {
  const double r = 0.002;
  SECTION("begun on a fine wavy sheet: no force while it overlaps, then a contact from above") {
    // 0.14 mm triangles under a 2 mm ball: swept from where it overlaps, it would meet a corner at t = 0 whichever
    // way it moved (the proxy stuck where it began, the force growing as the HIP moved away)
    const TriangleMesh sheet = test::wavy_sheet(0.1, 350, 0.002, 0.03);
    ProxyConstraint proxy(MeshShape(sheet), ProxyConfig{.stiffness = k, .radius = r});
    for (int i = 0; i <= 200; ++i) {  // sideways 20 mm along the surface, never farther than 1 mm from it
      const glm::dvec3 hip{1e-4 * i, 0.0, 0.0};
      const Contact c = proxy.contact(probe_at(hip));
      INFO("tick " << i);
      CHECK_FALSE(c.touching);
      CHECK(c.force == glm::dvec3{0.0});
      CHECK(proxy.last_tick().embedded);
      CHECK(proxy.proxy() == hip);
    }
    (void)proxy.contact(probe_at({0.02, 0.0, 0.01}));  // lifted clear: an ordinary ball again
    CHECK_FALSE(proxy.last_tick().embedded);
    const Contact c = press(proxy, {0.02, 0.0, 0.01}, {0.02, 0.0, -0.001});  // the sheet is at z = 0 along y = 0
    REQUIRE(c.touching);
    CHECK(MeshChecker(sheet).distance(proxy.proxy(), 2 * r) >= r * (1.0 - 1e-6));
    CHECK(c.force.z > 0.5 * k * 0.001);
  }
  SECTION("from under an open sheet up through it, and from the centre of a closed sphere out: no force") {
    ProxyConstraint sheet(MeshShape(test::flat_sheet(0.1, 60)), ProxyConfig{.stiffness = k, .radius = r});
    ProxyConstraint solid(MeshShape(test::icosphere(3, 0.03)), ProxyConfig{.stiffness = k, .radius = r});
    for (int i = 0; i <= 400; ++i) {
      const glm::dvec3 hip{0.001, 0.002, -0.01 + 5e-5 * i};  // z from -10 to +10 mm
      const Contact a = sheet.contact(probe_at(hip));
      const Contact b = solid.contact(probe_at({0.0, 0.0, 0.05 * i / 400.0}));  // the centre to 5 cm, out the top
      INFO("tick " << i);
      CHECK(a.force == glm::dvec3{0.0});
      CHECK(b.force == glm::dvec3{0.0});
    }
    // a fine wavy sheet (0.14 mm triangles, far smaller than the ball) crossed from under, slanting: a ball
    // overlapping it from behind meets some corner at t = 0 whichever way it moves; it was held there, the force
    // growing, until it passes on free (ProxyTick::embedded)
    for (const double radius : {0.0005, 0.002}) {
      ProxyConstraint wavy(MeshShape(test::wavy_sheet(0.1, 707, 0.002, 0.03)),
                           ProxyConfig{.stiffness = k, .radius = radius});
      int passed = 0;
      for (int i = 0; i <= 400; ++i) {
        const glm::dvec3 hip{0.01 + 2e-5 * i, 0.005 - 1e-5 * i, -0.006 + 3e-5 * i};  // z from -6 to +6 mm
        const Contact c = wavy.contact(probe_at(hip));
        INFO("radius " << radius << " tick " << i);
        CHECK(c.force == glm::dvec3{0.0});
        passed += wavy.last_tick().embedded;
      }
      CHECK(passed > 0);  // it did overlap the sheet on the way through
      CHECK(press(wavy, {0.018, 0.001, 0.01}, {0.018, 0.001, -0.001}).touching);  // felt from above once clear
    }
    // from above again, both are felt
    CHECK(press(sheet, {0.001, 0.002, 0.01}, {0.001, 0.002, -0.001}).touching);
    CHECK(sheet.proxy().z == Approx(r).epsilon(1e-4));
    CHECK(press(solid, {0.0, 0.0, 0.05}, {0.0, 0.0, 0.029}).touching);
  }
}

TEST_CASE(
    "a node's slab never passes by a contact: a ball's sweep answers exactly as through the same tree without "
    "the slabs, and meets what a brute-force sweep over every triangle meets",
    "[radius][invariant]") {
  // MeshBvh::NodeBounds::may_touch skips a whole subtree where the ball
  // stays clear of its slab. A second build of the same mesh refit to the
  // same vertices has no slabs (refit drops them) and is otherwise the same
  // tree, so every sweep must answer the same bit for bit: on wavy sheets
  // (where the slabs skip most), sheets flat to 1e-12 of their size or but
  // for rounding to float, spheres, boxes and sheets with slivers lying in
  // their plane, of 1 mm to 1 m, turned at random, near the origin or up to
  // 10 m from it; balls resting on a face, an edge or a corner (at r, within
  // rounding of it, a little nearer or farther), moved along the face,
  // grazing into it, into it, away, far or anywhere, some seeded with a
  // triangle's own contact. Besides, the tree meets what a brute force over
  // every triangle meets (each triangle's own first contact, the earliest),
  // or differs only where the ball grazes a face (its distance r within
  // rounding all along, the time of contact ill-conditioned).
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto unit = [&] { return 0.5 + 0.5 * u(rng); };
  int compared = 0, contacts = 0, same = 0, grazing = 0, served = 0;
  std::uint64_t nodes_with = 0, nodes_without = 0;
  for (int m = 0; m < 24; ++m) {
    const double size = std::pow(10.0, -3.0 + 3.0 * unit());  // [m]
    const int kind = m % 6;
    TriangleMesh mesh;
    if (kind == 0)
      mesh = test::wavy_sheet(size, 12 + static_cast<int>(20 * unit()), size * 0.1 * unit(), size * (0.2 + unit()));
    else if (kind == 1)  // all but flat: sibling nodes' normals a few 1e-9 rad apart
      mesh = test::wavy_sheet(size, 30, size * std::pow(10.0, -12.0 + 6.0 * unit()), size * (0.2 + unit()));
    else if (kind == 2)
      mesh = test::icosphere(2 + m % 2, 0.5 * size);
    else if (kind == 3)
      mesh = test::box(glm::dvec3{0.0}, size * glm::dvec3{1.0, 0.5 + unit(), 0.2 + unit()}, 2 + m % 5);
    else
      mesh = test::flat_sheet(size, 4 + static_cast<int>(12 * unit()));
    mesh.uvs.clear();
    mesh.normals.clear();
    if (kind == 4) {  // slivers 1e-11.5 to 1e-3 of their length across, in the sheet's plane
      for (int k = 0; k < 24; ++k) {
        const double along = 3.14159 * u(rng), length = size * (0.05 + 0.5 * unit());
        const double across = std::pow(10.0, -11.5 + 8.5 * unit());
        const glm::dvec3 centre{0.45 * size * u(rng), 0.45 * size * u(rng), 0.0};
        const glm::dvec3 dir{std::cos(along), std::sin(along), 0.0}, normal{-dir.y, dir.x, 0.0};
        const auto first = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(centre - 0.5 * length * dir);
        mesh.positions.push_back(centre + 0.5 * length * dir);
        mesh.positions.push_back(centre + 0.5 * u(rng) * length * dir + across * length * normal);
        mesh.triangles.push_back({first, first + 1, first + 2});
      }
    }
    if (kind == 5) round_heights_to_float(mesh, size, rng, u);
    // turned about a random axis, then moved
    const Turn turn = random_turn(rng, u);
    const glm::dvec3 shift = (m % 3 == 0 ? 10.0 * unit() : 0.0) * glm::dvec3{u(rng), u(rng), u(rng)};
    turn_and_move(mesh, turn, shift);
    const double rounding = 64.0 * std::numeric_limits<double>::epsilon() * (glm::length(shift) + size);  // [m]
    const MeshBvh bvh = MeshBvh::build(mesh);
    MeshBvh boxes_only = MeshBvh::build(mesh);
    boxes_only.refit(mesh);
    MeshBvh::Neighbourhood near;  // kept from sweep to sweep, as a proxy keeps one
    for (int i = 0; i < 1500; ++i) {
      const std::size_t start =
          kind == 4 && i % 2 == 0 ? mesh.triangles.size() - 1 - rng() % 24 : rng() % mesh.triangles.size();
      const glm::dvec3 a = corner(mesh, start, 0), e1 = corner(mesh, start, 1) - a, e2 = corner(mesh, start, 2) - a;
      if (!(glm::length(glm::cross(e1, e2)) > 0.0)) continue;
      const glm::dvec3 n = glm::normalize(glm::cross(e1, e2));
      double b1 = unit(), b2 = unit();
      if (b1 + b2 > 1.0) {
        b1 = 1.0 - b1;
        b2 = 1.0 - b2;
      }
      if (i % 7 == 0) b2 = 0.0;  // on an edge
      if (i % 11 == 0) {         // on a corner
        b1 = 1.0;
        b2 = 0.0;
      }
      const double r = size * std::pow(10.0, -3.5 + 3.0 * unit());
      const double heights[] = {r,
                                r * (1.0 + 1e-12),
                                r * (1.0 - 1e-12),
                                r * (1.0 - 1e-9),
                                0.5 * r,
                                r + size * 1e-9 * u(rng),
                                r + size * 1e-12 * u(rng),
                                2.0 * r,
                                r * (1.0 + 1e-6 * unit())};
      const double height = heights[i % 9];
      const glm::dvec3 from = a + b1 * e1 + b2 * e2 + height * n;
      const double reach = r * std::pow(10.0, -4.0 + 4.5 * unit());  // [m]
      glm::dvec3 d = reach * glm::dvec3{u(rng), u(rng), u(rng)};
      const int move = (i / 9) % 6;
      if (move == 0) d -= glm::dot(d, n) * n;                                                      // along the face
      if (move == 1) d -= (std::fabs(u(rng)) * 2.0 * reach) * n;                                   // into it
      if (move == 2) d += (std::fabs(u(rng)) * reach) * n;                                         // away
      if (move == 3) d -= glm::dot(d, n) * n + reach * std::pow(10.0, -12.0 + 10.0 * unit()) * n;  // grazing, in
      if (move == 4) d = 2.0 * size * glm::dvec3{u(rng), u(rng), u(rng)};                          // far
      const glm::dvec3 to = from + d;
      d = to - from;  // the move as the tree sees it
      BvhHit seeded;  // every fifth sweep seeded with a triangle's own contact, as the proxy's are
      if (i % 5 == 0) {
        const std::size_t other = i % 2 == 0 ? start : rng() % mesh.triangles.size();
        const glm::dvec3 p = corner(mesh, other, 0);
        double t = 1.0;
        (void)MeshBvh::touch_triangle(p, corner(mesh, other, 1) - p, corner(mesh, other, 2) - p,
                                      static_cast<std::uint32_t>(other), from, d, r, t, seeded);
      }
      QueryStats with, without;
      const BvhHit tree = bvh.sweep_sphere(from, to, r, &with, seeded);
      const BvhHit plain = boxes_only.sweep_sphere(from, to, r, &without, seeded);
      nodes_with += with.nodes;
      nodes_without += without.nodes;
      INFO("mesh " << m << " (kind " << kind << ") case " << i << ": size " << size << ", r " << r << ", height "
                   << height / r << " r; tree t " << tree.t << " (found " << tree.found() << "), without slabs t "
                   << plain.t << " (found " << plain.found() << ")");
      REQUIRE(tree.found() == plain.found());
      REQUIRE(tree.complete == plain.complete);
      if (tree.found()) {
        REQUIRE(tree.triangle == plain.triangle);
        REQUIRE(tree.t == plain.t);
      }
      // told a plane the move slides along (sweep_sphere's `slide`: the start face's normal, as the proxy's
      // slides give it, or any direction, of any length), the sweep passes by what lies out of the ball's
      // reach behind it and answers the same, bit for bit, through the tree and through the Neighbourhood
      const glm::dvec3 slide =
          i % 3 == 0 ? n
                     : (i % 3 == 1 ? 1.0 : 3.0 * unit() + 1e-3) *
                           glm::normalize(glm::dvec3{u(rng), u(rng), u(rng)} + glm::dvec3{0.0, 0.0, 1e-3});
      MeshBvh::Neighbourhood slide_near;
      for (MeshBvh::Neighbourhood* through : {static_cast<MeshBvh::Neighbourhood*>(nullptr), &slide_near}) {
        const BvhHit along = bvh.sweep_sphere(from, to, r, nullptr, seeded, through, &slide);
        INFO("with the slide plane " << (i % 3 == 0 ? "of the start face" : "at random") << ", |normal| "
                                     << glm::length(slide) << (through ? ", through a Neighbourhood" : "") << ": t "
                                     << along.t << " (found " << along.found() << ")");
        require_same_hit(along, tree);
      }
      // through the Neighbourhood: this sweep, then one from a little way off (inside the region it gathered)
      const glm::dvec3 nearby = from + 0.05 * r * glm::dvec3{u(rng), u(rng), u(rng)};
      for (const glm::dvec3& start_at : {from, nearby}) {
        const BvhHit& whole = start_at == from ? tree : bvh.sweep_sphere(start_at, to, r);
        const glm::dvec3 sweep_lo = glm::min(start_at, to) - glm::dvec3{r},
                         sweep_hi = glm::max(start_at, to) + glm::dvec3{r};
        const bool inside =
            near.gathered && near.fits && near.box.holds(BvhBox(sweep_lo, sweep_hi, glm::length(to - start_at)));
        const BvhHit local = bvh.sweep_sphere(start_at, to, r, nullptr, start_at == from ? seeded : BvhHit{}, &near);
        served += inside ? 1 : 0;
        INFO("through the Neighbourhood, from " << (start_at == from ? "the start" : "nearby") << ": t " << local.t
                                                << " (found " << local.found() << ", inside " << inside << ")");
        require_same_hit(local, whole);
      }
      ++compared;
      if (i % 15 != 2 || seeded.found()) continue;
      // the brute force: every triangle's own first contact (each with the whole move), the earliest; of
      // the triangles the tree holds (not those under 1e-12 of their longest edge across: no area)
      double first = 1.0;
      std::size_t met = mesh.triangles.size();
      for (std::size_t j = 0; j < mesh.triangles.size(); ++j) {
        const glm::dvec3 p = corner(mesh, j, 0), q = corner(mesh, j, 1), w = corner(mesh, j, 2);
        const double longest = std::fmax(glm::length(q - p), std::fmax(glm::length(w - q), glm::length(p - w)));
        if (!(glm::length(glm::cross(q - p, w - p)) > 1e-12 * longest * longest)) continue;
        double t = 1.0;
        glm::dvec3 contact{0.0};
        if (detail::sweep_ball_triangle(corner(mesh, j, 0), corner(mesh, j, 1) - corner(mesh, j, 0),
                                        corner(mesh, j, 2) - corner(mesh, j, 0), from, d, r, t, contact) &&
            (met == mesh.triangles.size() || t < first)) {
          first = t;
          met = j;
        }
      }
      const double until = tree.found() ? tree.t : 1.0;
      INFO("brute force t " << first << " (found " << (met < mesh.triangles.size()) << ")");
      if (met < mesh.triangles.size()) ++contacts;
      if (tree.found() == (met < mesh.triangles.size()) && (!tree.found() || tree.t == first)) {
        ++same;
        continue;
      }
      // a graze: a contact the brute force meets first is never entered up to where the tree stops, and
      // one the tree meets first is a real contact
      if (met < mesh.triangles.size() && until > first) {
        for (int k = 0; k <= 32; ++k)
          CHECK(distance_to(mesh, met, from + (first + (until - first) * k / 32.0) * d) >= r * (1.0 - 1e-9) - rounding);
      } else {
        REQUIRE(tree.found());
        CHECK(distance_to(mesh, tree.triangle, from + tree.t * d) <= r * (1.0 + 1e-9) + rounding);
      }
      ++grazing;
    }
  }
  INFO(compared << " sweeps compared (" << served << " more answered by a Neighbourhood alone), tree nodes "
                << nodes_with << " with the slabs, " << nodes_without << " without; against the brute force "
                << contacts << " contacts, equal in " << same << ", a graze in " << grazing);
  CHECK(compared > 30000);
  CHECK(served > compared / 10);  // the Neighbourhood answered alone that often
  CHECK(static_cast<double>(nodes_with) < 0.9 * static_cast<double>(nodes_without));  // the slabs skip nodes
  CHECK(contacts > 400);
  CHECK(grazing < same / 20);
}

TEST_CASE(
    "a tie (a ball met by several triangles at the very same t) goes to the seed, else to the lowest mesh index, "
    "whatever the order of the triangles and whether a Neighbourhood answers",
    "[radius]") {
  // A ball dropped straight onto a flat sheet's vertex or edge touches every
  // triangle around it at the same t (their faces' planes are one). The
  // oracle: every triangle's own contact, the earliest t, the lowest index
  // among those at it. The same sheet with its triangles in reverse order
  // names the other end of each tie, so an answer that hung on the order
  // the tree visits them would fail one of the two.
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TriangleMesh forward = test::flat_sheet(0.1, 40);
  forward.uvs.clear();
  TriangleMesh reversed = forward;
  std::reverse(reversed.triangles.begin(), reversed.triangles.end());
  int ties = 0, seeded_ties = 0;
  for (const TriangleMesh* mesh : {&forward, &reversed}) {
    const MeshBvh bvh = MeshBvh::build(*mesh);
    MeshBvh::Neighbourhood near;
    for (int i = 0; i < 400; ++i) {
      // a grid vertex, or the middle of an edge between two (0.0025 m apart)
      const double cell = 0.1 / 40;
      glm::dvec3 at{-0.05 + cell * static_cast<double>(rng() % 41), -0.05 + cell * static_cast<double>(rng() % 41),
                    0.0};
      if (i % 2) at.x = std::fmin(at.x + 0.5 * cell, 0.05 - 0.5 * cell);
      const double r = 0.0002 + 0.002 * u(rng);
      const glm::dvec3 from = at + glm::dvec3{0.0, 0.0, r + 0.001 * u(rng)}, to = at - glm::dvec3{0.0, 0.0, 0.001};
      double first = 2.0;
      std::vector<std::uint32_t> at_first;
      for (std::size_t j = 0; j < mesh->triangles.size(); ++j) {
        double t = 1.0;
        glm::dvec3 contact{0.0};
        const glm::dvec3 a = corner(*mesh, j, 0);
        if (!detail::sweep_ball_triangle(a, corner(*mesh, j, 1) - a, corner(*mesh, j, 2) - a, from, to - from, r, t,
                                         contact))
          continue;
        if (t < first) at_first.clear();
        if (t <= first) {
          first = t;
          at_first.push_back(static_cast<std::uint32_t>(j));
        }
      }
      REQUIRE(!at_first.empty());
      const std::uint32_t lowest = *std::min_element(at_first.begin(), at_first.end());
      ties += at_first.size() > 1 ? 1 : 0;
      INFO("case " << i << ": " << at_first.size() << " triangles at t " << first << ", the lowest " << lowest);
      const BvhHit tree = bvh.sweep_sphere(from, to, r),
                   local = bvh.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near);
      REQUIRE(tree.found());
      CHECK(tree.t == first);
      CHECK(tree.triangle == lowest);
      CHECK(local.triangle == lowest);
      // seeded with the highest of them: the seed keeps the tie
      const std::uint32_t highest = *std::max_element(at_first.begin(), at_first.end());
      BvhHit seed_hit;
      double t = 1.0;
      const glm::dvec3 a = corner(*mesh, highest, 0);
      REQUIRE(MeshBvh::touch_triangle(a, corner(*mesh, highest, 1) - a, corner(*mesh, highest, 2) - a, highest, from,
                                      to - from, r, t, seed_hit));
      CHECK(bvh.sweep_sphere(from, to, r, nullptr, seed_hit).triangle == highest);
      CHECK(bvh.sweep_sphere(from, to, r, nullptr, seed_hit, &near).triangle == highest);
      seeded_ties += at_first.size() > 1 ? 1 : 0;
    }
  }
  CHECK(ties > 600);  // (nearly) every drop is a tie of 2 to 6 triangles
  CHECK(seeded_ties == ties);
}

TEST_CASE("a Neighbourhood used with another tree, or after the tree's refit, is gathered again", "[radius]") {
  // A region gathered on one sheet, then asked of a sheet lifted 0.3 mm
  // (another tree) and of the first tree refit to the lifted sheet: each
  // answers as its own tree does (a stale region would miss the lifted
  // triangles or name the other tree's slots).
  const TriangleMesh sheet = test::wavy_sheet(0.05, 120, 0.002, 0.03);
  TriangleMesh lifted = sheet;
  for (glm::dvec3& p : lifted.positions)
    p.z += 0.0003;
  MeshBvh bvh = MeshBvh::build(sheet);
  const MeshBvh other = MeshBvh::build(lifted);
  const double r = 0.0005;
  const glm::dvec3 at{0.0075, 0.0075, 0.002};  // a crest of the sheet: level, 2 mm high
  const glm::dvec3 from = at + glm::dvec3{0.0, 0.0, r + 0.0004}, to = from - glm::dvec3{0.0, 0.0, 0.00015};
  MeshBvh::Neighbourhood near;
  const BvhHit first = bvh.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near);
  CHECK_FALSE(first.found());  // 0.4 mm over the sheet, moved down 0.15 mm
  REQUIRE(near.fits);
  const BvhHit on_other = other.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near),
               other_tree = other.sweep_sphere(from, to, r);
  REQUIRE(other_tree.found());  // the lifted sheet, 0.1 mm under the ball: met
  CHECK(on_other.triangle == other_tree.triangle);
  CHECK(on_other.t == other_tree.t);
  (void)bvh.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near);  // gathered on the first tree again
  bvh.refit(lifted);
  const BvhHit refit = bvh.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near),
               refit_tree = bvh.sweep_sphere(from, to, r);
  REQUIRE(refit_tree.found());
  CHECK(refit.triangle == refit_tree.triangle);
  CHECK(refit.t == refit_tree.t);
}

TEST_CASE("a ball's sweep up to its radius long gathers a region around it; a longer one walks the tree", "[radius]") {
  // A 0.5 mm ball 0.1 mm over a wavy sheet's crest slides level, each
  // sweep with a fresh Neighbourhood: up to bvh_neighbourhood_sweep radii
  // (a slip where static friction lets go) it gathers a region that holds
  // it, and answers as the tree does; past that it leaves the region
  // ungathered. Random directions, a new seed each run.
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const MeshBvh bvh = MeshBvh::build(test::wavy_sheet(0.05, 200, 0.002, 0.03));
  const double r = 0.0005;
  const glm::dvec3 from{0.0075, 0.0075, 0.002 + r + 0.0001};  // over a crest of the sheet: level, 2 mm high
  for (int i = 0; i < 200; ++i) {
    const double length = r * bvh_neighbourhood_sweep * (i % 2 == 0 ? 0.4 + 0.599 * u(rng) : 1.001 + u(rng));  // [m]
    const double angle = 2.0 * std::numbers::pi * u(rng);
    const glm::dvec3 to = from + length * glm::dvec3{std::cos(angle), std::sin(angle), 0.0};
    MeshBvh::Neighbourhood near;
    const BvhHit local = bvh.sweep_sphere(from, to, r, nullptr, BvhHit{}, &near);
    INFO("sweep " << i << ": " << length / r << " radii long, found " << local.found() << " at t " << local.t);
    require_same_hit(local, bvh.sweep_sphere(from, to, r));
    CHECK(near.gathered == (i % 2 == 0));
    if (i % 2 == 0) {
      CHECK(near.fits);
      CHECK(near.box.holds(BvhBox(glm::min(from, to) - glm::dvec3{r}, glm::max(from, to) + glm::dvec3{r}, length)));
    }
  }
}

TEST_CASE(
    "a ball proxy keeps its region of the tree from tick to tick: the same ticks bit for bit as a proxy whose "
    "sweeps all walk the tree",
    "[radius][invariant]") {
  // Presses and slides round a circle (26 mm/s to 1 m/s, random depths) of
  // 0.5 and 2 mm balls on fine wavy sheets (0.1 and 0.25 mm triangles: the
  // ball's region holds a few to a hundred leaves), an icosphere and a box.
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<TriangleMesh> meshes{test::wavy_sheet(0.04, 280, 0.002, 0.03),
                                         test::wavy_sheet(0.05, 140, 0.003, 0.02), test::icosphere(4, 0.03),
                                         test::box({-0.02, -0.02, -0.02}, {0.02, 0.02, 0.02}, 8)};
  long ticks = 0, touching = 0, fewer_nodes = 0;
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const MeshShape shape(meshes[m]);
    const bool sheet = m < 2;
    for (const double r : {0.0005, 0.002}) {
      ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
      config.radius = r;
      ProxyConstraint<MeshShape> kept(shape, config);
      ProxyConstraint<test::TreeWalk> walked(test::TreeWalk{shape}, config);
      for (int run = 0; run < 6; ++run) {
        kept.reset();
        walked.reset();
        const double angle = 2.0 * std::numbers::pi * u(rng), speed = 0.026 * std::pow(40.0, u(rng));  // [m/s]
        const glm::dvec3 top = sheet ? glm::dvec3{0.01 * (u(rng) - 0.5), 0.01 * (u(rng) - 0.5), 0.004}
                                     : glm::dvec3{0.005 * (u(rng) - 0.5), 0.005 * (u(rng) - 0.5), 0.04};
        const double depth = 0.006 + 0.004 * u(rng);  // how far under its start the HIP goes [m]
        for (int i = 0; i < 400; ++i) {
          // pressed in 100 ms, then round a circle of 4 mm radius at `speed`
          const double down = depth * std::fmin(1.0, i / 100.0);
          const double turned = angle + std::fmax(0.0, i - 100.0) * 1e-3 * speed / 0.004;  // [rad]
          const glm::dvec3 side{-std::sin(turned), std::cos(turned), 0.0};
          const glm::dvec3 hip = top - glm::dvec3{0.0, 0.0, (sheet ? 0.0 : 0.015) + down} +
                                 0.004 * glm::dvec3{std::cos(turned), std::sin(turned), 0.0};
          const Probe probe = probe_at(hip, (i < 100 ? 0.0 : speed) * side);
          const Contact a = kept.contact(probe), b = walked.contact(probe);
          INFO("mesh " << m << ", r " << r << ", run " << run << ", tick " << i);
          REQUIRE(a.touching == b.touching);
          REQUIRE(a.force == b.force);
          REQUIRE(a.primitive == b.primitive);
          REQUIRE(kept.proxy() == walked.proxy());
          REQUIRE(kept.last_path().count == walked.last_path().count);
          for (int q = 0; q < kept.last_path().count; ++q)
            REQUIRE(kept.last_path().points[static_cast<std::size_t>(q)] ==
                    walked.last_path().points[static_cast<std::size_t>(q)]);
          ++ticks;
          touching += a.touching ? 1 : 0;
          fewer_nodes += kept.last_tick().nodes < walked.last_tick().nodes ? 1 : 0;
        }
      }
    }
  }
  INFO(ticks << " ticks, " << touching << " touching, " << fewer_nodes << " with fewer nodes through the region");
  CHECK(touching > ticks / 2);
  CHECK(fewer_nodes > ticks / 10);  // the region answered
}

TEST_CASE("a node's slab never passes by a contact: two cases at the edge of rounding", "[radius]") {
  // a sliver 1e-9 of its length across lying in a turned sheet, in a leaf
  // with the sheet's triangles: the full test's face contact is off the
  // corners' plane by the sliver's rough normal (NodeBounds' tilt
  // allowance); and a sheet curved by 1e-10 of its size, whose sibling
  // nodes' normals are a few 1e-9 rad apart (merge()'s sine); each swept as
  // through the same tree without the slabs
  const auto same_without_slabs = [](const TriangleMesh& mesh, const glm::dvec3& from, const glm::dvec3& to, double r) {
    const MeshBvh bvh = MeshBvh::build(mesh);
    MeshBvh boxes_only = MeshBvh::build(mesh);
    boxes_only.refit(mesh);
    const BvhHit a = bvh.sweep_sphere(from, to, r), b = boxes_only.sweep_sphere(from, to, r);
    REQUIRE(b.found());
    CHECK(a.found());
    CHECK(a.triangle == b.triangle);
    CHECK(a.t == b.t);
  };
  {
    TriangleMesh mesh;
    mesh.positions = {{-0x1.7bbf50463bb2ep-10, -0x1.9ae0cff22786ep-9, -0x1.94637bb3f73p-8},
                      {0x1.fad4bf88fa38ap-10, -0x1.f7102675853cep-9, -0x1.4ef84b3c11c9fp-9},
                      {0x1.5c5a33d60c09p-8, -0x1.299fbe7c71797p-8, 0x1.15acc1df95984p-10},
                      {-0x1.bb4a07e79af5cp-9, 0x1.70bd5a0d76d7ep-11, -0x1.d9ceac2bdc961p-9},
                      {0x0p+0, 0x0p+0, 0x0p+0},
                      {0x1.bb4a07e79af5cp-9, -0x1.70bd5a0d76d7ep-11, 0x1.d9ceac2bdc961p-9},
                      {-0x1.5c5a33d60c09p-8, 0x1.299fbe7c71797p-8, -0x1.15acc1df95984p-10},
                      {-0x1.fad4bf88fa38ap-10, 0x1.f7102675853cep-9, 0x1.4ef84b3c11c9fp-9},
                      {0x1.7bbf50463bb2ep-10, 0x1.9ae0cff22786ep-9, 0x1.94637bb3f73p-8},
                      {-0x1.6f56f7d98f053p-10, 0x1.0089434aa0b8cp-10, -0x1.2c97c59e2dac2p-11},
                      {0x1.4936f01255dd2p-11, 0x1.23d41d59fa232p-11, 0x1.a245b898beaadp-10},
                      {-0x1.815f3f81cc578p-13, 0x1.7c537ab924feap-11, 0x1.7db08e8582934p-11}};
    mesh.triangles = {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4},  {3, 4, 7},
                      {3, 7, 6}, {4, 5, 8}, {4, 8, 7}, {9, 10, 11}};  // the sheet, then the sliver
    same_without_slabs(mesh, {0x1.bbc0c47973c3fp-12, 0x1.128856e0e44bfp-11, 0x1.86a85dde4c32bp-10},
                       {0x1.bbc0c700a4f27p-12, 0x1.12885823ad0cap-11, 0x1.86a85d6652665p-10}, 0x1.a36e2eb1c432dp-14);
  }
  {
    TriangleMesh mesh = test::wavy_sheet(0x1.fa9b6889276e7p-7, 45, 0x1.803656b3083f2p-35, 0x1.78a16d751deebp-8);
    const glm::dvec3 x{0x1.146a2547d1945p-1, -0x1.21ec799c7b799p-1, 0x1.3ee0c4ed31bb1p-1},
        y{-0x1.7bf2e37c9114bp-1, 0x1.dbd8545db22dfp-6, 0x1.56df73f3af975p-1},
        z{-0x1.96d4bee73705ap-2, -0x1.a5be316c80d9p-1, -0x1.9e3dd6f8c5bb9p-2};
    for (glm::dvec3& p : mesh.positions)
      p = p.x * x + p.y * y + p.z * z;  // turned
    same_without_slabs(mesh, {-0x1.5bcf079988a52p-14, -0x1.a9a10ba20979dp-11, 0x1.75bf70fd62793p-11},
                       {-0x1.a425305e88248p-15, -0x1.85eed4407f59ap-11, 0x1.874747df219a8p-11}, 0x1.5aaf1p-12);
  }
}

TEST_CASE(
    "the slide plane never passes by a contact: a small ball resting on a vertex of a coarse sheet, slid along its "
    "face",
    "[radius][invariant]") {
  // sweep_sphere's `slide` passes by a triangle whose corners all lie below
  // the plane a sliding ball cannot reach past, less a rounding margin. A
  // ball 1e-5 to 1e-2 of a sheet's size, resting exactly r above a corner of
  // one of its faces (the sheet flat but for rounding to float, 4 to 8
  // squares across, turned at random) and slid along that face, touches the
  // faces around the corner at t = 0: the corner lies on the plane to the
  // last bits. A margin taken from the ball's coordinates alone, where the
  // far corners of the triangles are far larger, passed such a face by and
  // named another (3-4 of 10 000 sweeps a run); the answer must be the
  // plain sweep's, bit for bit.
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto unit = [&] { return 0.5 + 0.5 * u(rng); };
  int compared = 0, at_once = 0;
  for (int m = 0; m < 40; ++m) {
    const double size = std::pow(10.0, -2.0 + 2.0 * unit());  // [m]
    TriangleMesh mesh = test::flat_sheet(size, 4 + static_cast<int>(rng() % 5));
    round_heights_to_float(mesh, size, rng, u);
    turn_and_move(mesh, random_turn(rng, u), glm::dvec3{0.0});
    const MeshBvh bvh = MeshBvh::build(mesh);
    for (std::size_t j = 0; j < mesh.triangles.size(); ++j) {
      const glm::dvec3 a = corner(mesh, j, 0);
      const glm::dvec3 n = glm::normalize(glm::cross(corner(mesh, j, 1) - a, corner(mesh, j, 2) - a));
      for (std::size_t k = 0; k < 3; ++k) {
        const double r = size * std::pow(10.0, -5.0 + 3.0 * unit());
        const glm::dvec3 from = corner(mesh, j, k) + r * n;
        glm::dvec3 d = r * std::pow(10.0, -3.0 + 3.0 * unit()) * glm::dvec3{u(rng), u(rng), u(rng)};
        d -= glm::dot(d, n) * n;  // along the face
        const BvhHit plain = bvh.sweep_sphere(from, from + d, r);
        const BvhHit along = bvh.sweep_sphere(from, from + d, r, nullptr, BvhHit{}, nullptr, &n);
        INFO("mesh " << m << ", triangle " << j << ", corner " << k << ": r " << r << " of a sheet " << size
                     << " across; plain t " << plain.t << " on " << plain.triangle << ", along the face t " << along.t
                     << " on " << along.triangle);
        require_same_hit(along, plain);
        ++compared;
        at_once += plain.found() && plain.t == 0.0;
      }
    }
  }
  INFO(compared << " sweeps, " << at_once << " touching at t = 0");
  CHECK(compared > 5000);
  CHECK(at_once > compared / 10);
}

TEST_CASE("a triangle's bounds never pass by a contact: the tree's sweep of one triangle equals the bare test",
          "[radius]") {
  // MeshBvh::TriangleBounds::may_touch skips a triangle before its full
  // test (sweep_ball_triangle): on random triangles of 10 um to 1 m (a
  // quarter of them slivers, 1e-12 to 1e-6 of their size across), as far as
  // 100 m from the origin, and balls swept past, along, into, behind and
  // grazing them, the tree over that one triangle must answer exactly as
  // the bare test does
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int contacts = 0, grazing = 0, slivers = 0;
  for (int i = 0; i < 60000; ++i) {
    const double size = std::pow(10.0, -5.0 + 5.0 * (0.5 + 0.5 * u(rng)));             // [m]
    const double far = i % 3 == 0 ? 0.0 : std::pow(10.0, 2.0 * (0.5 + 0.5 * u(rng)));  // [m]
    const glm::dvec3 origin = far * glm::dvec3{u(rng), u(rng), u(rng)};
    TriangleMesh mesh;
    for (int k = 0; k < 3; ++k)
      mesh.positions.push_back(origin + size * glm::dvec3{u(rng), u(rng), u(rng)});
    if (i % 4 == 0) {  // a sliver: its third corner 1e-12 to 1e-6 of the size off the line of the others
      const double off = std::pow(10.0, -12.0 + 6.0 * (0.5 + 0.5 * u(rng)));
      mesh.positions[2] = mesh.positions[0] + 0.7 * (mesh.positions[1] - mesh.positions[0]) +
                          off * size * glm::dvec3{u(rng), u(rng), u(rng)};
    }
    mesh.triangles.push_back({0, 1, 2});
    const glm::dvec3 a = mesh.positions[0], e1 = mesh.positions[1] - a, e2 = mesh.positions[2] - a;
    const glm::dvec3 cross = glm::cross(e1, e2);
    if (!(glm::length(cross) > 0.0)) continue;
    const glm::dvec3 n = glm::normalize(cross);
    const bool sliver = i % 4 == 0;
    // 1 % to 3x the triangle; by a sliver, 0.1 to 50 mm whatever its size [m]
    const double r = sliver ? std::pow(10.0, -4.0 + 2.7 * (0.5 + 0.5 * u(rng)))
                            : size * std::pow(10.0, -2.0 + 2.5 * (0.5 + 0.5 * u(rng)));
    // a start near the triangle: at r (resting), a little nearer or farther, or behind; a move along it, into it,
    // away from it or anywhere
    glm::dvec3 on =
        a + std::fabs(u(rng)) * e1 + std::fabs(u(rng)) * 0.5 * e2 + 0.3 * size * glm::dvec3{u(rng), u(rng), 0.0};
    double heights[] = {r, r * (1.0 + 1e-12), r * (1.0 - 1e-9), 0.5 * r, 2.0 * r, -0.5 * r};
    if (sliver) {  // over its line, resting within 1e-16 to 1e-6 r of r: grazing its long edges
      const glm::dvec3 middle = (a + mesh.positions[1] + mesh.positions[2]) / 3.0;
      on = middle + (0.75 * size * (0.5 + 0.5 * u(rng))) * glm::dvec3{u(rng), u(rng), u(rng)};
      on -= glm::dot(on - middle, n) * n;
      heights[i % 6] = r * (1.0 + (u(rng) < 0.0 ? -1.0 : 1.0) * std::pow(10.0, -16.0 + 10.0 * (0.5 + 0.5 * u(rng))));
    }
    const glm::dvec3 from = on + heights[i % 6] * n;
    glm::dvec3 d =
        (sliver ? std::pow(10.0, -6.0 + 5.0 * (0.5 + 0.5 * u(rng))) : size) * glm::dvec3{u(rng), u(rng), u(rng)};
    if (i % 4 == 0) d -= glm::dot(d, n) * n;                 // along the plane
    if (i % 4 == 1) d -= (std::fabs(u(rng)) * 3.0 * r) * n;  // into it
    const glm::dvec3 to = from + d;
    d = to - from;  // the move as the tree sees it
    const MeshBvh bvh = MeshBvh::build(mesh);
    if (bvh.triangle_count() == 0) continue;  // too thin for the tree: left out, never met
    const BvhHit tree = bvh.sweep_sphere(from, to, r);
    double t = 1.0;
    glm::dvec3 contact{0.0};
    const bool bare = detail::sweep_ball_triangle(a, e1, e2, from, d, r, t, contact);
    INFO("case " << i << ": size " << size << ", far " << far << ", r " << r);
    REQUIRE(tree.found() == bare);
    if (bare) {
      ++contacts;
      grazing += heights[i % 6] >= r;
      slivers += sliver;
      CHECK(tree.t == t);
    }
  }
  INFO(contacts << " contacts, " << grazing << " from a start r or more off the plane, " << slivers << " on slivers");
  CHECK(contacts > 6000);
  CHECK(grazing > 600);
  CHECK(slivers > 600);
}
