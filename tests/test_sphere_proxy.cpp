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
            if (p.x < 0.0 || p.y < 0.0 || p.x > extent || p.y > extent) continue;  // off the field: nothing there
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
    "a node's bounds never pass by a contact: a ball's sweep through the tree meets what a brute-force sweep over "
    "every triangle meets, on smooth and sharp meshes, built and refit",
    "[radius][invariant]") {
  // MeshBvh::NodeBounds::may_touch skips a whole subtree where the ball
  // stays clear of its slab: on wavy sheets (the smooth surfaces where it
  // skips most), spheres and boxes, of 1 mm to 1 m, up to 10 m from the
  // origin, balls resting on the surface (at r, within rounding of it, a
  // little nearer or farther), moved along it, into it, away or anywhere,
  // must meet what the brute force meets (every triangle's own first
  // contact, the earliest), or differ only where the ball grazes a face (its
  // distance r within rounding all along, the time of contact
  // ill-conditioned); and again after the tree is refit to the mesh deformed
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto unit = [&] { return 0.5 + 0.5 * u(rng); };
  int contacts = 0, same = 0, grazing = 0;
  for (int m = 0; m < 16; ++m) {
    const double size = std::pow(10.0, -3.0 + 3.0 * unit());  // [m]
    TriangleMesh mesh;
    if (m % 4 == 0 || m % 4 == 1)
      mesh = test::wavy_sheet(size, 12 + static_cast<int>(20 * unit()), size * 0.1 * unit(), size * (0.2 + unit()));
    else if (m % 4 == 2)
      mesh = test::icosphere(2 + m % 2, 0.5 * size);
    else
      mesh = test::box(glm::dvec3{0.0}, size * glm::dvec3{1.0, 0.5 + unit(), 0.2 + unit()}, 2 + m % 5);
    const glm::dvec3 shift = (m % 3 == 0 ? 10.0 * unit() : 0.0) * glm::dvec3{u(rng), u(rng), u(rng)};
    for (glm::dvec3& p : mesh.positions)
      p += shift;
    const double rounding = 64.0 * std::numeric_limits<double>::epsilon() * (glm::length(shift) + size);  // [m]
    MeshBvh bvh = MeshBvh::build(mesh);
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1) {  // deformed smoothly, the tree refit
        for (glm::dvec3& p : mesh.positions)
          p += 0.02 * size *
               glm::dvec3{std::sin(7.0 * p.y / size), std::cos(5.0 * p.x / size), std::sin(3.0 * p.x / size)};
        bvh.refit(mesh);
      }
      for (int i = 0; i < 150; ++i) {
        const auto& tri = mesh.triangles[static_cast<std::size_t>(rng() % mesh.triangles.size())];
        const glm::dvec3 a = mesh.positions[tri[0]], e1 = mesh.positions[tri[1]] - a, e2 = mesh.positions[tri[2]] - a;
        const glm::dvec3 n = glm::normalize(glm::cross(e1, e2));
        double b1 = unit(), b2 = unit();
        if (b1 + b2 > 1.0) {
          b1 = 1.0 - b1;
          b2 = 1.0 - b2;
        }
        const double r = size * std::pow(10.0, -3.0 + 2.5 * unit());
        const double heights[] = {r, r * (1.0 + 1e-12), r * (1.0 - 1e-9), 0.5 * r, 2.0 * r, r * (1.0 + 1e-6 * unit())};
        const double height = heights[i % 6];
        const glm::dvec3 from = a + b1 * e1 + b2 * e2 + height * n;
        glm::dvec3 d = 3.0 * r * glm::dvec3{u(rng), u(rng), u(rng)};
        if (i % 4 == 0) d -= glm::dot(d, n) * n;                 // along the face
        if (i % 4 == 1) d -= (std::fabs(u(rng)) * 2.0 * r) * n;  // into it
        if (i % 4 == 2) d += (std::fabs(u(rng)) * r) * n;        // away
        const glm::dvec3 to = from + d;
        d = to - from;  // the move as the tree sees it
        // the oracle: every triangle's own first contact (each with the whole move), the earliest
        double first = 1.0;
        std::size_t met = mesh.triangles.size();
        for (std::size_t j = 0; j < mesh.triangles.size(); ++j) {
          double t = 1.0;
          glm::dvec3 contact{0.0};
          if (detail::sweep_ball_triangle(corner(mesh, j, 0), corner(mesh, j, 1) - corner(mesh, j, 0),
                                          corner(mesh, j, 2) - corner(mesh, j, 0), from, d, r, t, contact) &&
              (met == mesh.triangles.size() || t < first)) {
            first = t;
            met = j;
          }
        }
        const BvhHit tree = bvh.sweep_sphere(from, to, r);
        const double until = tree.found() ? tree.t : 1.0;
        INFO("mesh " << m << " pass " << pass << " case " << i << ": size " << size << ", r " << r << ", height "
                     << height / r << " r; tree t " << until << " (found " << tree.found() << "), oracle t " << first
                     << " (found " << (met < mesh.triangles.size()) << ")");
        if (met < mesh.triangles.size()) ++contacts;
        if (tree.found() == (met < mesh.triangles.size()) && (!tree.found() || tree.t == first)) {
          ++same;
          continue;
        }
        // they differ only where the ball grazes (its distance r within rounding, the contact's time
        // ill-conditioned): a contact the oracle meets first is never entered up to where the tree stops,
        // and one the tree meets first is a real contact
        if (met < mesh.triangles.size() && until > first) {
          for (int k = 0; k <= 32; ++k)
            CHECK(distance_to(mesh, met, from + (first + (until - first) * k / 32.0) * d) >=
                  r * (1.0 - 1e-9) - rounding);
        } else {
          REQUIRE(tree.found());
          CHECK(distance_to(mesh, tree.triangle, from + tree.t * d) <= r * (1.0 + 1e-9) + rounding);
        }
        ++grazing;
      }
    }
  }
  INFO(contacts << " contacts; the tree and the oracle equal in " << same << " cases, a graze in " << grazing);
  CHECK(contacts > 1500);
  CHECK(grazing < same / 50);
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
