// The viewer's and servo_demo's --shape pipeline (tools/view/shape_scene.hpp)
// against closed forms: a mesh file scaled to an 80 mm footprint with its
// top 1 mm below z = 0, a height map picture laid out with its heights, and
// the proxy started from above the shape giving Fc = k depth along the
// surface normal for a HIP that is inside from its first tick.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "view/shape_scene.hpp"
#include "view/uv_sphere.hpp"

using namespace hapticfield;
using namespace hapticfield::view;

namespace {

std::string tmp_file(const std::string& name) {
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  return (std::filesystem::path(HAPTICFIELD_TEST_TMP) / name).string();
}

Probe at(const glm::dvec3& p) {
  Probe probe;
  probe.position = p;
  return probe;
}

}  // namespace

TEST_CASE("a mesh file is scaled to an 80 mm footprint with its top 1 mm below the start", "[view3d]") {
  const std::string path = tmp_file("unit_sphere.obj");
  std::ofstream(path) << test::to_obj(test::uv_sphere(1.0, 64, 32));
  ShapeScene scene = load_shape_scene(path);
  REQUIRE(scene.mesh);
  CHECK_FALSE(scene.height_field);
  // radius 1 -> 40 mm; the box is 80 mm across in x and y (the UV sphere's
  // equator has a vertex at +-x and at +-z; y runs pole to pole)
  CHECK(scene.top.z == Approx(-0.001).margin(1e-9));
  CHECK(scene.centre.x == Approx(0.0).margin(1e-9));
  CHECK(scene.centre.y == Approx(0.0).margin(1e-9));
  CHECK(scene.centre.z == Approx(-0.041).margin(1e-9));
  CHECK(scene.display.hi.y - scene.display.lo.y == Approx(0.08f));
  CHECK(scene.display.triangles.size() == scene.mesh->mesh().triangles.size());

  // the HIP 1 mm inside the top from the first tick: the proxy comes from
  // above, stops on the top, Fc = k x 1 mm along +z (the top is a vertex of
  // 64 x 32 facets, each tilted up to 2.8 degrees: within 0.5 % and 0.01 N)
  const glm::dvec3 top = scene.top;
  ShapeProxyField<MeshShape> field(std::move(*scene.mesh), scene.shift, top + glm::dvec3{0.0, 0.0, 0.005});
  const glm::dvec3 f = field.force(at(top - glm::dvec3{0.0, 0.0, 0.001}));
  CHECK(field.last_contact().touching);
  CHECK(f.z == Approx(1.5).epsilon(5e-3));
  CHECK(std::abs(f.x) < 0.01);
  CHECK(std::abs(f.y) < 0.01);
  CHECK(field.proxy().z == Approx(top.z).margin(1e-5));
  // reset(): the next tick starts from above again, the same force
  field.reset();
  CHECK(field.force(at(top - glm::dvec3{0.0, 0.0, 0.001})).z == Approx(f.z));
}

TEST_CASE("a proxy that starts at a HIP inside the solid feels nothing: why the field starts from above", "[view3d]") {
  const std::string path = tmp_file("unit_sphere_b.obj");
  std::ofstream(path) << test::to_obj(test::uv_sphere(1.0, 64, 32));
  ShapeScene scene = load_shape_scene(path);
  ProxyConstraint<MeshShape> bare(std::move(*scene.mesh), ProxyConfig{});
  Probe inside = at(scene.top - scene.shift - glm::dvec3{0.0, 0.0, 0.001});
  CHECK_FALSE(bare.contact(inside).touching);
  CHECK_FALSE(bare.contact(inside).touching);
}

TEST_CASE("a height map picture: white high, its footprint 80 mm, its top 1 mm below the start", "[view3d]") {
  // 21 x 11 px: the left 10 columns black, the rest white
  cv::Mat picture(11, 21, CV_8UC1, cv::Scalar(255));
  picture(cv::Rect(0, 0, 10, 11)).setTo(cv::Scalar(0));
  const std::string path = tmp_file("step_height.png");
  REQUIRE(cv::imwrite(path, picture));
  ShapeSceneConfig config;
  config.height_mm = 4.0;
  ShapeScene scene = load_shape_scene(path, config);
  REQUIRE(scene.height_field);
  CHECK(scene.height_field->spacing().x == Approx(0.08 / 20.0));
  CHECK(scene.display.hi.x - scene.display.lo.x == Approx(0.08f));
  CHECK(scene.display.hi.y - scene.display.lo.y == Approx(0.04f));
  CHECK(scene.display.hi.z == Approx(-0.001f));
  CHECK(scene.display.lo.z == Approx(-0.005f));
  const glm::dvec3 above = scene.top + glm::dvec3{0.0, 0.0, 0.005};
  ShapeProxyField<HeightFieldShape> field(std::move(*scene.height_field), scene.shift, above);
  // 0.5 mm into the white plateau (x = +20 mm), then over the black one
  // (x = -20 mm, 4 mm lower) 0.5 mm into it: 0.75 N along +z each time
  const glm::dvec3 white = field.force(at({0.02, 0.0, -0.0015}));
  CHECK(white.z == Approx(0.75).epsilon(1e-3));
  CHECK(std::abs(white.x) < 1e-6);
  field.reset();
  const glm::dvec3 black = field.force(at({-0.02, 0.0, -0.0055}));
  CHECK(black.z == Approx(0.75).epsilon(1e-3));
}

TEST_CASE("--shape files that are not shapes: one clear error", "[view3d]") {
  const std::string empty = tmp_file("empty.obj");
  std::ofstream(empty) << "";
  CHECK_THROWS_WITH(load_shape_scene(empty), Catch::Contains("empty.obj"));
  CHECK_THROWS_WITH(load_shape_scene(tmp_file("missing.stl")), Catch::Contains("missing.stl"));
  const std::string flat = tmp_file("point.obj");
  std::ofstream(flat) << "v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n";
  CHECK_THROWS_WITH(load_shape_scene(flat), Catch::Contains("no extent"));
  // an extent but nothing to touch: the mesh is named, not the hand's raster
  const std::string degenerate = tmp_file("degenerate.obj");
  std::ofstream(degenerate) << "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 4\n";
  CHECK_THROWS_WITH(load_shape_scene(degenerate),
                    Catch::Contains("cannot use '" + degenerate + "': all 2 triangles have zero area"));
  ShapeSceneConfig bad;
  bad.span_mm = 0.0;
  CHECK_THROWS_WITH(load_shape_scene(flat, bad), Catch::Contains("span"));
}
