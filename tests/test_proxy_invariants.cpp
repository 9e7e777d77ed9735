// The proxy's invariants (docs/surfaces.md, "What the proxy guarantees"),
// each on thousands of random cases with a new seed every run (printed on
// failure; replay with --rng-seed N), on constructed meshes and on every real
// model in ../shared/data (skipped when the folder is absent):
//   (a) a press that crosses a front-facing triangle is always caught;
//   (b) the proxy never passes through the surface: every piece of its path
//       in a tick is clean against a brute-force scan (MeshChecker);
//   (c) a probe on the boundary (in a face's plane, on an edge or a vertex)
//       is not inside: no force beyond k times its distance into the solid
//       plus a tolerance relative to the triangle's size;
// and the query the proxy checks its contact with: closest() within a
// reach answers as a brute-force scan, and as the same tree without its
// nodes' slabs.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/proxy_check.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"
#if HAPTICFIELD_TEST_HAS_IO
#include "hapticfield/io/load_mesh.hpp"
#endif

using namespace hapticfield;
using test::probe_at;
using test::run_seed;

namespace {

constexpr double k = 1500.0;  // [N/m]

/// Scales the case counts: HAPTICFIELD_PROPERTY_SCALE (default 1).
double scale() {
  if (const char* s = std::getenv("HAPTICFIELD_PROPERTY_SCALE")) return std::max(0.01, std::atof(s));
  return 1.0;
}

struct Triangle {
  glm::dvec3 a, b, c, n;  ///< corners [m] and unit normal
  double size;            ///< longest edge [m]
};

Triangle triangle(const TriangleMesh& m, std::size_t i) {
  const auto& t = m.triangles[i];
  Triangle out{m.positions[t[0]], m.positions[t[1]], m.positions[t[2]], glm::dvec3{0.0}, 0.0};
  const glm::dvec3 n = glm::cross(out.b - out.a, out.c - out.a);
  out.size = std::fmax(glm::length(out.b - out.a), std::fmax(glm::length(out.c - out.b), glm::length(out.a - out.c)));
  out.n = glm::length(n) > 1e-12 * out.size * out.size ? glm::normalize(n) : glm::dvec3{0.0};
  return out;
}

/// Counts the triangles the segment a -> b crosses either way (plain
/// brute force over every triangle, no margin): the press's precondition.
int crossings(const TriangleMesh& m, const glm::dvec3& a, const glm::dvec3& b) {
  int count = 0;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const Triangle t = triangle(m, i);
    if (t.n == glm::dvec3{0.0}) continue;
    const double ha = glm::dot(a - t.a, t.n), hb = glm::dot(b - t.a, t.n);
    if ((ha > 0.0) == (hb > 0.0)) continue;
    const glm::dvec3 p = a + (ha / (ha - hb)) * (b - a);
    const glm::dvec3 e0 = t.b - t.a, e1 = t.c - t.a, q = p - t.a;
    const double d00 = glm::dot(e0, e0), d01 = glm::dot(e0, e1), d11 = glm::dot(e1, e1);
    const double det = d00 * d11 - d01 * d01;
    const double w1 = (d11 * glm::dot(q, e0) - d01 * glm::dot(q, e1)) / det;
    const double w2 = (d00 * glm::dot(q, e1) - d01 * glm::dot(q, e0)) / det;
    if (w1 >= -1e-6 && w2 >= -1e-6 && w1 + w2 <= 1.0 + 1e-6) ++count;
  }
  return count;
}

/// A uniformly random rotation (a normalised Gaussian quaternion).
glm::dmat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  double w = g(rng), x = g(rng), y = g(rng), z = g(rng);
  const double l = std::sqrt(w * w + x * x + y * y + z * z);
  w /= l, x /= l, y /= l, z /= l;
  return glm::dmat3{{1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)},
                    {2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)},
                    {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}};
}

TriangleMesh moved(TriangleMesh m, const glm::dmat3& r, const glm::dvec3& t) {
  for (auto& p : m.positions)
    p = r * p + t;
  if (!m.normals.empty())
    for (auto& n : m.normals)
      n = r * n;
  return m;
}

/// A closed star-shaped mesh: an icosphere with each vertex pushed radially
/// by a random factor in [1 - bump, 1 + bump].
TriangleMesh random_closed_mesh(std::mt19937& rng, double radius, double bump) {
  TriangleMesh m = test::icosphere(3, radius);
  std::uniform_real_distribution<double> u(1.0 - bump, 1.0 + bump);
  for (auto& p : m.positions)
    p *= u(rng);
  m.normals.clear();
  return m;
}

/// A slab of thickness h [m] (a box) and a fin (a wedge of base h): thin
/// parts the proxy must never pass.
TriangleMesh slab(double h) {
  return test::box({-0.02, -0.02, -h}, {0.02, 0.02, 0.0}, 4);
}

TriangleMesh wedge(double base, double height, double length) {
  // a triangular prism: the ridge along y at (0, ., height), the base on z = 0
  TriangleMesh m;
  const double b = base / 2;
  m.positions = {{-b, 0, 0}, {b, 0, 0}, {0, 0, height}, {-b, length, 0}, {b, length, 0}, {0, length, height}};
  m.triangles = {{0, 1, 2}, {3, 5, 4},   // ends (-y, +y)
                 {0, 4, 1}, {0, 3, 4},   // base (-z)
                 {1, 5, 2}, {1, 4, 5},   // right slope
                 {0, 5, 3}, {0, 2, 5}};  // left slope
  return m;
}

/// A regular tetrahedron and an octahedron (convex, outward).
TriangleMesh tetrahedron(double s) {
  TriangleMesh m;
  m.positions = {{s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return m;
}
TriangleMesh octahedron(double s) {
  TriangleMesh m;
  m.positions = {{s, 0, 0}, {-s, 0, 0}, {0, s, 0}, {0, -s, 0}, {0, 0, s}, {0, 0, -s}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

/// Presses `count` random front-facing triangles (every one when count is
/// 0) at random interior points along their inward normal, 0.05 to 0.2 mm a
/// tick from 2.5 mm outside to 5 mm inside (scaled with the triangle for
/// small ones), each with a fresh proxy; the straight path must cross that
/// triangle and no other (checked by brute force first, else skipped).
/// Returns {pressed, missed}; every tick's path is checked too.
std::array<int, 2> press_all(const TriangleMesh& mesh, std::mt19937& rng, int count, const std::string& name) {
  const MeshShape shape(mesh);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::size_t> order(mesh.triangles.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  if (count > 0) {
    std::shuffle(order.begin(), order.end(), rng);
    order.resize(std::min<std::size_t>(order.size(), static_cast<std::size_t>(count)));
  }
  int pressed = 0, missed = 0, crossed = 0;
  const MeshChecker checker(mesh);
  for (const std::size_t i : order) {
    const Triangle t = triangle(mesh, i);
    if (t.n == glm::dvec3{0.0}) continue;
    double w1 = u(rng), w2 = u(rng);
    if (w1 + w2 > 1.0) w1 = 1.0 - w1, w2 = 1.0 - w2;
    w1 = 0.02 + 0.96 * w1, w2 = 0.02 + 0.96 * w2;  // inside, off the edges (ties are (c)'s)
    if (w1 + w2 > 0.98) continue;
    const glm::dvec3 point = t.a + w1 * (t.b - t.a) + w2 * (t.c - t.a);
    const double out = std::fmin(0.0025, 0.5 * t.size), in = std::fmin(0.005, t.size);
    const glm::dvec3 from = point + out * t.n, to = point - in * t.n;
    if (crossings(mesh, from, to) != 1) continue;  // the path must cross this triangle and no other
    ++pressed;
    const double step = (5e-5 + 1.5e-4 * u(rng)) * std::fmin(1.0, t.size / 0.005);
    ProxyConstraint proxy(shape, ProxyConfig{k});
    bool caught = false;
    const int ticks = static_cast<int>(std::ceil((out + in) / step));
    for (int j = 0; j <= ticks; ++j) {
      const glm::dvec3 hip = from - std::fmin(out + in, j * step) * t.n;
      const Contact c = proxy.contact(probe_at(hip, -step * 1e3 * t.n));
      caught = caught || c.touching;
      if (checker.check(proxy.last_path()).found()) ++crossed;
    }
    // caught, and at the end the proxy is on the pressed face's side
    const bool front = glm::dot(proxy.proxy() - t.a, t.n) > -1e-9 * t.size;
    if (!caught || !front) {
      ++missed;
      UNSCOPED_INFO(name << ": triangle " << i << " pressed at " << w1 << ", " << w2 << " step " << step << " caught "
                         << caught << " proxy in front " << front);
    }
  }
  CHECK(crossed == 0);
  return {pressed, missed};
}

/// Where a slide starts: a random triangle, a random point of it and a
/// random direction in its plane (found false: a triangle with no area).
struct SlideStart {
  std::size_t index{0};
  Triangle t{};
  glm::dvec3 point{0.0}, dir{0.0};
  bool found{false};
};

SlideStart slide_start(const TriangleMesh& mesh, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g;
  SlideStart out;
  out.index = rng() % mesh.triangles.size();
  out.t = triangle(mesh, out.index);
  if (out.t.n == glm::dvec3{0.0}) return out;
  double w1 = u(rng), w2 = u(rng);
  if (w1 + w2 > 1.0) w1 = 1.0 - w1, w2 = 1.0 - w2;
  out.point = out.t.a + w1 * (out.t.b - out.t.a) + w2 * (out.t.c - out.t.a);
  const glm::dvec3 dir{g(rng), g(rng), g(rng)};
  out.dir = glm::normalize(dir - glm::dot(dir, out.t.n) * out.t.n);
  out.found = true;
  return out;
}

/// Slides: pressed 1 mm deep at a random interior point, then along a
/// random tangent direction at `speed` [m/s] for `ticks` ticks at 1 kHz.
/// Returns {slides, ticks whose path crossed the surface}.
std::array<long, 2> slide_all(const TriangleMesh& mesh, std::mt19937& rng, int count, double speed, int ticks,
                              const std::string& name, double friction = 0.0) {
  ProxyConfig config{k};
  config.static_friction = friction;
  config.dynamic_friction = 0.75 * friction;
  CheckedProxy checked(ProxyConstraint(MeshShape(mesh), config), mesh);
  long slides = 0;
  for (int s = 0; s < count; ++s) {
    const SlideStart start = slide_start(mesh, rng);
    if (!start.found) continue;
    const std::size_t i = start.index;
    const Triangle& t = start.t;
    const glm::dvec3 point = start.point, dir = start.dir;
    checked.reset();
    ++slides;
    for (int j = 0; j < 10 + ticks; ++j) {
      const double press = std::fmin(1.0, j / 10.0);  // 2 mm out to 1 mm in over 10 ticks
      const glm::dvec3 hip = point + (0.002 - 0.003 * press) * t.n + std::fmax(0, j - 10) * 1e-3 * speed * dir;
      (void)checked.contact(probe_at(hip, speed * dir));
      if (checked.violations() > 0) break;
    }
    if (checked.violations() > 0) {
      const PathCrossing& c = checked.first_violation();
      UNSCOPED_INFO(name << ": slide " << s << " from triangle " << i << " crossed triangle " << c.triangle
                         << " on piece " << c.piece << " from (" << c.from.x << ", " << c.from.y << ", " << c.from.z
                         << ") to (" << c.to.x << ", " << c.to.y << ", " << c.to.z << ")");
      const ProxyPath& path = checked.proxy().last_path();
      for (int q = 0; q < path.count; ++q)
        UNSCOPED_INFO("  path " << q << ": (" << path.points[q].x << ", " << path.points[q].y << ", "
                                << path.points[q].z << ")");
      UNSCOPED_INFO("  moves " << checked.proxy().last_tick().moves << " planes " << checked.proxy().last_tick().planes
                               << " sliding " << checked.proxy().last_tick().sliding);
      return {slides, static_cast<long>(checked.violations())};
    }
  }
  return {slides, 0};
}

struct Model {
  std::string name;
  TriangleMesh mesh;
  bool small;  ///< press every triangle
};

/// Every real model in ../shared/data that this build can read, fitted to
/// a 0.2 m diagonal; glTF models also in their own units (metres).
std::vector<Model> real_models() {
  std::vector<Model> out;
#if HAPTICFIELD_TEST_HAS_IO
  const std::filesystem::path data = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  if (!std::filesystem::is_directory(data)) return out;
  for (const char* name :
       {"gltf/Duck.gltf", "gltf/OrientationTest.gltf", "gltf/Box.gltf", "gltf/BoxTextured.gltf", "meshes/spot.obj",
        "meshes/teapot.obj", "meshes/fandisk.obj", "meshes/rocker-arm.obj", "meshes/stanford-bunny.obj"}) {
    const std::filesystem::path p = data / name;
    if (!std::filesystem::exists(p)) continue;
    TriangleMesh m = io::load_mesh(p.string()).mesh;
    const bool small = m.triangles.size() <= 7000;
    if (p.extension() == ".gltf") out.push_back({std::string(name) + " (own units)", m, small});
    out.push_back({std::string(name) + " (0.2 m)", test::fitted(m), small});
  }
#endif
  return out;
}

bool real_data_absent() {
  const std::filesystem::path data = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  return !std::filesystem::is_directory(data);
}

}  // namespace

TEST_CASE("(a) presses: every press through a front-facing triangle of a constructed mesh is caught", "[invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::vector<Model> models = {
      {"random closed mesh", random_closed_mesh(rng, 0.04, 0.15), true},
      {"box", test::box({-0.01, -0.01, -0.01}, {0.01, 0.01, 0.01}, 3), true},
      {"0.1 mm slab", slab(1e-4), true},
      {"0.1 mm fin", wedge(1e-4, 0.02, 0.03), true},
      {"wedge", wedge(0.02, 0.01, 0.03), true},
      {"flat sheet", test::flat_sheet(0.05, 24), true},
  };
  for (Model& m : models) {
    m.mesh = moved(m.mesh, random_rotation(rng), glm::dvec3{0.01, -0.02, 0.03});
    const auto [pressed, missed] = press_all(m.mesh, rng, 0, m.name);
    INFO(m.name << ": " << missed << " missed of " << pressed);
    CHECK(pressed > 0);
    CHECK(missed == 0);
  }
}

TEST_CASE("(b) slides at 26 mm/s and 2 m/s never cross the surface: constructed and random closed meshes",
          "[invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  const std::vector<Model> models = {
      {"random closed mesh", random_closed_mesh(rng, 0.04, 0.15), true},
      {"random closed mesh, rough", random_closed_mesh(rng, 0.02, 0.4), true},
      {"0.1 mm slab", slab(1e-4), true},
      {"0.1 mm fin", wedge(1e-4, 0.02, 0.03), true},
      {"cube", test::box({-0.01, -0.01, -0.01}, {0.01, 0.01, 0.01}, 1), true},
  };
  for (const Model& m : models)
    for (const double speed : {0.026, 2.0})
      for (const double mu : {0.0, 0.5}) {
        const auto [slides, crossed] =
            slide_all(m.mesh, rng, static_cast<int>(300 * scale()), speed, speed < 1.0 ? 300 : 50, m.name, mu);
        INFO(m.name << " at " << speed << " m/s, mu " << mu << ": " << crossed << " crossings in " << slides
                    << " slides");
        CHECK(crossed == 0);
      }
}

TEST_CASE(
    "(a) and (b) on every real model: each small model's triangles and thousands of the large ones pressed, "
    "hundreds of slides at 26 mm/s and 2 m/s",
    "[invariant][real]") {
  if (real_data_absent()) {
    WARN("skipped: ../shared/data is absent");
    return;
  }
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  SECTION("presses are caught") {
    for (const Model& m : real_models()) {
      const auto [pressed, missed] = press_all(m.mesh, rng, m.small ? 0 : static_cast<int>(2000 * scale()), m.name);
      INFO(m.name << ": " << missed << " missed of " << pressed);
      CHECK(pressed > 0);
      CHECK(missed == 0);
    }
  }
  SECTION("slides never cross the surface") {
    for (const Model& m : real_models())
      for (const double speed : {0.026, 2.0}) {
        const auto [slides, crossed] =
            slide_all(m.mesh, rng, static_cast<int>(200 * scale()), speed, speed < 1.0 ? 200 : 50, m.name);
        INFO(m.name << " at " << speed << " m/s: " << crossed << " crossings in " << slides << " slides");
        CHECK(crossed == 0);
      }
  }
}

/// Slides of a ball-shaped tool (ProxyConfig::radius): along every piece
/// of every tick's path its centre never comes within r of a triangle it
/// was clear of (MeshChecker::entered, brute force over the nearby
/// triangles, every r / 8). Returns {ticks touching, the nearest such
/// distance / r (infinity: none)}.
std::array<double, 2> ball_slides(const TriangleMesh& mesh, std::mt19937& rng, int count, double r) {
  const MeshChecker checker(mesh);
  // half the slides with friction: a proxy that sticks, or slides and settles, first (ProxyConfig::stick_first)
  const MeshShape shape(mesh);
  ProxyConstraint smooth(shape, ProxyConfig{.stiffness = k, .radius = r});
  ProxyConstraint rough(shape,
                        ProxyConfig{.stiffness = k, .static_friction = 0.6, .dynamic_friction = 0.45, .radius = r});
  double nearest = std::numeric_limits<double>::infinity();
  double touching = 0.0;
  for (int s = 0; s < count; ++s) {
    const SlideStart start = slide_start(mesh, rng);
    if (!start.found) continue;
    const Triangle& t = start.t;
    const glm::dvec3 point = start.point, dir = start.dir;
    const double speed = s % 2 ? 2.0 : 0.026;
    auto& proxy = s % 4 < 2 ? smooth : rough;
    proxy.reset();
    for (int j = 0; j < 110; ++j) {  // from r + 2 mm out to 1 mm deep over 10 ticks, then along
      const double press = std::fmin(1.0, j / 10.0);
      const glm::dvec3 hip = point + (r + 0.002 - 0.003 * press) * t.n + std::fmax(0, j - 10) * 1e-3 * speed * dir;
      touching += proxy.contact(probe_at(hip, speed * dir)).touching ? 1.0 : 0.0;
      // a start within r of another part of the model: that ball is free until clear (ProxyTick::embedded), no slide
      if (j == 0 && proxy.last_tick().embedded) break;
      const ProxyPath& path = proxy.last_path();
      for (int q = 0; q + 1 < path.count; ++q)
        nearest = std::fmin(nearest, checker.entered(path.points[static_cast<std::size_t>(q)],
                                                     path.points[static_cast<std::size_t>(q + 1)], r));
    }
  }
  return {touching, nearest / r};
}

TEST_CASE("(b) with a ball-shaped tool: its centre stays r from every real model and the thin parts", "[invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::vector<Model> models = {{"0.1 mm slab", slab(1e-4), true}, {"0.1 mm fin", wedge(1e-4, 0.02, 0.03), true}};
  for (Model& m : real_models())
    if (m.name.find("(0.2 m)") != std::string::npos) models.push_back(std::move(m));
  for (const Model& m : models)
    for (const double r : {0.0005, 0.002}) {
      const auto [touching, nearest] = ball_slides(m.mesh, rng, static_cast<int>(60 * scale()), r);
      INFO(m.name << ", r " << r << ": nearest " << nearest << " r over " << touching << " touching ticks");
      CHECK(touching > 0.0);
      CHECK(nearest >= 1.0 - 1e-6);  // infinity: no triangle's reach entered
    }
}

TEST_CASE(
    "(c) a probe (a point, or a ball r out) moving on the boundary of a convex solid is not inside: no force beyond "
    "k x tolerance",
    "[invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g;
  const std::vector<Model> solids = {{"cube", test::box({-0.01, -0.01, -0.01}, {0.01, 0.01, 0.01}, 1), true},
                                     {"finely cut cube", test::box({-0.01, -0.01, -0.01}, {0.01, 0.01, 0.01}, 3), true},
                                     {"wedge", wedge(0.02, 0.01, 0.03), true},
                                     {"tetrahedron", tetrahedron(0.01), true},
                                     {"octahedron", octahedron(0.012), true}};
  const int cases = static_cast<int>(400 * scale());
  for (const Model& solid : solids) {
    int worst_case = -1;
    double worst = 0.0;
    for (int c = 0; c < cases; ++c) {
      const glm::dmat3 r = random_rotation(rng);
      const glm::dvec3 shift{0.05 * (u(rng) - 0.5), 0.05 * (u(rng) - 0.5), 0.05 * (u(rng) - 0.5)};
      const double s = 0.5 + u(rng);  // 5 to 30 mm solids
      TriangleMesh mesh = solid.mesh;
      for (auto& p : mesh.positions)
        p = r * (s * p) + shift;
      // a supporting line: through a random vertex (or a point of a random
      // edge, or of a face) in a plane whose normal lies in that feature's
      // normal cone, so it never enters the convex solid
      const std::size_t ti = rng() % mesh.triangles.size();
      const Triangle t = triangle(mesh, ti);
      const int kind = static_cast<int>(rng() % 3);  // 0: vertex, 1: edge, 2: face
      glm::dvec3 point = t.a, normal = t.n;
      double size = t.size;
      // the normals of every face through the feature
      std::vector<glm::dvec3> cone;
      const auto on_plane = [](const Triangle& f, const glm::dvec3& p) {
        return std::fabs(glm::dot(p - f.a, f.n)) <= 1e-12 * f.size;
      };
      if (kind == 1) point = t.a + u(rng) * (t.b - t.a);
      if (kind == 2) point = t.a + 0.3 * (t.b - t.a) + 0.3 * (t.c - t.a);
      for (std::size_t j = 0; j < mesh.triangles.size(); ++j) {
        const Triangle f = triangle(mesh, j);
        if (f.n != glm::dvec3{0.0} && on_plane(f, point)) cone.push_back(f.n);
      }
      normal = glm::dvec3{0.0};
      for (const glm::dvec3& n : cone)
        normal += u(rng) * n;
      if (kind == 2 || glm::length(normal) < 1e-3) normal = t.n;
      normal = glm::normalize(normal);
      glm::dvec3 dir{g(rng), g(rng), g(rng)};
      if (kind == 1 && u(rng) < 0.5) dir = t.b - t.a;  // along the edge itself
      dir = glm::normalize(dir - glm::dot(dir, normal) * normal);
      // from 15 mm before the feature to 15 mm past it, 0.1 mm a tick: a
      // point on the line, and a ball on the line moved r out along the
      // plane's normal (its centre r from the solid, or farther)
      const double tolerance = 1e-5 * size;  // [m]: ten times the proxy's offset
      for (const double r : {0.0, c % 2 ? 0.0005 : 0.002}) {
        ProxyConstraint proxy(MeshShape(mesh), ProxyConfig{.stiffness = k, .radius = r});
        for (int j = 0; j <= 300; ++j) {
          const glm::dvec3 hip = point + r * normal + (-0.015 + 1e-4 * j) * dir;
          const double f = glm::length(proxy.contact(probe_at(hip, 0.1 * dir)).force);
          if (f > k * tolerance && f > worst) {
            worst = f;
            worst_case = c;
            UNSCOPED_INFO(solid.name << " case " << c << " feature " << kind << " radius " << r << " tick " << j
                                     << ": |F| " << f << " N on the boundary");
          }
        }
      }
    }
    INFO(solid.name << ": worst |F| " << worst << " N in case " << worst_case);
    CHECK(worst_case == -1);
  }
}

TEST_CASE("regressions: the cube's side plane, vertical edge and top-front edge at k = 800 and 1500 N/m",
          "[invariant]") {
  // a 20 mm cube; the probe moves down exactly in the plane x = 0 of a side
  // face, along the vertical edge x = y = 0, and along the top-front edge's
  // plane y = 0: on the boundary throughout, it must feel nothing
  const TriangleMesh cube = test::box({0, 0, 0}, {0.02, 0.02, 0.02});
  for (const double stiffness : {800.0, 1500.0})
    for (const glm::dvec3 line : {glm::dvec3{0.0, 0.01, 0.0}, glm::dvec3{0.0, 0.0, 0.0}, glm::dvec3{0.01, 0.0, 0.0}}) {
      ProxyConstraint proxy(MeshShape(cube), ProxyConfig{stiffness});
      double worst = 0.0;
      for (int i = 0; i <= 400; ++i) {
        const glm::dvec3 hip = line + glm::dvec3{0.0, 0.0, 0.03 - 1e-4 * i};
        worst = std::fmax(worst, glm::length(proxy.contact(probe_at(hip, {0, 0, -0.1})).force));
      }
      INFO("k " << stiffness << " line (" << line.x << ", " << line.y << ")");
      CHECK(worst <= stiffness * 1e-7);
      // 1 um inside the side face (x = 1e-6): caught on the top as a god-object must be
      ProxyConstraint inside(MeshShape(cube), ProxyConfig{stiffness});
      double deepest = 0.0;
      for (int i = 0; i <= 400; ++i) {
        const glm::dvec3 hip = line + glm::dvec3{1e-6, 1e-6, 0.03 - 1e-4 * i};
        deepest = std::fmax(deepest, glm::length(inside.contact(probe_at(hip, {0, 0, -0.1})).force));
      }
      CHECK(deepest > stiffness * 0.02);  // held on the top face, 30 mm above the HIP at the end
    }
}

TEST_CASE("regressions: the bunny's ear slide slips off the rim along the surface; Duck's triangle 22 is caught",
          "[invariant][real]") {
  if (real_data_absent()) {
    WARN("skipped: ../shared/data is absent");
    return;
  }
#if HAPTICFIELD_TEST_HAS_IO
  const std::filesystem::path data = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  {
    const TriangleMesh bunny = with_vertex_normals(io::load_mesh((data / "meshes/stanford-bunny.obj").string()).mesh);
    CheckedProxy checked(ProxyConstraint(MeshShape(bunny), ProxyConfig{}), bunny);
    double longest = 0.0;
    for (int i = 0; i < 500; ++i) {
      const double t = i * 1e-3;
      const glm::dvec3 before = checked.proxy().proxy();
      (void)checked.contact(probe_at({-0.03, 0.170 - 0.026 * t, 0.0}, {0.0, -0.026, 0.0}));
      if (i > 0) longest = std::fmax(longest, glm::length(checked.proxy().proxy() - before));
    }
    INFO("the longest one-tick move " << longest * 1e3 << " mm");
    CHECK(longest > 1e-3);             // the slip off the ear's rim happens (2.86 mm at t = 0.498 s)
    CHECK(checked.violations() == 0);  // and every piece of it follows the surface
  }
  {
    const TriangleMesh duck = io::load_mesh((data / "gltf/Duck.gltf").string()).mesh;
    const Triangle t = triangle(duck, 22);
    const glm::dvec3 centre = (t.a + t.b + t.c) / 3.0;
    ProxyConstraint proxy(MeshShape(duck), ProxyConfig{});
    bool caught = false;
    for (int i = 0; i * 1.9e-4 <= 0.0075; ++i)
      caught = proxy.contact(probe_at(centre + (0.0025 - i * 1.9e-4) * t.n, -0.19 * t.n)).touching || caught;
    CHECK(caught);
  }
#endif
}

TEST_CASE("checked mode: MeshChecker finds a piece that passes through a face, and the proxy's path is recorded",
          "[invariant]") {
  // the oracle must be able to fail: a segment through a box's top is caught,
  // one along it and one from behind are not
  const TriangleMesh cube = test::box({0, 0, 0}, {0.02, 0.02, 0.02}, 2);
  const MeshChecker checker(cube);
  CHECK(checker.crossing({0.011, 0.013, 0.03}, {0.011, 0.013, 0.01}).found());
  CHECK_FALSE(checker.crossing({0.0, 0.013, 0.03}, {0.0, 0.013, 0.01}).found());     // in the side's plane: a tie
  CHECK_FALSE(checker.crossing({0.01, 0.013, 0.01}, {0.01, 0.013, 0.03}).found());   // from inside out
  CHECK_FALSE(checker.crossing({0.01, 0.013, 0.03}, {0.01, 0.013, 0.025}).found());  // above it
  ProxyConstraint proxy(MeshShape(cube), ProxyConfig{});
  (void)proxy.contact(probe_at({0.011, 0.012, 0.03}));
  (void)proxy.contact(probe_at({0.011, 0.012, 0.015}));
  const ProxyPath& path = proxy.last_path();
  REQUIRE(path.count >= 2);
  CHECK(path.points[0] == glm::dvec3{0.011, 0.012, 0.03});
  CHECK(path.points[static_cast<std::size_t>(path.count - 1)] == proxy.proxy());
  CHECK(proxy.proxy().z > 0.02);
  CHECK_FALSE(checker.check(path).found());
  // a path that cut through is reported with its piece
  ProxyPath cut;
  cut.points[0] = {0.011, 0.012, 0.03};
  cut.points[1] = {0.011, 0.012, 0.021};
  cut.points[2] = {0.011, 0.012, 0.015};
  cut.count = 3;
  const PathCrossing c = checker.check(cut);
  REQUIRE(c.found());
  CHECK(c.piece == 1);
}

TEST_CASE("a non-finite velocity keeps Fc and drops only the damping", "[invariant]") {
  const TriangleMesh cube = test::box({0, 0, 0}, {0.02, 0.02, 0.02});
  ProxyConfig config{k};
  config.damping = 5.0;
  ProxyConstraint proxy(MeshShape(cube), config);
  (void)proxy.contact(probe_at({0.01, 0.01, 0.025}));
  const Contact c = proxy.contact(probe_at({0.01, 0.01, 0.018}, {0.0, 0.0, std::nan("")}));
  REQUIRE(c.touching);
  CHECK(c.force.z == Approx(k * 0.002).epsilon(1e-6));
  const Contact d = proxy.contact(probe_at({0.01, 0.01, 0.018}, {0.0, 0.0, -HUGE_VAL}));
  CHECK(d.force.z == Approx(k * 0.002).epsilon(1e-6));
}

TEST_CASE("the constructed solids are outward: a positive volume by the divergence theorem", "[invariant]") {
  std::mt19937 rng(7);
  for (const TriangleMesh& m : {wedge(0.02, 0.01, 0.03), wedge(1e-4, 0.02, 0.03), tetrahedron(0.01), octahedron(0.012),
                                random_closed_mesh(rng, 0.04, 0.15)}) {
    double volume = 0.0;  // divergence theorem: sum of a . (b x c) / 6
    for (const auto& t : m.triangles)
      volume += glm::dot(m.positions[t[0]], glm::cross(m.positions[t[1]], m.positions[t[2]])) / 6.0;
    CHECK(volume > 0.0);
  }
}

TEST_CASE(
    "closest within a reach (a ball's nearest): the tree with its nodes' slabs, without them and through a ball's "
    "Neighbourhood answer as a brute-force scan, bit for bit (the lowest mesh index of the nearest), on constructed "
    "meshes and every real model",
    "[invariant]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Model> models = {
      {"wavy sheet", test::wavy_sheet(0.1, 120, 0.002, 0.03), true},
      {"icosphere", test::icosphere(3, 0.02), true},
      {"0.1 mm slab", slab(1e-4), true},
      {"20 mm cube (ties at every edge and corner)", test::box({0, 0, 0}, {0.02, 0.02, 0.02}), true}};
  for (Model& m : real_models())
    models.push_back(std::move(m));
  const auto same = [](const BvhHit& a, const BvhHit& b) {
    return a.found() == b.found() && (!a.found() || (a.triangle == b.triangle && a.point == b.point &&
                                                     a.distance == b.distance && a.b1 == b.b1 && a.b2 == b.b2));
  };
  for (const Model& m : models) {
    const MeshBvh tree = MeshBvh::build(m.mesh);
    MeshBvh boxes = MeshBvh::build(m.mesh);
    boxes.refit(m.mesh);  // the same tree with its nodes' slabs dropped: boxes alone prune
    const std::size_t n = m.mesh.triangles.size();
    double edge = 0.0;  // the mean longest edge [m]
    for (std::size_t i = 0; i < n; ++i)
      edge += triangle(m.mesh, i).size / static_cast<double>(n);
    const int cases = static_cast<int>(2000 * scale());
    const int brute_every = m.small ? 4 : 40;  // the brute-force scan on a share of the queries
    int found = 0, scanned = 0, served = 0, ties = 0;
    for (int i = 0; i < cases; ++i) {
      const Triangle t = triangle(m.mesh, rng() % n);
      if (t.n == glm::dvec3{0.0}) continue;
      double b1 = u(rng), b2 = u(rng);
      if (b1 + b2 > 1.0) {
        b1 = 1.0 - b1;
        b2 = 1.0 - b2;
      }
      // a ball's reach of a quarter to eight edges, from under the surface to well above it
      const double reach = edge * (0.25 + 8.0 * u(rng) * u(rng));  // [m]
      glm::dvec3 p = t.a + b1 * (t.b - t.a) + b2 * (t.c - t.a) + (2.0 * u(rng) - 0.5) * reach * t.n;
      if (i % 8 == 0) p = (i % 16 == 0) ? t.a : 0.5 * (t.a + t.b);  // on a corner or an edge: ties
      const BvhHit a = tree.closest(p, reach), b = boxes.closest(p, reach);
      INFO(m.name << ", query " << i << ", reach " << reach);
      REQUIRE(same(a, b));
      found += a.found() ? 1 : 0;
      // through a region gathered by a short sweep of a ball of that reach
      // from a little way off: its leaves answer where p's reach lies inside
      MeshBvh::Neighbourhood near;
      const glm::dvec3 off{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
      const glm::dvec3 from = p + 0.6 * reach * off;
      (void)tree.sweep_sphere(from, from + 0.1 * reach * t.n, reach, nullptr, BvhHit{}, &near);
      const BvhHit c = tree.closest(p, reach, nullptr, &near);
      REQUIRE(same(a, c));
      const glm::dvec3 around{reach};
      served += near.fits && near.box.holds(BvhBox(p - around, p + around)) ? 1 : 0;
      if (i % brute_every != 0) continue;
      ++scanned;
      // the oracle: every triangle with area (the tree's), the least squared
      // distance, and of those at it the lowest mesh index
      double least = reach * reach;  // [m^2]
      std::uint32_t lowest = no_primitive;
      int at_least = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (triangle(m.mesh, j).n == glm::dvec3{0.0}) continue;
        const auto& tri = m.mesh.triangles[j];
        const glm::dvec3 v = m.mesh.positions[tri[0]];
        double w1 = 0.0, w2 = 0.0;
        const glm::dvec3 q =
            detail::closest_on_triangle(p, v, m.mesh.positions[tri[1]] - v, m.mesh.positions[tri[2]] - v, w1, w2);
        const double d2 = glm::dot(q - p, q - p);
        if (d2 < least || (d2 == least && lowest == no_primitive)) {
          least = d2;
          lowest = static_cast<std::uint32_t>(j);
          at_least = 1;
        } else if (d2 == least) {
          ++at_least;  // j > lowest: the first met keeps it
        }
      }
      REQUIRE(a.found() == (lowest != no_primitive));
      if (!a.found()) continue;
      REQUIRE(a.triangle == lowest);
      REQUIRE(a.distance == std::sqrt(least));
      ties += at_least > 1 ? 1 : 0;
    }
    INFO(m.name << ": " << found << " of " << cases << " found, " << scanned << " scanned, " << ties
                << " exact ties among those, " << served << " answered by a Neighbourhood");
    CHECK(found > cases / 4);
    CHECK(served > cases / 10);
    CHECK(ties > scanned / 20);  // the corners and edges asked: the tie rule is tested
  }
}
