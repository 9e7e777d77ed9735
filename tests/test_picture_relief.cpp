// Tests of picture_relief() (scenes/picture_relief.hpp): the relief's height at
// each pixel is the gray level OpenCV reads x mm_per_level, the proxy rests
// on it with Fc = k depth, and the texture is the flat tangible image's
// force turned into the tangent plane of the touched point.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/scenes/picture_relief.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using test::probe_at;

namespace {

namespace fs = std::filesystem;

fs::path temp_file(const std::string& name) {
  const fs::path dir = fs::path(HAPTICFIELD_TEST_TMP) / "relief";
  fs::create_directories(dir);
  return dir / name;
}

/// A smooth 8-bit picture, W x H: 128 + 100 sin(2 pi c / 40) cos(2 pi r / 50).
cv::Mat hills(int width, int height) {
  cv::Mat m(height, width, CV_8U);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      m.at<unsigned char>(r, c) = cv::saturate_cast<unsigned char>(128.0 + 100.0 * std::sin(2.0 * M_PI * c / 40.0) *
                                                                               std::cos(2.0 * M_PI * r / 50.0));
  return m;
}

}  // namespace

TEST_CASE("picture relief: the height at each pixel is the gray level OpenCV reads x mm_per_level", "[relief]") {
  const std::string coffee = std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png";
  PictureReliefConfig config{.mm_per_level = 0.02, .width_m = 0.12};
  config.weights = GrayWeights::bt601;  // cvtColor's weights
  const PictureRelief relief = picture_relief(coffee, config);
  cv::Mat gray;  // the oracle: OpenCV's own BT.601 gray, rounded to whole levels
  cv::cvtColor(cv::imread(coffee, cv::IMREAD_COLOR), gray, cv::COLOR_BGR2GRAY);
  REQUIRE(gray.cols == 600);
  const HeightFieldShape& shape = relief.constraint().shape();
  REQUIRE(shape.width() == 600u);
  REQUIRE(shape.height() == 400u);
  const double pitch = 0.12 / 599.0;
  CHECK_THAT(shape.spacing().x, WithinAbs(pitch, 1e-15));
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> col(0, gray.cols - 1), row(0, gray.rows - 1);
  for (int k = 0; k < 2000; ++k) {
    const int c = col(rng), r = row(rng);
    const double expected = gray.at<unsigned char>(r, c) * 0.02e-3;  // [m]
    const double x = c * pitch, y = (gray.rows - 1 - r) * pitch;
    INFO("column " << c << ", row " << r);
    CHECK_THAT(shape.height_at(x, y), WithinAbs(expected, 0.5 * 0.02e-3 + 1e-12));  // OpenCV rounds to a level
  }
  // the corners: bottom-left pixel at the origin, the footprint width_m wide
  CHECK_THAT(shape.height_at(0.0, 0.0), WithinAbs(gray.at<unsigned char>(399, 0) * 0.02e-6 * 1e3, 1e-5));
  CHECK(std::isnan(shape.height_at(0.12 + 1e-6, 0.0)));
}

TEST_CASE("picture relief: the proxy rests on the relief, Fc = k depth, on a picture in memory", "[relief]") {
  // two plateaus (gray 200 left, 50 right) far from their step: flat there
  cv::Mat steps(60, 120, CV_8U, cv::Scalar(200));
  steps(cv::Rect(60, 0, 60, 60)).setTo(50);
  const double k = 800.0, mm = 0.01, width = 0.119;  // pitch 1 mm
  auto relief = picture_relief(steps, {.mm_per_level = mm, .width_m = width, .stiffness = k, .texture_gain = 2.0});
  for (const auto& [x, level] : {std::pair{0.015, 200.0}, std::pair{0.100, 50.0}}) {
    relief.reset();
    const double top = level * mm * 1e-3;
    (void)relief.force(probe_at({x, 0.03, top + 0.002}));
    const glm::dvec3 f = relief.force(probe_at({x, 0.03, top - 0.001}));
    INFO("plateau at level " << level);
    REQUIRE(relief.last_contact().touching);
    CHECK_THAT(relief.constraint().proxy().z, WithinAbs(top, 1e-6));
    CHECK_THAT(f.z, WithinAbs(k * 0.001, 1e-6));
    // a uniform plateau 17 px from any edge has no image force
    CHECK_THAT(f.x, WithinAbs(0.0, 1e-9));
    CHECK_THAT(f.y, WithinAbs(0.0, 1e-9));
  }
  // above the relief: nothing
  relief.reset();
  CHECK(relief.force(probe_at({0.015, 0.03, 0.01})) == glm::dvec3{0.0});
}

TEST_CASE("picture relief: the texture is the flat tangible-image force turned into the tangent plane", "[relief]") {
  const cv::Mat picture = hills(160, 120);
  const fs::path file = temp_file("hills.png");
  REQUIRE(cv::imwrite(file.string(), picture));
  const double k = 1000.0, gain = 1.5, width = 0.08, mm = 0.02;
  const PictureReliefConfig config{.mm_per_level = mm, .width_m = width, .stiffness = k, .texture_gain = gain};
  auto relief = picture_relief(file.string(), config);
  auto from_mat = picture_relief(picture, config);
  // the flat field: the same picture's tangible image, evaluated at a pixel
  const TangibleImage flat(to_gray(picture), TangibleConfig{});
  const double pitch = width / 159.0;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.01, width - 0.01), uy(0.01, 119 * pitch - 0.01);
  int textured = 0;
  for (int i = 0; i < 300; ++i) {
    relief.reset();
    from_mat.reset();
    const double x = ux(rng), y = uy(rng);
    const double z = relief.constraint().shape().height_at(x, y);
    (void)relief.force(probe_at({x, y, z + 0.002}));
    (void)from_mat.force(probe_at({x, y, z + 0.002}));
    const glm::dvec3 hip{x, y, z - 0.0005};
    const glm::dvec3 f = relief.force(probe_at(hip));
    CHECK(from_mat.force(probe_at(hip)) == f);  // the file and the picture in memory agree
    const Contact& c = relief.last_contact();
    REQUIRE(c.touching);
    const glm::dvec3 texture = f - c.force;
    // the touched point's pixel, y down the picture
    const double px = c.surface_uv.x * 159.0, py = (1.0 - c.surface_uv.y) * 119.0;
    const glm::dvec2 image = flat.at(px, py);
    // on_surface's frame: the touched point's t and b turned into the plane
    // normal to the contact normal (the proxy's n)
    const glm::dvec3 t = glm::normalize(c.surface_tangent - glm::dot(c.surface_tangent, c.normal) * c.normal);
    glm::dvec3 b = glm::cross(c.normal, t);
    if (glm::dot(b, c.surface_bitangent) < 0.0) b = -b;
    const glm::dvec3 expected = gain * (image.x * t - image.y * b);
    INFO("HIP " << x << ", " << y << "; pixel " << px << ", " << py);
    CHECK(glm::length(texture - expected) < 1e-9 * (1.0 + glm::length(expected)));
    // normal to the proxy's n (HIP to the nearest surface point), which is
    // within 3 degrees of the touched point's shaded normal t x b on these slopes
    const glm::dvec3 n = glm::normalize(glm::cross(c.surface_tangent, c.surface_bitangent));
    CHECK_THAT(glm::dot(texture, c.normal), WithinAbs(0.0, 1e-9));
    CHECK(glm::dot(n, c.normal) > std::cos(3.0 * M_PI / 180.0));
    CHECK(c.surface_tangent.x > 0.5);    // u runs along +x ...
    CHECK(c.surface_bitangent.y > 0.5);  // ... and v along +y (up the picture)
    // the touched point is the relief under the proxy: its uv is the proxy's x, y over the footprint
    CHECK_THAT(c.surface_uv.x * width, WithinAbs(relief.constraint().proxy().x, 1e-5));
    if (glm::length(expected) > 0.05 * gain) ++textured;
  }
  CHECK(textured > 100);  // the hills give a texture force almost everywhere
}

TEST_CASE("picture relief: a tick allocates nothing and stays finite on hostile probes", "[relief]") {
  auto relief = picture_relief(hills(160, 120), {.width_m = 0.08, .static_friction = 0.5, .dynamic_friction = 0.4});
  std::vector<Probe> path;
  for (int i = 0; i < 3000; ++i)
    path.push_back(probe_at({0.04 + 0.03 * std::sin(i * 0.003), 0.03 + 0.02 * std::cos(i * 0.002),
                             0.002 - 0.004 * std::fabs(std::sin(i * 0.01))},
                            {0.09, -0.04, 0.0}));
  glm::dvec3 sum{0.0};
  const long n = test::count_allocations([&] {
    for (const Probe& p : path)
      sum += relief.force(p);
  });
  if (test::allocations_counted) CHECK(n == 0);
  CHECK(is_finite(sum));
  CHECK(glm::length(sum) > 0.0);
  const double nan = std::nan(""), inf = INFINITY;
  for (const glm::dvec3 p : {glm::dvec3{nan, 0.0, 0.0}, glm::dvec3{0.04, inf, 0.0}, glm::dvec3{1e300, -1e300, 1e300},
                             glm::dvec3{0.04, 0.03, -1e6}, glm::dvec3{-0.5, 0.03, -0.001}})
    CHECK(is_finite(relief.force(probe_at(p, {1e6, 0.0, nan}))));
}

TEST_CASE("picture relief: bad settings and files fail with one clear error", "[relief]") {
  const cv::Mat picture = hills(40, 30);
  CHECK_THROWS_WITH(picture_relief(picture, {.width_m = 0.0}), Contains("width_m"));
  CHECK_THROWS_WITH(picture_relief(picture, {.width_m = NAN}), Contains("width_m"));
  CHECK_THROWS_WITH(picture_relief(picture, {.mm_per_level = -1.0}), Contains("mm_per_level"));
  CHECK_THROWS_WITH(picture_relief(picture, {.stiffness = -5.0}), Contains("stiffness"));
  CHECK_THROWS_WITH(picture_relief(picture, {.texture_gain = -1.0}), Contains("texture_gain"));
  CHECK_THROWS_WITH(picture_relief(picture, {.blur_sigma = -1.0}), Contains("blur_sigma"));
  CHECK_THROWS_AS(picture_relief(cv::Mat(10, 10, CV_8U, cv::Scalar(0))), std::invalid_argument);  // < 17 px mask
  CHECK_THROWS_AS(picture_relief(cv::Mat()), std::invalid_argument);
  CHECK_THROWS_AS(picture_relief("/nonexistent/relief.png"), ImageError);
  CHECK_THROWS_WITH(picture_relief("/nonexistent/relief.png"), Contains("/nonexistent/relief.png"));
}
