// Tests of the normal field: face labels, force law signs on known slopes,
// speed threshold and velocity filter, gradient variant, edges and force
// shading, O(1) lookup with many faces, zero allocations per tick.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

// g++ 12 inlines the counting operator new / delete into OpenCV's and the
// standard library's containers and then flags malloc/free as mismatched
// (a false positive, -Wmismatched-new-delete); silence it for this header.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
#include "alloc_counter.hpp"
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#include "hapticfield/normals.hpp"

using namespace hapticfield;

namespace {

constexpr double deg = std::numbers::pi / 180.0;

std::vector<glm::dvec2> rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

/// A unit normal tilted by slant [deg] so that downhill points along the
/// image direction azimuth [deg] (x right, y down).
glm::dvec3 tilted(double slant, double azimuth) {
  return {std::sin(slant * deg) * std::cos(azimuth * deg), std::sin(slant * deg) * std::sin(azimuth * deg),
          -std::cos(slant * deg)};
}

/// Force in image axes [N] at pixel p moving with image velocity v [px/s], fresh filter.
glm::dvec2 felt(NormalField& field, glm::dvec2 p, glm::dvec2 v) {
  field.reset();
  return field.to_image_axes(field.force(field.probe_at(p, v)));
}

/// n faces: a grid of small squares tiling the 640 x 640 picture.
std::vector<ImageFace> tiles(int n) {
  const int per_row = static_cast<int>(std::ceil(std::sqrt(double(n))));
  const double side = 640.0 / per_row;
  std::vector<ImageFace> faces;
  for (int k = 0; k < n; ++k) {
    const double x0 = (k % per_row) * side;
    const double y0 = (k / per_row) * side;
    faces.push_back({rect(x0 + 1.0, y0 + 1.0, x0 + side - 2.0, y0 + side - 2.0), tilted(10.0 + k % 50, 7.0 * k)});
  }
  return faces;
}

}  // namespace

TEST_CASE("force along the motion: climbing resists, descending assists, level is silent") {
  // one face over the whole picture, slant 30 deg, downhill toward image +x
  NormalField field(640, 640, {{rect(-1, -1, 641, 641), tilted(30.0, 0.0)}});
  const glm::dvec2 p{320.0, 320.0};
  const double expected = kim_kwon_max_force * std::sin(30.0 * deg);  // 0.6 N * (n . m_hat)

  const glm::dvec2 descend = felt(field, p, {200.0, 0.0});
  CHECK(descend.x == Approx(expected));  // with the motion
  CHECK(descend.y == Approx(0.0).margin(1e-12));
  const glm::dvec2 climb = felt(field, p, {-200.0, 0.0});
  CHECK(climb.x == Approx(expected));  // against the motion (motion is -x)
  const glm::dvec2 level = felt(field, p, {0.0, 150.0});
  CHECK(glm::length(level) == Approx(0.0).margin(1e-12));
  // oblique motion at 60 deg from downhill: F = 0.6 sin30 cos60 along m_hat
  const glm::dvec2 m{std::cos(60.0 * deg), std::sin(60.0 * deg)};
  const glm::dvec2 oblique = felt(field, p, 300.0 * m);
  CHECK(oblique.x == Approx(expected * 0.5 * m.x));
  CHECK(oblique.y == Approx(expected * 0.5 * m.y));

  // device frame with the default Kim & Kwon mapping: image y down = device -y
  NormalField down(640, 640, {{rect(-1, -1, 641, 641), tilted(45.0, 90.0)}});  // downhill toward image +y
  down.reset();
  const glm::dvec3 f = down.force(down.probe_at(p, {0.0, 100.0}));
  CHECK(f.y == Approx(-kim_kwon_max_force * std::sin(45.0 * deg)));
  CHECK(f.x == Approx(0.0).margin(1e-12));
  CHECK(f.z == 0.0);
}

TEST_CASE("signs agree with the 3D geometry of the box stimulus") {
  // Independent oracle: cast rays through two image points onto the true
  // face; the motion climbs when the surface comes closer to the viewer
  // (its depth z decreases). On a plane, z seen through pixel (u, v) is
  // d / (n . K^-1 (u, v, 1)), whose image gradient is along +(n_x, n_y) at
  // every pixel, so the sign must hold everywhere on the face.
  const BoxScene scene;
  const Camera camera = scene.camera();
  const cv::Matx33d Kinv = camera.matrix().inv();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (double rotation : {20.0, 45.0, 70.0}) {
    const BoxView view = render_box(scene, rotation, false);
    std::vector<ImageFace> faces;
    std::vector<FacePose> poses;
    for (std::size_t f = 0; f < 2; ++f) {
      std::vector<glm::dvec2> c(view.corners[f].begin(), view.corners[f].end());
      poses.push_back(estimate_rectangle_pose(camera, c, glm::dvec2{200.0, 200.0}));
      faces.push_back({c, poses.back().normal});
    }
    NormalField field(scene.width, scene.height, faces);
    const cv::Matx33d R = detail::box_rotation(rotation, scene.elevation_deg);
    for (std::size_t f = 0; f < 2; ++f) {
      const auto& c = view.corners[f];
      const glm::dvec2 centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
      // the true plane: outward normal and face centre from the box pose
      const cv::Vec3d n(view.normals[f].x, view.normals[f].y, view.normals[f].z);
      const cv::Vec3d on_plane =
          R * (f == 0 ? cv::Vec3d(0, 0, -100) : cv::Vec3d(100, 0, 0)) + cv::Vec3d(0, 0, scene.distance_mm);
      const auto depth = [&](glm::dvec2 px) {  // z of the plane point seen at px [mm]
        const cv::Vec3d ray = Kinv * cv::Vec3d(px.x, px.y, 1.0);
        return n.dot(on_plane) / n.dot(ray);  // ray.z = 1
      };
      for (int corner = -1; corner < 4; ++corner) {
        const glm::dvec2 p = corner < 0 ? centre : 0.5 * (centre + c[static_cast<std::size_t>(corner)]);
        for (int k = 0; k < 24; ++k) {
          const double a = 2.0 * std::numbers::pi * unit(rng);
          const glm::dvec2 m{std::cos(a), std::sin(a)};
          const glm::dvec2 force = felt(field, p, 300.0 * m);
          const double climb = depth(p) - depth(p + 1e-3 * m);  // > 0: coming closer
          INFO("rotation " << rotation << " face " << f << " corner " << corner << " angle " << a);
          if (std::abs(climb) > 1e-9) CHECK((glm::dot(force, m) < 0.0) == (climb > 0.0));
          // magnitude: 0.6 N |n . m_hat| with the true normal
          CHECK(glm::length(force) == Approx(kim_kwon_max_force * std::abs(n[0] * m.x + n[1] * m.y)).margin(1e-9));
        }
      }
    }
  }
}

TEST_CASE("speed threshold, velocity low-pass and reset") {
  NormalFieldConfig options;
  options.speed_threshold = 0.01;  // [m/s] = 64 px/s at 6.4 px/mm
  options.velocity_cutoff_hz = 10.0;
  NormalField field(640, 640, {{rect(-1, -1, 641, 641), tilted(30.0, 0.0)}}, options);
  const glm::dvec2 p{320.0, 320.0};
  CHECK(glm::length(felt(field, p, {60.0, 0.0})) == 0.0);
  CHECK(glm::length(felt(field, p, {70.0, 0.0})) == Approx(0.3));
  CHECK(glm::length(felt(field, p, {0.0, 0.0})) == 0.0);

  // step from -200 to +200 px/s: the filtered velocity follows a first-order
  // lag with time constant 1 / (2 pi fc); the force flips sign when it crosses zero
  field.reset();
  (void)field.force(field.probe_at(p, {-200.0, 0.0}));
  CHECK(field.filtered_velocity().x == Approx(-200.0));
  const double tau = 1.0 / (2.0 * std::numbers::pi * options.velocity_cutoff_hz);
  const int ticks = static_cast<int>(std::round(tau / servo_period));
  glm::dvec3 f{0.0};
  for (int i = 0; i < ticks; ++i)
    f = field.force(field.probe_at(p, {200.0, 0.0}));
  // after one time constant: -200 + 400 (1 - e^-1) = 52.8 px/s
  CHECK(field.filtered_velocity().x == Approx(200.0 - 400.0 * std::exp(-ticks * servo_period / tau)).epsilon(1e-9));
  CHECK(field.filtered_velocity().x == Approx(52.8).margin(2.0));
  CHECK(glm::length(f) == 0.0);  // 52.8 px/s is below the 64 px/s threshold
  for (int i = 0; i < 200; ++i)
    f = field.force(field.probe_at(p, {200.0, 0.0}));
  CHECK(field.to_image_axes(f).x == Approx(0.3).epsilon(1e-3));
  field.reset();
  CHECK(field.filtered_velocity() == glm::dvec2{0.0});
}

TEST_CASE("by default the field adds no second low-pass to the device's filtered velocity") {
  NormalField field(640, 640, {{rect(-1, -1, 641, 641), tilted(30.0, 0.0)}});
  const glm::dvec2 p{320.0, 320.0};
  (void)field.force(field.probe_at(p, {-200.0, 0.0}));
  (void)field.force(field.probe_at(p, {200.0, 0.0}));
  CHECK(field.filtered_velocity().x == Approx(200.0));  // the step passes on the same tick: no added lag
}

TEST_CASE("non-finite probes give zero force and leave the state alone") {
  NormalField field(640, 640, {{rect(-1, -1, 641, 641), tilted(30.0, 0.0)}});
  const glm::dvec2 p{320.0, 320.0};
  (void)field.force(field.probe_at(p, {200.0, 0.0}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Probe bad = field.probe_at(p, {200.0, 0.0});
  bad.position.x = nan;
  CHECK(field.force(bad) == glm::dvec3{0.0});
  bad = field.probe_at(p, {200.0, 0.0});
  bad.velocity.y = inf;
  CHECK(field.force(bad) == glm::dvec3{0.0});
  bad = field.probe_at(p, {200.0, 0.0});
  bad.position = glm::dvec3{1e300, -1e300, 0.0};
  CHECK(field.force(bad) == glm::dvec3{0.0});
  CHECK(field.filtered_velocity().x == Approx(200.0));
  CHECK(glm::length(field.force(field.probe_at(p, {200.0, 0.0}))) == Approx(0.3));
  // off the picture and on the background: nothing
  CHECK(glm::length(felt(field, {-50.0, 10.0}, {200.0, 0.0})) == 0.0);
  NormalField small(640, 640, {{rect(100, 100, 200, 200), tilted(30.0, 0.0)}});
  CHECK(glm::length(felt(small, {300.0, 300.0}, {200.0, 0.0})) == 0.0);
  CHECK(glm::length(felt(small, {150.0, 150.0}, {200.0, 0.0})) > 0.0);
}

TEST_CASE("gradient variant pushes downhill whatever the motion") {
  NormalFieldConfig options;
  options.mode = NormalForceMode::gradient;
  const glm::dvec3 n = tilted(40.0, 135.0);
  NormalField field(640, 640, {{rect(-1, -1, 641, 641), n}}, options);
  for (glm::dvec2 v : {glm::dvec2{0.0}, glm::dvec2{300.0, 0.0}, glm::dvec2{-50.0, 400.0}}) {
    const glm::dvec2 f = felt(field, {320.0, 320.0}, v);
    CHECK(f.x == Approx(kim_kwon_max_force * n.x));
    CHECK(f.y == Approx(kim_kwon_max_force * n.y));
  }
}

TEST_CASE("the force never exceeds the bound") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const glm::dvec3 n = tilted(89.9 * u(rng), 360.0 * u(rng));
    for (auto mode : {NormalForceMode::along_motion, NormalForceMode::gradient}) {
      NormalFieldConfig options;
      options.mode = mode;
      NormalField field(64, 64, {{rect(-1, -1, 65, 65), n}}, options, PlaneMapping(6.4, {32.0, 32.0}));
      const double a = 2.0 * std::numbers::pi * u(rng);
      const glm::dvec3 f = field.force(field.probe_at({32.0, 32.0}, 500.0 * glm::dvec2{std::cos(a), std::sin(a)}));
      CHECK(glm::length(f) <= kim_kwon_max_force * (1.0 + 1e-12));
    }
  }
}

TEST_CASE("edges are felt; force shading makes the slope continuous") {
  // two faces meeting at x = 320 with different slopes (a roof ridge)
  const std::vector<ImageFace> faces{{rect(0, 0, 320, 640), tilted(40.0, 180.0)},
                                     {rect(320, 0, 640, 640), tilted(40.0, 0.0)}};
  NormalFieldConfig flat;
  flat.mode = NormalForceMode::gradient;
  NormalFieldConfig shaded = flat;
  shaded.shading_cell_px = 16.0;
  NormalField edged(640, 640, faces, flat);
  NormalField smooth(640, 640, faces, shaded);
  double max_jump_edged = 0.0;
  double max_jump_smooth = 0.0;
  glm::dvec2 prev_e = felt(edged, {250.0, 301.0}, {});
  glm::dvec2 prev_s = felt(smooth, {250.0, 301.0}, {});
  for (double x = 250.25; x <= 390.0; x += 0.25) {
    const glm::dvec2 e = felt(edged, {x, 301.0 + 0.1 * (x - 250.0)}, {});
    const glm::dvec2 s = felt(smooth, {x, 301.0 + 0.1 * (x - 250.0)}, {});
    max_jump_edged = std::max(max_jump_edged, glm::length(e - prev_e));
    max_jump_smooth = std::max(max_jump_smooth, glm::length(s - prev_s));
    prev_e = e;
    prev_s = s;
  }
  // flat faces: the force flips across the ridge (2 * 0.6 sin 40 deg)
  CHECK(max_jump_edged == Approx(2.0 * 0.6 * std::sin(40.0 * deg)).epsilon(1e-6));
  // shaded: Lipschitz, spread over the cells around the ridge
  CHECK(max_jump_smooth < 0.02);
  // far from the ridge the shaded normal is the face's own
  CHECK(smooth.normal_at({100.0, 300.0}).x == Approx(faces[0].normal.x));
  CHECK(smooth.normal_at({540.0, 300.0}).x == Approx(faces[1].normal.x));
  // on the ridge the shaded normal is the (pixel-area weighted) average:
  // nearly level (16 vs 17 pixel columns of each face in the window)
  CHECK(smooth.normal_at({320.0, 300.0}).x == Approx(0.0).margin(0.05));
  CHECK(std::abs(smooth.normal_at({320.0, 300.0}).x) < 0.1 * std::abs(faces[0].normal.x));
}

TEST_CASE("explicit shading grid: bilinear interpolation of vertex normals") {
  // a cylinder-like surface: normals turn with x across 3 x 2 vertices
  const std::vector<glm::dvec3> normals{tilted(30.0, 180.0), glm::dvec3{0.0, 0.0, -1.0}, tilted(30.0, 0.0),
                                        tilted(30.0, 180.0), glm::dvec3{0.0, 0.0, -1.0}, tilted(30.0, 0.0)};
  const ShadingGrid grid({100.0, 100.0}, 50.0, 3, 2, normals);
  CHECK(grid.normal_at({100.0, 100.0}).x == Approx(normals[0].x));
  CHECK(grid.normal_at({200.0, 150.0}).x == Approx(normals[5].x));
  const glm::dvec3 mid = grid.normal_at({125.0, 120.0});
  const glm::dvec3 expected = glm::normalize(0.5 * (normals[0] + normals[1]));
  CHECK(mid.x == Approx(expected.x));
  CHECK(mid.z == Approx(expected.z));
  CHECK(grid.normal_at({99.0, 120.0}) == glm::dvec3{0.0});
  NormalFieldConfig options;
  options.mode = NormalForceMode::gradient;
  NormalField field(640, 640, {{rect(90, 90, 210, 160), glm::dvec3{0.0, 0.0, -1.0}}}, options, std::nullopt, grid);
  CHECK(felt(field, {110.0, 120.0}, {}).x < 0.0);
  CHECK(felt(field, {190.0, 120.0}, {}).x > 0.0);
  CHECK_THROWS_WITH(ShadingGrid({0.0, 0.0}, 0.0, 3, 2, normals), Catch::Contains("spacing"));
  CHECK_THROWS_WITH(ShadingGrid({0.0, 0.0}, 5.0, 3, 3, normals), Catch::Contains("cols * rows"));
  auto away = normals;
  away[1] = glm::dvec3{0.0, 0.0, 1.0};
  CHECK_THROWS_WITH(ShadingGrid({0.0, 0.0}, 5.0, 3, 2, away), Catch::Contains("face the camera"));
}

TEST_CASE("labels match point-in-polygon for 1, 10 and 1000 faces and non-convex polygons") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 640.0);
  for (int n : {1, 10, 1000}) {
    const auto faces = tiles(n);
    NormalField field(640, 640, faces);
    REQUIRE(field.normals().size() == static_cast<std::size_t>(n));
    int checked = 0;
    for (int k = 0; k < 3000; ++k) {
      const glm::dvec2 p{u(rng), u(rng)};
      // expected face by the polygon test (oracle: cv::pointPolygonTest), away from edges
      int expected = -1;
      bool near_edge = false;
      for (std::size_t f = 0; f < faces.size(); ++f) {
        std::vector<cv::Point2f> poly;
        for (auto v : faces[f].polygon)
          poly.emplace_back(static_cast<float>(v.x), static_cast<float>(v.y));
        const double d =
            cv::pointPolygonTest(poly, cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), true);
        if (std::abs(d) < 1.0) near_edge = true;
        if (d > 0.0) expected = static_cast<int>(f);
      }
      if (near_edge) continue;
      ++checked;
      CHECK(field.labels().label_at(p) == expected);
    }
    CHECK(checked > 1000);
  }
  // a non-convex (L-shaped) face and a star
  std::vector<glm::dvec2> star;
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 == 0 ? 200.0 : 80.0;
    star.push_back({320.0 + r * std::cos(i * 36.0 * deg), 320.0 + r * std::sin(i * 36.0 * deg)});
  }
  const std::vector<glm::dvec2> ell{{20, 20}, {120, 20}, {120, 60}, {60, 60}, {60, 140}, {20, 140}};
  NormalField shapes(640, 640, {{ell, tilted(20.0, 0.0)}, {star, tilted(20.0, 90.0)}});
  CHECK(shapes.labels().label_at({40.0, 100.0}) == 0);
  CHECK(shapes.labels().label_at({100.0, 40.0}) == 0);
  CHECK(shapes.labels().label_at({100.0, 100.0}) == -1);  // the notch of the L
  CHECK(shapes.labels().label_at({320.0, 320.0}) == 1);
  CHECK(shapes.labels().label_at({320.0 + 190.0, 320.0}) == 1);  // a star tip
  CHECK(shapes.labels().label_at({320.0 + 150.0 * std::cos(36.0 * deg), 320.0 + 150.0 * std::sin(36.0 * deg)}) ==
        -1);  // between tips
}

TEST_CASE("a tick never allocates, with or without shading, whatever the face count") {
  for (int n : {1, 10, 1000}) {
    for (double cell : {0.0, 8.0}) {
      NormalFieldConfig options;
      options.shading_cell_px = cell;
      NormalField field(640, 640, tiles(n), options);
      AnyField erased = NormalField(640, 640, tiles(n), options);
      double sum = 0.0;
      const long allocations = test::count_allocations([&] {
        for (int k = 0; k < 2000; ++k) {
          Probe p;
          p.position = glm::dvec3{0.05 * std::sin(k * 0.01), 0.04 * std::cos(k * 0.013), 0.0};
          p.velocity = glm::dvec3{0.05 * std::cos(k * 0.01), -0.05 * std::sin(k * 0.013), 0.0};
          p.time = k * servo_period;
          sum += field.force(p).x + erased.force(p).y;
        }
      });
      CHECK(allocations == 0);
      CHECK(std::isfinite(sum));
    }
  }
}

TEST_CASE("bad field setup is rejected with a clear error") {
  const auto face = [](std::vector<glm::dvec2> poly, glm::dvec3 n) { return std::vector<ImageFace>{{poly, n}}; };
  CHECK_THROWS_WITH(NormalField(0, 640, {}), Catch::Contains("size"));
  CHECK_THROWS_WITH(NormalField(640, 640, face({{0, 0}, {10, 0}}, {0, 0, -1})), Catch::Contains("3 vertices"));
  CHECK_THROWS_WITH(NormalField(640, 640, face({{0, 0}, {10, 0}, {0, std::nan("")}}, {0, 0, -1})),
                    Catch::Contains("non-finite"));
  CHECK_THROWS_WITH(NormalField(640, 640, face(rect(0, 0, 10, 10), {0, 0, 0})), Catch::Contains("non-zero normal"));
  CHECK_THROWS_WITH(NormalField(640, 640, face(rect(0, 0, 10, 10), {0, std::nan(""), -1})),
                    Catch::Contains("non-zero normal"));
  CHECK_THROWS_WITH(NormalField(640, 640, face(rect(0, 0, 10, 10), {0.1, 0, 1})), Catch::Contains("face the camera"));
  NormalFieldConfig o;
  o.max_force = 0.0;
  CHECK_THROWS_WITH(NormalField(640, 640, {}, o), Catch::Contains("max_force"));
  o = {};
  o.speed_threshold = -1.0;
  CHECK_THROWS_WITH(NormalField(640, 640, {}, o), Catch::Contains("speed_threshold"));
  o = {};
  o.velocity_cutoff_hz = -1.0;
  CHECK_THROWS_WITH(NormalField(640, 640, {}, o), Catch::Contains("velocity_cutoff_hz"));
  o = {};
  o.shading_cell_px = std::nan("");
  CHECK_THROWS_WITH(NormalField(640, 640, {}, o), Catch::Contains("shading_cell_px"));
  // a non-unit normal is normalised
  NormalField field(640, 640, face(rect(-1, -1, 641, 641), {3.0, 0.0, -4.0}));
  CHECK(field.normals()[0].x == Approx(0.6));
  // no faces: zero everywhere
  NormalField empty(640, 640, {});
  CHECK(empty.force(empty.probe_at({10.0, 10.0}, {100.0, 0.0})) == glm::dvec3{0.0});
}
