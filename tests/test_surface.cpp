// Tests of the surfaces (surface/): the analytic shapes against their
// closed forms, MeshBvh against a brute-force scan of the same triangles,
// and the proxy (ProxyConstraint) on planes, meshes and spheres.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/surface.hpp"
#include "page_flags.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;
using hapticfield::test::probe_at;

namespace {

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

TEST_CASE("detail::smaller and larger answer b < a ? b : a and b > a ? b : a to the bit, signed zeros and NaN too",
          "[invariant]") {
  // The traversals' min and max (an SSE2 instruction where there is one):
  // the same bits as the comparisons they stand for, whichever operand is
  // a zero of either sign, an infinity or a NaN, and on random doubles.
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937_64 rng(seed);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> values{0.0,
                             -0.0,
                             1.0,
                             -1.0,
                             inf,
                             -inf,
                             nan,
                             -nan,
                             std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::max(),
                             1e-300};
  for (int i = 0; i < 2000; ++i) {
    double v = 0.0;
    const std::uint64_t bits = rng();
    std::memcpy(&v, &bits, sizeof v);  // any double, NaNs with payloads too
    values.push_back(v);
  }
  const auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  long compared = 0;
  for (std::size_t i = 0; i < values.size(); i += (i < 11 ? 1 : 97))
    for (const double b : values) {
      const double a = values[i];
      INFO("a " << a << ", b " << b);
      REQUIRE(same(detail::smaller(a, b), b < a ? b : a));
      REQUIRE(same(detail::larger(a, b), b > a ? b : a));
      ++compared;
    }
  CHECK(compared > 40000);
  static_assert(detail::smaller(1.0, 2.0) == 1.0 && detail::larger(1.0, 2.0) == 2.0);  // still constexpr
}

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

TEST_CASE("a large mesh's tree and arrays are asked onto 2 MB pages, and answer as on 4 KB pages", "[rt]") {
  // 450 x 450 cells: 203k vertices (4.9 MB of positions), 405k triangles
  TriangleMesh mesh = test::wavy_sheet(0.1, 450, 0.002, 0.03);
  TriangleMesh copy = mesh;
  const glm::dvec3* given = copy.positions.data();
  const MeshShape huge(std::move(mesh));
  MeshShapeConfig small_pages;
  small_pages.huge_pages = false;
  const MeshShape plain(std::move(copy), small_pages);
  CHECK(plain.mesh().positions.data() == given);  // moved in, not copied
  CHECK(huge.config().huge_pages);
  CHECK_FALSE(plain.config().huge_pages);
  CHECK(huge.bvh().config().huge_pages);
  CHECK_FALSE(plain.bvh().config().huge_pages);
  if (test::kernel_has_huge_pages()) {
    const auto first_whole_page = [](const void* p) {
      const auto at = reinterpret_cast<std::uintptr_t>(p);
      return reinterpret_cast<const void*>((at + huge_page_bytes - 1) & ~(huge_page_bytes - 1));
    };
    CHECK(test::marked_for_huge_pages(first_whole_page(huge.mesh().positions.data())));
    CHECK(test::marked_for_huge_pages(first_whole_page(huge.mesh().triangles.data())));
    CHECK(test::marked_for_huge_pages(first_whole_page(huge.bvh().pairs().data())));
    // a copy of the tree keeps the hint, and so does a shape made from a
    // mesh and a tree (a deforming mesh's frames)
    const MeshBvh tree = huge.bvh();
    CHECK(test::marked_for_huge_pages(first_whole_page(tree.pairs().data())));
    const MeshShape framed(huge.mesh(), tree);
    CHECK(test::marked_for_huge_pages(first_whole_page(framed.bvh().pairs().data())));
    CHECK(test::marked_for_huge_pages(first_whole_page(framed.mesh().positions.data())));
  } else {
    WARN("the page marks are not checked: this kernel has no transparent huge pages");
  }
  // the same answers, bit for bit
  REQUIRE(huge.mesh().positions == plain.mesh().positions);
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> across(-0.05, 0.05), up(-0.004, 0.004);
  for (int i = 0; i < 3000; ++i) {
    const glm::dvec3 p{across(rng), across(rng), up(rng)};
    const glm::dvec3 q = p + glm::dvec3{0.2 * up(rng), 0.2 * up(rng), 2.0 * up(rng)};
    const Hit a = huge.first_hit(p, q), b = plain.first_hit(p, q);
    REQUIRE(a.primitive == b.primitive);
    REQUIRE(a.t == b.t);
    const Hit c = huge.closest(p, 0.003), d = plain.closest(p, 0.003);
    REQUIRE(c.primitive == d.primitive);
    REQUIRE(c.point == d.point);
    const Hit e = huge.sweep_sphere(p, q, 0.0005), f = plain.sweep_sphere(p, q, 0.0005);
    REQUIRE(e.primitive == f.primitive);
    REQUIRE(e.t == f.t);
  }
}

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

// --- height fields -----------------------------------------------------------------

namespace {

/// A plain grid as the readers fill one (the io::HeightGrid layout).
struct Grid {
  int width{0}, height{0};
  double spacing_x{0.0}, spacing_y{0.0};
  std::vector<double> heights;
};

template <class F>
Grid sample(int width, int height, double spacing, F&& h) {
  Grid g{width, height, spacing, spacing, {}};
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      g.heights.push_back(h(i * spacing, j * spacing));
  return g;
}

}  // namespace

TEST_CASE("a height field of a known function has its heights and analytic normals") {
  const double A = 0.002, k = 2.0 * 3.14159265358979323846 / 0.02, spacing = 1e-4;  // 2 mm waves of 20 mm, 0.1 mm grid
  const auto h = [&](double x, double y) { return A * std::sin(k * x) * std::cos(k * y); };
  const HeightFieldShape field(sample(401, 301, spacing, h));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ux(0.001, 0.039), uy(0.001, 0.029);
  const double curvature = A * k * k;  // [1/m]: bounds the second derivatives
  for (int n = 0; n < 500; ++n) {
    const double x = ux(rng), y = uy(rng);
    const glm::dvec3 analytic = glm::normalize(
        glm::dvec3{-A * k * std::cos(k * x) * std::cos(k * y), A * k * std::sin(k * x) * std::sin(k * y), 1.0});
    const Hit hit = field.first_hit({x, y, 0.01}, {x, y, -0.01});
    REQUIRE(hit.found());
    // bilinear interpolation error <= curvature spacing^2 / 4
    CHECK_THAT(hit.point.z, WithinAbs(h(x, y), curvature * spacing * spacing / 4.0));
    // the patch normal is first order, the shaded one second order in the spacing
    CHECK(std::acos(std::fmin(1.0, glm::dot(hit.face_normal, analytic))) <= 2.0 * curvature * spacing);
    CHECK(std::acos(std::fmin(1.0, glm::dot(hit.normal, analytic))) <= curvature * spacing);
    CHECK_THAT(hit.uv.x, WithinAbs(x / 0.04, 1e-9));
    CHECK_THAT(hit.uv.y, WithinAbs(y / 0.03, 1e-9));
    // closest from just above agrees with the vertical hit to second order
    const Hit near = field.closest(hit.point + 1e-6 * hit.face_normal, 1e-3);
    REQUIRE(near.found());
    CHECK_THAT(near.distance, WithinAbs(1e-6, 1e-9));
  }
}

TEST_CASE("a tilted planar height field is hit exactly where the plane is, from above only") {
  const double a = 0.3, b = -0.2;  // slopes [-]
  const HeightFieldShape field(sample(50, 40, 1e-3, [&](double x, double y) { return a * x + b * y; }));
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.0, 0.039), w(-0.02, 0.02);
  for (int n = 0; n < 500; ++n) {
    const glm::dvec3 p0{u(rng), u(rng), 0.05}, p1{u(rng), u(rng), -0.05};
    const double f0 = p0.z - (a * p0.x + b * p0.y), f1 = p1.z - (a * p1.x + b * p1.y);
    const double t = f0 / (f0 - f1);  // the closed form
    const Hit hit = field.first_hit(p0, p1);
    REQUIRE(hit.found());
    CHECK_THAT(hit.t, WithinAbs(t, 1e-9));
    CHECK_FALSE(field.first_hit(p1, p0).found());  // from below: passes
    const glm::dvec3 normal = glm::normalize(glm::dvec3{-a, -b, 1.0});
    CHECK(glm::length(hit.face_normal - normal) < 1e-12);
    CHECK(glm::length(hit.normal - normal) < 1e-12);
  }
}

TEST_CASE("a flat height field is hit by every vertical segment, however its root rounds") {
  // flat cells have boxes of no height: the root of each segment, computed by division, may lie one ulp
  // outside the box's entry and exit, computed by a reciprocal; the hit must still be found
  for (const double z : {0.0, 1e-9, 0.002, -0.03}) {
    const HeightFieldShape field(sample(21, 21, 4e-3, [z](double, double) { return z; }));
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(0.0, 0.08), above(1e-6, 0.01), below(1e-6, 0.01);
    int missed = 0;
    for (int n = 0; n < 2000; ++n) {
      const double x = n % 4 == 0 ? 0.004 * (n % 20) : u(rng), y = n % 3 == 0 ? 0.04 : u(rng);  // cell borders too
      const double h0 = above(rng), h1 = below(rng);
      const Hit hit = field.first_hit({x, y, z + h0}, {x, y, z - h1});
      if (!hit.found()) {
        ++missed;
        continue;
      }
      CHECK_THAT(hit.t, WithinAbs(h0 / (h0 + h1), 1e-9));  // the closed form
      CHECK_THAT(hit.point.z, WithinAbs(z, 1e-12));
    }
    CHECK(missed == 0);
  }
}

TEST_CASE("a cliff in a height field is a wall the proxy does not pass at 2 m/s") {
  // 5 mm step between two samples, 0.1 mm grid
  const HeightFieldShape field(sample(200, 50, 1e-4, [](double x, double) { return x > 0.01 ? 0.005 : 0.0; }));
  ProxyConstraint proxy(field, ProxyConfig{2000.0});
  const double cliff_end = 0.0101;  // the steep cell spans x in [0.0100, 0.0101]
  glm::dvec3 hip{0.002, 0.0025, 0.002};
  (void)proxy.contact(probe_at(hip));
  for (int i = 0; i < 10; ++i) {
    hip.x += 0.002;  // 2 m/s at 1 kHz, 2 mm below the top of the cliff
    const Contact c = proxy.contact(probe_at(hip, {2.0, 0.0, 0.0}));
    CHECK(proxy.proxy().x <= cliff_end);
    if (hip.x > cliff_end) {
      CHECK(c.touching);
      CHECK(c.force.x < 0.0);
    }
  }
}

TEST_CASE("a proxy pressed onto a height field slides off its border and is free beyond it") {
  const HeightFieldShape field(sample(11, 11, 1e-3, [](double, double) { return 0.0; }));
  ProxyConstraint proxy(field, ProxyConfig{1000.0});
  (void)proxy.contact(probe_at({0.005, 0.005, 0.001}));
  CHECK(proxy.contact(probe_at({0.005, 0.005, -0.001})).touching);
  CHECK(proxy.contact(probe_at({0.0095, 0.005, -0.001})).touching);
  CHECK_FALSE(proxy.contact(probe_at({0.0115, 0.005, -0.001})).touching);  // past x = 10 mm: nothing there
}

TEST_CASE("height fields refuse 0 x 0, non-finite heights and more than 100 Mpx before allocating") {
  CHECK_THROWS_AS(HeightFieldShape(Grid{}), std::invalid_argument);
  Grid nan = sample(3, 3, 1e-3, [](double, double) { return 0.0; });
  nan.heights[4] = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(HeightFieldShape(nan), std::invalid_argument);
  Grid huge{20000, 20000, 1e-4, 1e-4, {}};  // 400 Mpx, no heights: refused by its size alone
  CHECK_THROWS_WITH(HeightFieldShape(huge), Catch::Contains("100 Mpx"));
  Grid short_grid = sample(3, 3, 1e-3, [](double, double) { return 0.0; });
  short_grid.heights.pop_back();
  CHECK_THROWS_AS(HeightFieldShape(short_grid), std::invalid_argument);
  CHECK_THROWS_AS(HeightFieldShape(Grid{3, 3, 0.0, 1e-3, std::vector<double>(9, 0.0)}), std::invalid_argument);
}
