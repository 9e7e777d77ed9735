// The 3D view's software renderer (tools/view/orbit_camera.hpp,
// display_mesh.hpp, mesh_render.hpp, scene3d.hpp) against closed forms: the
// pinhole projection of known points, the pixels a known triangle covers,
// the z-buffer keeping the nearer of two triangles, back faces culled, a
// sphere's silhouette radius f r / sqrt(d^2 - r^2), and decimation for
// display within its budget, the tool's ball at the proxy at the size of its
// silhouette, and the mouse's 3D handle position.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>

#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/servo/clock.hpp"
#include "view/display_mesh.hpp"
#include "view/mesh_render.hpp"
#include "view/mouse_device.hpp"
#include "view/orbit_camera.hpp"
#include "view/scene3d.hpp"
#include "view/uv_sphere.hpp"

using namespace hapticfield;
using namespace hapticfield::view;

namespace {

/// Looking along -z at the origin from d = 1 m, f = 500 px, 800 x 600.
OrbitCamera head_on() {
  OrbitCamera c;
  c.distance = 1.0;
  c.fov_y = 2.0 * std::atan(300.0 / 500.0);
  return c;
}

/// The device point on z = 0 seen at image position (u, v) [px] by head_on().
glm::dvec3 at_pixel(double u, double v) {
  return {(u - 400.0) / 500.0, (300.0 - v) / 500.0, 0.0};
}

DisplayMesh one_triangle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  DisplayMesh m;
  m.positions = {glm::vec3(a), glm::vec3(b), glm::vec3(c)};
  m.triangles = {{0, 1, 2}};
  m.source_triangles = 1;
  m.finish();
  return m;
}

std::size_t covered(const RenderTarget& t) {
  std::size_t n = 0;
  for (const float z : t.inverse_depth)
    n += z > 0.0f;
  return n;
}

}  // namespace

TEST_CASE("orbit camera: the pinhole projection of known points", "[view3d]") {
  const OrbitCamera c = head_on();
  CHECK(c.focal() == Approx(500.0));
  const Projected p = c.project({0.1, 0.2, 0.0});
  CHECK(p.pixel.x == Approx(400.0 + 500.0 * 0.1));
  CHECK(p.pixel.y == Approx(300.0 - 500.0 * 0.2));
  CHECK(p.depth == Approx(1.0));
  const Projected q = c.project({0.1, 0.2, -1.0});  // twice as far: half the offset
  CHECK(q.pixel.x == Approx(400.0 + 250.0 * 0.1));
  CHECK(q.depth == Approx(2.0));
  CHECK(c.project({0.0, 0.0, 2.0}).depth < 0.0);  // behind the eye
  // turned: yaw 90 degrees puts the eye on +x, looking along -x, with -z to the right... and back
  OrbitCamera turned = c;
  turned.yaw = std::numbers::pi / 2.0;
  turned.pitch = 0.3;
  const glm::dvec3 x{0.01, -0.02, 0.03};
  const Projected r = turned.project(x);
  const glm::dvec3 back = turned.unproject(r.pixel, r.depth);
  CHECK(back.x == Approx(x.x).margin(1e-12));
  CHECK(back.y == Approx(x.y).margin(1e-12));
  CHECK(back.z == Approx(x.z).margin(1e-12));
  CHECK(glm::length(turned.eye() - glm::dvec3{std::cos(0.3), std::sin(0.3), 0.0}) < 1e-12);
}

TEST_CASE("a right triangle facing the camera covers the pixels whose centres it holds", "[view3d]") {
  // legs along the image axes: from (100.2, 400.3) right to (300.7, 400.3)
  // and up to (100.2, 120.6); hypotenuse v = 120.6 + (u - 100.2) * 279.7 / 200.5
  const double u0 = 100.2, u1 = 300.7, v0 = 400.3, v1 = 120.6;
  const DisplayMesh m = one_triangle(at_pixel(u0, v0), at_pixel(u1, v0), at_pixel(u0, v1));
  RenderTarget t;
  const RenderStats s = render_mesh(m, head_on(), t);
  CHECK(s.drawn == 1);
  // closed form: column i (centre x = i + 0.5) holds the rows whose centre
  // y is in [hypotenuse(x), v0]
  std::size_t expected = 0;
  for (int i = 0; i < 800; ++i) {
    const double x = i + 0.5;
    if (x < u0 || x > u1) continue;
    const double top = v1 + (x - u0) * (v0 - v1) / (u1 - u0);
    expected += static_cast<std::size_t>(std::floor(v0 - 0.5) - std::ceil(top - 0.5) + 1);
  }
  CHECK(covered(t) == expected);
  CHECK(s.pixels == expected);
  CHECK(t.depth_at(150, 350) == Approx(1.0f));
  CHECK(t.depth_at(99, 350) == 0.0f);   // left of the vertical leg (centre 99.5 < 100.2)
  CHECK(t.depth_at(150, 400) == 0.0f);  // below the base (centre 400.5 > 400.3)
  CHECK(t.depth_at(290, 300) == 0.0f);  // beyond the hypotenuse (above it)
  CHECK(t.depth_at(290, 398) == Approx(1.0f));
  // flat Lambert: the normal is +z, the light (-f + 0.45 u - 0.35 r) normalised
  const RenderConfig rc;
  const float lit =
      rc.ambient + (1.0f - rc.ambient) * static_cast<float>(1.0 / std::sqrt(1.0 + 0.45 * 0.45 + 0.35 * 0.35));
  const cv::Vec3b seen = t.image.at<cv::Vec3b>(350, 150);
  for (int k = 0; k < 3; ++k)
    CHECK(std::abs(seen[k] - rc.colour[k] * lit) <= 0.51);
  CHECK(t.image.at<cv::Vec3b>(350, 99) == rc.background);
}

TEST_CASE("back faces are culled", "[view3d]") {
  const DisplayMesh m = one_triangle(at_pixel(100, 400), at_pixel(100, 120), at_pixel(300, 400));  // clockwise
  RenderTarget t;
  const RenderStats s = render_mesh(m, head_on(), t);
  CHECK(s.drawn == 0);
  CHECK(s.culled == 1);
  CHECK(covered(t) == 0);
}

TEST_CASE("the z-buffer shows the nearer of two triangles, in either order", "[view3d]") {
  // a square's two halves would meet; here two full triangles over the same
  // pixels, one at z = 0 (depth 1 m), one at z = 0.3 (depth 0.7 m), tilted
  // so their shades differ
  const auto near_triangle = [] {
    glm::dvec3 a = at_pixel(200, 400) * 0.7, b = at_pixel(600, 400) * 0.7, c = at_pixel(400, 100) * 0.7;
    a.z = 0.3 - 0.05;  // tilted in z: still in front of the far one everywhere
    b.z = 0.3 + 0.05;
    c.z = 0.3;
    return std::array{a, b, c};
  }();
  const std::array far_triangle{at_pixel(150, 450), at_pixel(650, 450), at_pixel(400, 50)};
  for (const bool near_first : {true, false}) {
    DisplayMesh m;
    for (const auto& tri :
         near_first ? std::array{near_triangle, far_triangle} : std::array{far_triangle, near_triangle})
      for (const glm::dvec3& p : tri)
        m.positions.emplace_back(p);
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    m.source_triangles = 2;
    m.finish();
    RenderTarget t;
    (void)render_mesh(m, head_on(), t);
    // at the centre pixel, the near plane's depth: 1 - z there (z = 0.3 at u = 400)
    CHECK(1.0 / t.depth_at(400, 300) == Approx(0.7).epsilon(2e-3));
    // outside the near one, the far one (depth 1)
    CHECK(t.depth_at(160, 440) == Approx(1.0f));
  }
}

TEST_CASE("a sphere's silhouette radius is the pinhole projection's, within a pixel", "[view3d]") {
  const double r = 0.04, d = 0.2;
  const DisplayMesh m = display_mesh(test::uv_sphere(r, 256, 128));
  OrbitCamera c;
  c.distance = d;
  c.yaw = 0.4;
  c.pitch = 0.5;
  RenderTarget t;
  const RenderStats s = render_mesh(m, c, t);
  CHECK(s.culled > s.drawn / 2);  // the back half
  const double rho = c.focal() * r / std::sqrt(d * d - r * r);
  // the outline is a circle of radius rho about the image centre: its area
  // and its extent along the centre row and column
  const double area_radius = std::sqrt(static_cast<double>(covered(t)) / std::numbers::pi);
  CHECK(std::abs(area_radius - rho) < 1.0);
  int left = 800, right = -1, top = 600, bottom = -1;
  for (int x = 0; x < 800; ++x)
    if (t.depth_at(x, 300) > 0.0f) {
      left = std::min(left, x);
      right = std::max(right, x);
    }
  for (int y = 0; y < 600; ++y)
    if (t.depth_at(400, y) > 0.0f) {
      top = std::min(top, y);
      bottom = std::max(bottom, y);
    }
  CHECK(std::abs((right - left + 1) / 2.0 - rho) < 1.5);
  CHECK(std::abs((bottom - top + 1) / 2.0 - rho) < 1.5);
  CHECK(std::abs((left + right + 1) / 2.0 - 400.0) < 1.0);
  CHECK(std::abs((top + bottom + 1) / 2.0 - 300.0) < 1.0);
  // and the nearest point is at depth d - r
  CHECK(1.0 / t.depth_at(400, 300) == Approx(d - r).epsilon(1e-3));
}

TEST_CASE("decimation for display keeps a mesh within its budget and its box", "[view3d]") {
  const TriangleMesh sphere = test::uv_sphere(0.05, 250, 160);  // 79 500 triangles
  const DisplayMesh full = display_mesh(sphere, glm::dvec3{0.0, 0.0, -0.05}, 100'000);
  CHECK_FALSE(full.decimated());
  CHECK(full.triangles.size() == sphere.triangles.size());
  CHECK(full.hi.z == Approx(0.0f).margin(1e-6));
  const DisplayMesh small = display_mesh(sphere, glm::dvec3{0.0}, 5'000);
  CHECK(small.decimated());
  CHECK(small.triangles.size() <= 5'000);
  CHECK(small.triangles.size() > 1'000);
  CHECK(small.source_triangles == sphere.triangles.size());
  // every kept vertex is a mean of sphere points close together: near the sphere
  for (const glm::vec3& p : small.positions)
    CHECK(std::abs(glm::length(p) - 0.05f) < 0.05f * 0.1f);
  // its silhouette still matches the sphere's within a few pixels
  OrbitCamera c;
  c.distance = 0.25;
  RenderTarget t;
  (void)render_mesh(small, c, t);
  const double rho = c.focal() * 0.05 / std::sqrt(0.25 * 0.25 - 0.05 * 0.05);
  CHECK(std::abs(std::sqrt(static_cast<double>(covered(t)) / std::numbers::pi) - rho) < 0.05 * rho);
}

TEST_CASE("a height grid as display triangles: two per cell, sampled over the budget", "[view3d]") {
  struct Grid {
    int width{5}, height{4};
    double spacing_x{0.01}, spacing_y{0.02};
    std::vector<double> heights;
  } g;
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i)
      g.heights.push_back(0.001 * i + 0.002 * j);
  const DisplayMesh m = display_height_grid(g, glm::dvec3{1.0, 0.0, 0.0});
  CHECK(m.triangles.size() == 2 * 4 * 3);
  CHECK(m.positions[6].x == Approx(1.01f));  // (i, j) = (1, 1)
  CHECK(m.positions[6].y == Approx(0.02f));
  CHECK(m.positions[6].z == Approx(0.003f));
  for (const glm::vec3& n : m.face_normals)
    CHECK(n.z > 0.0f);  // facing +z (up the relief)
  const DisplayMesh coarse = display_height_grid(g, glm::dvec3{0.0}, 8);
  CHECK(coarse.triangles.size() <= 8);
  CHECK(coarse.hi.x == Approx(0.04f));  // the last column is kept
}

TEST_CASE("the 3D frame marks the proxy and the HIP where they project", "[view3d]") {
  const DisplayMesh m = display_mesh(test::uv_sphere(0.04, 64, 32));
  OrbitCamera c;
  c.distance = 0.2;
  Sample3d now;
  now.proxy = {0.0, 0.0, 0.04};
  now.hip = {0.01, 0.0, 0.035};
  now.force = {0.0, 0.0, 1.5};
  RenderTarget t;
  const Scene3dMarks marks = draw_scene3d(t, m, c, now);
  const Projected p = c.project(now.proxy), h = c.project(now.hip);
  CHECK(marks.proxy ==
        cv::Point(static_cast<int>(std::lround(p.pixel.x - 0.5)), static_cast<int>(std::lround(p.pixel.y - 0.5))));
  CHECK(t.image.at<cv::Vec3b>(marks.proxy) == cv::Vec3b(255, 0, 255));
  CHECK(marks.hip.x == static_cast<int>(std::lround(h.pixel.x - 0.5)));
  CHECK(t.image.at<cv::Vec3b>(marks.hip + cv::Point(hip_radius_px, 0)) == cv::Vec3b(0, 255, 0));
}

namespace {
/// Pixels of the tool ball's colour: magenta shaded (B = R > 0, G = 0), and
/// their bounding box.
struct Tip {
  std::size_t pixels{0};
  int left{1 << 20}, right{-1}, top{1 << 20}, bottom{-1};
};
Tip tip_pixels(const cv::Mat& image) {
  Tip t;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b c = image.at<cv::Vec3b>(y, x);
      if (c[1] != 0 || c[0] != c[2] || c[0] == 0) continue;
      ++t.pixels;
      t.left = std::min(t.left, x), t.right = std::max(t.right, x);
      t.top = std::min(t.top, y), t.bottom = std::max(t.bottom, y);
    }
  return t;
}
}  // namespace

TEST_CASE("a tool of radius r is drawn as a ball at the proxy: the sphere's silhouette f r / sqrt(d^2 - r^2)",
          "[view3d][radius]") {
  OrbitCamera c;  // 800 x 600, 40 degrees: f = 824 px
  c.distance = 0.2;
  for (const double r : {0.002, 0.005, 0.02}) {
    INFO("r " << r);
    Sample3d now;
    now.proxy = {0.0, 0.0, 0.0};   // on the optical axis, 0.2 m from the eye
    now.hip = {0.0, -0.001, 0.0};  // inside the ball: its ring stays visible over it
    Scene3dConfig config;
    config.tip_radius = r;
    RenderTarget t;
    const Scene3dMarks marks = draw_scene3d(t, DisplayMesh{}, c, now, config);
    const double rho = c.focal() * r / std::sqrt(c.distance * c.distance - r * r);
    const Tip tip = tip_pixels(t.image);
    // the ball's own count: a disc of radius rho within half a pixel; what is left of it in the tip's colour
    // under the HIP's ring (radius 8 px, 2 to 3 px wide) and the line to it
    CHECK(std::abs(std::sqrt(static_cast<double>(marks.ball_pixels) / std::numbers::pi) - rho) < 0.5);
    CHECK(tip.pixels <= marks.ball_pixels);
    CHECK(tip.pixels + 250 >= marks.ball_pixels);
    CHECK(std::abs((tip.right - tip.left + 1) / 2.0 - rho) < 1.0);
    CHECK(std::abs((tip.bottom - tip.top + 1) / 2.0 - rho) < 1.0);
    CHECK(std::abs((tip.left + tip.right + 1) / 2.0 - 400.0) < 1.0);
    CHECK(std::abs((tip.top + tip.bottom + 1) / 2.0 - 300.0) < 1.0);
    // shaded: lit on the light's side (above and to the left), darker below and to the right
    const int d = static_cast<int>(std::lround(0.6 * rho));  // clear of the HIP's ring
    const cv::Vec3b upper_left = t.image.at<cv::Vec3b>(300 - d, 400 - d);
    const cv::Vec3b lower_right = t.image.at<cv::Vec3b>(300 + d, 400 + d);
    CHECK(upper_left[1] == 0);
    CHECK(lower_right[1] == 0);
    CHECK(upper_left[0] > lower_right[0]);
    CHECK(t.image.at<cv::Vec3b>(marks.hip + cv::Point(hip_radius_px, 0)) == cv::Vec3b(0, 255, 0));
  }
  // twice as far, half the size
  Sample3d far;
  far.hip = far.proxy = {0.0, 0.0, -0.2};
  Scene3dConfig config;
  config.tip_radius = 0.01;
  RenderTarget t;
  const Scene3dMarks marks = draw_scene3d(t, DisplayMesh{}, c, far, config);
  const double rho = c.focal() * 0.01 / std::sqrt(0.4 * 0.4 - 0.01 * 0.01);
  CHECK(std::abs(std::sqrt(static_cast<double>(marks.ball_pixels) / std::numbers::pi) - rho) < 0.5);
  // r = 0 is the dot alone; a ball smaller than the dot is drawn with the dot over it
  std::size_t dot = 0;
  for (const double r : {0.0, 1e-4}) {
    Sample3d now;
    now.hip = {0.01, 0.0, 0.0};
    config.tip_radius = r;
    const Scene3dMarks small = draw_scene3d(t, DisplayMesh{}, c, now, config);
    CHECK(t.image.at<cv::Vec3b>(small.proxy) == cv::Vec3b(255, 0, 255));
    if (r == 0.0) {
      dot = tip_pixels(t.image).pixels;
      CHECK(small.ball_pixels == 0);
      CHECK(std::abs(static_cast<double>(dot) - std::numbers::pi * proxy_radius_px * proxy_radius_px) < 10.0);
    } else {
      CHECK(tip_pixels(t.image).pixels == dot);
      CHECK(small.ball_pixels < 10);
    }
  }
}

TEST_CASE("MouseDevice in the 3D view: the handle where set_position put it, to 0.25 um", "[view3d]") {
  VirtualClock clock;
  MouseDevice<VirtualClock> mouse(PlaneMapping::fit(800, 600, 80.0), clock);
  DeviceState state;
  for (const glm::dvec3 p : {glm::dvec3{0.0123456, -0.0456789, 0.001}, glm::dvec3{-0.25, 0.25, -0.1234567}}) {
    mouse.set_position(p);
    clock.advance(1'000'000);
    REQUIRE(mouse.read(state) == Status::ok);
    for (int k = 0; k < 3; ++k)
      CHECK(std::abs(state.position[k] - p[k]) <= 0.125e-6 + 1e-15);
  }
  mouse.set_position(glm::dvec3{1.0, -1.0, 0.0});  // beyond the range: clamped, finite
  clock.advance(1'000'000);
  REQUIRE(mouse.read(state) == Status::ok);
  CHECK(state.position.x == Approx(0.262144).epsilon(1e-5));
  CHECK(state.position.y == Approx(-0.262144).epsilon(1e-5));
}
