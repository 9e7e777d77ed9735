// Material maps: properties over uv (constant or picture, bilinear), the
// material sampled at the proxy's uv each tick, HaTT taxel maps, the
// vibration tap's per-texel materials, bad inputs.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/core/live_field.hpp"
#include "hapticfield/material/material_image.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/material/material_surface.hpp"
#include "hapticfield/material/property_map.hpp"
#include "hapticfield/material/taxel_map.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/texture/hatt_model_file.hpp"
#include "hapticfield/vibration/tap.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using namespace hapticfield::material;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using hapticfield::test::probe_at;

namespace {

/// The plane z = 0, solid below; its uv are (x, y) [m], so a picture over
/// uv [0, 1]^2 covers the square metre x, y in [0, 1].
PlaneShape floor_plane() {
  return PlaneShape(PlaneShapeConfig{glm::dvec3{0.0}, glm::dvec3{0.0, 0.0, 1.0}, 0.01});
}

/// The oracle: OpenCV's bilinear read of a float picture at texel
/// coordinates (x, y) (centres at integers), edges replicated.
double opencv_at(const cv::Mat& picture, double x, double y) {
  cv::Mat out;
  cv::getRectSubPix(picture, cv::Size(1, 1), cv::Point2f(static_cast<float>(x), static_cast<float>(y)), out, CV_32F);
  return out.at<float>(0, 0);
}

std::vector<float> values_of(const cv::Mat& picture) {
  std::vector<float> v;
  for (int j = 0; j < picture.rows; ++j)
    for (int i = 0; i < picture.cols; ++i)
      v.push_back(picture.at<float>(j, i));
  return v;
}

/// A 2 x 1 picture: u < 0.5 reads left, u > 0.5 right (clamped at the edges).
PropertyMap two_regions(double left, double right) {
  return PropertyMap(2, 1, {static_cast<float>(left), static_cast<float>(right)}, UvLayout{UvWrap::clamp});
}

constexpr double depth = 0.002;  // [m]

}  // namespace

// --- property maps against OpenCV -------------------------------------------

TEST_CASE("a picture property is OpenCV's bilinear read at the texel under uv, clamped or repeated") {
  const std::uint32_t seed = hapticfield::test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> size(1, 40);
  std::uniform_real_distribution<double> level(-5.0, 5.0);
  std::uniform_real_distribution<double> inside(0.0, 1.0);
  std::uniform_real_distribution<double> anywhere(-3.0, 4.0);
  // OpenCV takes the point as floats: 1e-5 px of rounding at coordinates
  // near 100, on slopes up to 10 per texel
  const double tolerance = 2e-4;
  for (int picture = 0; picture < 60; ++picture) {
    const int w = size(rng);
    const int h = size(rng);
    cv::Mat image(h, w, CV_32F);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i)
        image.at<float>(j, i) = static_cast<float>(level(rng));
    const PropertyMap clamped(w, h, values_of(image), UvLayout{UvWrap::clamp});
    const PropertyMap repeated(w, h, values_of(image), UvLayout{UvWrap::repeat});
    const PropertyMap down(w, h, values_of(image), UvLayout{UvWrap::clamp, true});
    cv::Mat tiled;
    cv::repeat(image, 3, 3, tiled);
    for (int k = 0; k < 100; ++k) {
      const glm::dvec2 uv{inside(rng), inside(rng)};
      INFO(w << " x " << h << " at uv (" << uv.x << ", " << uv.y << ")");
      const double x = uv.x * w - 0.5;
      CHECK_THAT(clamped.at(uv), WithinAbs(opencv_at(image, x, (1.0 - uv.y) * h - 0.5), tolerance));
      CHECK_THAT(down.at(uv), WithinAbs(opencv_at(image, x, uv.y * h - 0.5), tolerance));
      const glm::dvec2 far{anywhere(rng), anywhere(rng)};
      const double fu = far.x - std::floor(far.x);
      const double fv = (1.0 - far.y) - std::floor(1.0 - far.y);
      CHECK_THAT(repeated.at(far), WithinAbs(opencv_at(tiled, (fu + 1.0) * w - 0.5, (fv + 1.0) * h - 0.5), tolerance));
    }
  }
}

TEST_CASE("an index map gives the nearest texel's id and bilinear weights that sum to one") {
  const IndexMap ids(4, 2, {0, 1, 2, 3, 4, 5, 6, 7}, UvLayout{UvWrap::clamp});
  CHECK(ids.at({0.1, 0.9}) == 0);  // top row is v = 1
  CHECK(ids.at({0.9, 0.9}) == 3);
  CHECK(ids.at({0.9, 0.1}) == 7);
  CHECK(ids.largest() == 7);
  std::uint32_t around[4];
  double weights[4];
  REQUIRE(ids.around({0.5, 0.75}, around, weights));
  CHECK_THAT(weights[0] + weights[1] + weights[2] + weights[3], WithinAbs(1.0, 1e-12));
  CHECK(around[0] == 1);
  CHECK(around[1] == 2);
  CHECK_THAT(weights[0], WithinAbs(0.5, 1e-12));
}

// --- the material felt through the proxy -------------------------------------

TEST_CASE("two friction regions give mu 0.2 and 0.8 on their own sides on the same tick") {
  MaterialMaps maps;
  maps.stiffness = 1000.0;
  maps.static_friction = two_regions(0.3, 0.9);
  maps.dynamic_friction = two_regions(0.2, 0.8);
  auto left = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  auto right = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  const double y = 0.5;
  (void)left.force(probe_at({0.1, y, 0.001}));
  (void)right.force(probe_at({0.8, y, 0.001}));
  for (int tick = 0; tick < 400; ++tick) {  // pressed in 2 mm, stroking +x at 0.1 mm per tick
    const double dx = 1e-4 * tick;
    const glm::dvec3 fl = left.force(probe_at({0.1 + dx, y, -depth}));
    const glm::dvec3 fr = right.force(probe_at({0.8 + dx, y, -depth}));
    REQUIRE(left.last_contact().touching);
    REQUIRE(right.last_contact().touching);
    CHECK_THAT(fl.z, WithinRel(1000.0 * depth, 1e-9));
    CHECK_THAT(fr.z, WithinRel(1000.0 * depth, 1e-9));
    if (tick >= 20) {  // sliding: the proxy lags mu_k d behind, so |Ft| / |Fn| = mu_k
      INFO("tick " << tick);
      CHECK_THAT(-fl.x / fl.z, WithinAbs(0.2, 1e-7));  // the picture holds floats
      CHECK_THAT(-fr.x / fr.z, WithinAbs(0.8, 1e-7));
      CHECK(left.constraint().last_tick().sliding);
    }
  }
}

TEST_CASE("MaterialSurface's look-ahead changes nothing: the same forces bit for bit across two friction regions") {
  const std::uint32_t seed = hapticfield::test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-3e-3, 3e-3);
  MaterialMaps maps;
  maps.stiffness = 1000.0;
  maps.static_friction = two_regions(0.3, 0.9);
  maps.dynamic_friction = two_regions(0.2, 0.8);
  const TriangleMesh sheet = test::wavy_sheet(1.0, 60, 0.004, 0.1);
  auto plain = material_surface(MeshShape(sheet), ProxyConfig{}, MaterialMap(maps));
  auto ahead = material_surface(MeshShape(sheet), ProxyConfig{}, MaterialMap(maps));
  static_assert(AnticipatingField<decltype(ahead)>);
  long allocations = 0;
  int touching = 0;
  for (int tick = 0; tick < 600; ++tick) {  // across the border at x = 0, 1 mm into the sheet's top
    Probe p = probe_at({-0.03 + 1e-4 * tick, 0.2, 0.003 - 1e-4 * std::min(tick, 40)});
    Probe next = p;
    next.position += glm::dvec3{jitter(rng), jitter(rng), jitter(rng)};
    allocations += test::count_allocations([&] { ahead.anticipate(next); });
    const glm::dvec3 a = plain.force(p), b = ahead.force(p);
    INFO("tick " << tick);
    REQUIRE(a == b);
    REQUIRE(plain.constraint().proxy() == ahead.constraint().proxy());
    touching += plain.last_contact().touching ? 1 : 0;
  }
  CHECK(touching > 500);
  if (test::allocations_counted) CHECK(allocations == 0);
}

TEST_CASE("a stiffness map changes Fc in proportion to k(uv), the oracle OpenCV's read of the picture") {
  const std::uint32_t seed = hapticfield::test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> k(200.0, 3000.0);
  std::uniform_real_distribution<double> inside(0.02, 0.98);
  cv::Mat picture(7, 9, CV_32F);
  for (int j = 0; j < picture.rows; ++j)
    for (int i = 0; i < picture.cols; ++i)
      picture.at<float>(j, i) = static_cast<float>(k(rng));
  MaterialMaps maps;
  maps.stiffness = PropertyMap(picture.cols, picture.rows, values_of(picture), UvLayout{UvWrap::clamp});
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  for (int point = 0; point < 500; ++point) {
    const glm::dvec2 uv{inside(rng), inside(rng)};
    const double expected_k = opencv_at(picture, uv.x * picture.cols - 0.5, (1.0 - uv.y) * picture.rows - 0.5);
    INFO("uv (" << uv.x << ", " << uv.y << ") k " << expected_k);
    surface.reset();
    (void)surface.force(probe_at({uv.x, uv.y, 0.001}));
    for (int tick = 0; tick < 3; ++tick) {  // the first contact tick and the ones after agree
      const glm::dvec3 f = surface.force(probe_at({uv.x, uv.y, -depth}));
      CHECK_THAT(f.z, WithinRel(expected_k * depth, 1e-5));
      CHECK_THAT(surface.last_material().stiffness, WithinRel(expected_k, 1e-5));
    }
  }
}

TEST_CASE("a region border crossed slowly gives no force step above 7% (the JND of force)") {
  // 256 texels across one metre: the border between k 800 and 2400 N/m,
  // mu 0.2 and 0.6, is one texel (3.9 mm) wide; the stroke is 5 cm/s.
  std::vector<float> k(256), mu(256);
  for (int i = 0; i < 256; ++i) {
    k[static_cast<std::size_t>(i)] = i < 128 ? 800.0F : 2400.0F;
    mu[static_cast<std::size_t>(i)] = i < 128 ? 0.2F : 0.6F;
  }
  MaterialMaps maps;
  maps.stiffness = PropertyMap(256, 1, k, UvLayout{UvWrap::clamp});
  maps.static_friction = PropertyMap(256, 1, mu, UvLayout{UvWrap::clamp});
  maps.dynamic_friction = PropertyMap(256, 1, mu, UvLayout{UvWrap::clamp});
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  const double speed = 0.05;  // [m/s]
  (void)surface.force(probe_at({0.45, 0.5, 0.001}));
  double previous = 0.0;
  double worst = 0.0;
  for (int tick = 0; tick < 2000; ++tick) {
    const glm::dvec3 f = surface.force(probe_at({0.45 + speed * 1e-3 * tick, 0.5, -depth}, {speed, 0.0, 0.0}));
    const double magnitude = glm::length(f);
    if (tick > 50) worst = std::fmax(worst, std::fabs(magnitude - previous) / previous);
    previous = magnitude;
  }
  INFO("largest step between ticks " << 100.0 * worst << " %");
  CHECK(worst < 0.07);
  CHECK(worst > 0.0);
  CHECK_THAT(previous, WithinRel(2400.0 * depth * std::sqrt(1.0 + 0.6 * 0.6), 1e-6));  // the far side, sliding
}

TEST_CASE("a published material reaches the next tick and the proxy keeps its contact") {
  MaterialMaps soft;
  soft.stiffness = 500.0;
  MaterialMaps hard;
  hard.stiffness = 2000.0;
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(soft));
  (void)surface.force(probe_at({0.5, 0.5, 0.001}));
  CHECK_THAT(surface.force(probe_at({0.5, 0.5, -depth})).z, WithinRel(500.0 * depth, 1e-9));
  surface.publish(MaterialMap(hard));
  CHECK_THAT(surface.force(probe_at({0.5, 0.5, -depth})).z, WithinRel(2000.0 * depth, 1e-9));
  CHECK(surface.last_contact().touching);
  // and the whole surface as a LiveField's field
  LiveField<decltype(surface)> live(std::move(surface));
  CHECK_THAT(live.force(probe_at({0.5, 0.5, -depth})).z, WithinRel(2000.0 * depth, 1e-9));
}

TEST_CASE("a material surface's tick allocates nothing") {
  if (!hapticfield::test::allocations_counted) return;  // not counted under ThreadSanitizer
  MaterialMaps maps;
  maps.stiffness = two_regions(800.0, 2400.0);
  maps.static_friction = two_regions(0.3, 0.9);
  maps.dynamic_friction = two_regions(0.2, 0.8);
  maps.texture_gain = two_regions(0.0, 1.0);
  maps.vibration = IndexMap(2, 1, {3, 4}, UvLayout{UvWrap::clamp});
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  vibration::ContactRing<64> ring;
  auto tapped = vibration::tap(std::move(surface), ring);
  (void)tapped.force(probe_at({0.1, 0.5, 0.001}));
  const long allocations = hapticfield::test::count_allocations([&] {
    for (int tick = 0; tick < 3000; ++tick) {
      (void)tapped.force(probe_at({0.1 + 3e-4 * tick, 0.5, -depth}, {0.3, 0.0, 0.0}));
      (void)ring.try_pop();
    }
  });
  CHECK(allocations == 0);
}

// --- the vibration path ------------------------------------------------------

TEST_CASE("the vibration tap receives the material id of the texel touched, or of the triangle") {
  MaterialMaps maps;
  maps.vibration = IndexMap(2, 1, {7, 9}, UvLayout{UvWrap::clamp});
  vibration::ContactRing<1024> ring;
  auto tapped = vibration::tap(material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps)), ring);
  (void)tapped.force(probe_at({0.2, 0.5, 0.001}));
  REQUIRE(ring.try_pop());  // the tick in free space
  int seen_left = 0;
  int seen_right = 0;
  for (int tick = 0; tick < 600; ++tick) {
    const double x = 0.2 + 1e-3 * tick;  // across the border at u = 0.5
    (void)tapped.force(probe_at({x, 0.5, -depth}, {1.0, 0.0, 0.0}));
    const auto popped = ring.try_pop();
    REQUIRE(popped);
    const vibration::ContactSample s = *popped;
    const double u = tapped.field().last_contact().surface_uv.x;
    CHECK(s.normal_force > 0.0);
    CHECK(s.material == (u < 0.5 ? 7u : 9u));
    (s.material == 7 ? seen_left : seen_right)++;
  }
  CHECK(seen_left > 100);
  CHECK(seen_right > 100);

  // per triangle: a sheet whose right half is material 5, left half 2
  TriangleMesh sheet = hapticfield::test::flat_sheet(1.0, 4);
  for (const auto& t : sheet.triangles) {
    const double cx = (sheet.positions[t[0]].x + sheet.positions[t[1]].x + sheet.positions[t[2]].x) / 3.0;
    sheet.materials.push_back(cx > 0.0 ? 5u : 2u);
  }
  MaterialMaps per_triangle;
  per_triangle.vibration = per_primitive_material;
  auto mesh_tap = vibration::tap(material_surface(MeshShape(sheet), ProxyConfig{}, MaterialMap(per_triangle)), ring);
  (void)mesh_tap.force(probe_at({-0.3, 0.1, 0.001}));
  (void)mesh_tap.force(probe_at({-0.3, 0.1, -depth}));
  REQUIRE(ring.try_pop());  // the tick in free space
  const auto first = ring.try_pop();
  REQUIRE(first);
  CHECK(first->material == 2u);
  for (int tick = 0; tick < 60; ++tick)
    (void)mesh_tap.force(probe_at({-0.3 + 0.01 * tick, 0.1, -depth}, {1.0, 0.0, 0.0}));
  vibration::ContactSample s;
  while (const auto next = ring.try_pop())
    s = *next;
  CHECK(s.material == 5u);
}

// --- HaTT taxel maps ---------------------------------------------------------

TEST_CASE("a HaTT taxel map fades from one model to the next across a border, without a step") {
  const std::filesystem::path dir = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "tests" / "data" / "hatt";
  const std::vector<texture::HattModelSet> sets = {texture::load_hatt_model_set(dir / "Models_Synthetic Grid.xml"),
                                                   texture::load_hatt_model_set(dir / "Models_Synthetic ARMA.xml")};
  texture::HattConfig config;
  config.friction = false;  // the proxy's friction cone holds the friction
  std::vector<std::uint32_t> ids(64);
  for (std::size_t i = 0; i < ids.size(); ++i)
    ids[i] = i < 32 ? 0u : 1u;
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(MaterialMaps{}),
                                  TaxelTexture<>(IndexMap(64, 1, ids, UvLayout{UvWrap::clamp}), sets, config));
  (void)surface.force(probe_at({0.4, 0.5, 0.001}));
  double previous_w1 = 0.0;
  double largest_change = 0.0;
  bool both = false;
  const double step = 1e-4;  // [m per tick]
  const long allocations = hapticfield::test::count_allocations([&] {
    for (int tick = 0; tick < 2000; ++tick) {
      const glm::dvec3 f = surface.force(probe_at({0.4 + step * tick, 0.5, -depth}, {0.1, 0.0, 0.0}));
      const auto& w = surface.texture<0>().last_weights();
      if (!(std::fabs(w[0] + w[1] - 1.0) < 1e-12) || !is_finite(f)) FAIL("weights do not sum to one or F not finite");
      if (tick > 0) largest_change = std::fmax(largest_change, std::fabs(w[1] - previous_w1));
      if (w[0] > 0.0 && w[1] > 0.0) both = true;
      previous_w1 = w[1];
    }
  });
  if (hapticfield::test::allocations_counted) CHECK(allocations == 0);
  CHECK(both);
  CHECK(previous_w1 == 1.0);
  // continuous: a weight moves at most one tick's share of a texel (64 texels over 1 m)
  CHECK(largest_change <= step * 64.0 + 1e-9);

  std::vector<std::uint32_t> past = ids;
  past[3] = 2;  // only two model sets
  CHECK_THROWS_WITH(TaxelTexture<>(IndexMap(64, 1, past), sets, config),
                    Catch::Contains("names model 2 but there are 2 model sets"));
  CHECK_THROWS_AS(TaxelTexture<>(IndexMap(0u), {}, config), std::invalid_argument);
}

// --- bad inputs ----------------------------------------------------------------

TEST_CASE("bad material inputs are one clear error each") {
  CHECK_THROWS_WITH(PropertyMap(std::nan("")), Catch::Contains("must be finite"));
  CHECK_THROWS_WITH(PropertyMap(0, 3, {}), Catch::Contains("empty"));
  CHECK_THROWS_WITH(PropertyMap(2, 2, {1.0F, 2.0F, 3.0F}), Catch::Contains("3 values for a 2 x 2"));
  CHECK_THROWS_WITH(PropertyMap(2, 1, {1.0F, std::nanf("")}), Catch::Contains("value 1 is not finite"));
  CHECK_THROWS_WITH(IndexMap(2, 1, {1}), Catch::Contains("1 ids for a 2 x 1"));
  MaterialMaps maps;
  maps.stiffness = two_regions(1000.0, 0.0);
  CHECK_THROWS_WITH(MaterialMap(maps), Catch::Contains("stiffness must be > 0"));
  maps = MaterialMaps{};
  maps.dynamic_friction = -0.1;
  CHECK_THROWS_WITH(MaterialMap(maps), Catch::Contains("dynamic friction"));
  CHECK_THROWS_WITH(property_map_from_image(cv::Mat(), 0, 0.0, 1.0), Catch::Contains("empty"));
  CHECK_THROWS_WITH(property_map_from_image(cv::Mat(2, 2, CV_8UC1, cv::Scalar(3)), 1, 0.0, 1.0),
                    Catch::Contains("channel 1 of a picture with 1 channel"));
  cv::Mat nan_picture(2, 2, CV_32FC1, cv::Scalar(0.5));
  nan_picture.at<float>(1, 1) = std::nanf("");
  CHECK_THROWS_WITH(property_map_from_image(nan_picture, 0, 0.0, 1.0), Catch::Contains("not finite"));
  CHECK_THROWS_AS(load_property_map("/nonexistent/material-mask.png", 0, 0.0, 1.0), ImageError);
  CHECK_THROWS_WITH(index_map_from_image(cv::Mat(1, 1, CV_32FC1, cv::Scalar(1.5))), Catch::Contains("not a region id"));

  // a tick with bad numbers: no force, and the material stays usable
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(MaterialMaps{}));
  CHECK(surface.force(probe_at({std::nan(""), 0.0, 0.0})) == glm::dvec3{0.0});
  CHECK(surface.touched_material() == 0);
}

TEST_CASE("a painted mask read from a picture file is the material it says") {
  const std::filesystem::path dir = std::filesystem::path(HAPTICFIELD_TEST_TMP);
  std::filesystem::create_directories(dir);
  cv::Mat mask(4, 8, CV_8UC3, cv::Scalar(0, 0, 0));
  mask(cv::Rect(4, 0, 4, 4)).setTo(cv::Scalar(0, 0, 255));  // right half red (channel 2 in BGR)
  const std::string path = (dir / "material_mask.png").string();
  REQUIRE(cv::imwrite(path, mask));
  const PropertyMap mu = load_property_map(path, 2, 0.2, 0.8, UvLayout{UvWrap::clamp});
  CHECK_THAT(mu.at({0.1, 0.5}), WithinAbs(0.2, 1e-6));
  CHECK_THAT(mu.at({0.9, 0.5}), WithinAbs(0.8, 1e-6));
  CHECK_THAT(mu.at({0.5, 0.5}), WithinAbs(0.5, 1e-6));  // the border, bilinear
  const IndexMap regions = load_index_map(path, 2);
  CHECK(regions.at({0.9, 0.5}) == 255u);
}

// --- the picture in docs/materials.md ----------------------------------------

TEST_CASE("a stroke over a painted friction mask: the mask and the felt forces drawn (docs/images/material_map.png)") {
  // glass (mu 0.1) with a disc of sandpaper (mu 0.9) and a band of soft
  // rubber (k 600 N/m, else 1500); the stroke runs along v = 0.5.
  const int size = 128;
  cv::Mat mu_mask(size, size, CV_8UC1, cv::Scalar(0));
  cv::circle(mu_mask, cv::Point(40, 64), 24, cv::Scalar(255), cv::FILLED);
  cv::Mat k_mask(size, size, CV_8UC1, cv::Scalar(255));
  k_mask(cv::Rect(84, 0, 20, size)).setTo(cv::Scalar(0));
  MaterialMaps maps;
  maps.static_friction = property_map_from_image(mu_mask, 0, 0.1, 0.9, UvLayout{UvWrap::clamp});
  maps.dynamic_friction = maps.static_friction;
  maps.stiffness = property_map_from_image(k_mask, 0, 600.0, 1500.0, UvLayout{UvWrap::clamp});
  auto surface = material_surface(floor_plane(), ProxyConfig{}, MaterialMap(maps));
  (void)surface.force(probe_at({0.02, 0.5, 0.001}));
  std::vector<double> tangential, normal, us;
  for (int tick = 0; tick < 4800; ++tick) {  // 0.2 mm per tick
    const glm::dvec3 f = surface.force(probe_at({0.02 + 2e-4 * tick, 0.5, -depth}, {0.2, 0.0, 0.0}));
    tangential.push_back(std::hypot(f.x, f.y));
    normal.push_back(f.z);
    us.push_back(surface.last_contact().surface_uv.x);
  }
  // on the disc's centre line the friction is 0.9 of Fn, on glass 0.1, in the band Fn = 600 N/m x 2 mm
  const auto at_u = [&](double u) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < us.size(); ++i)
      if (std::fabs(us[i] - u) < std::fabs(us[best] - u)) best = i;
    return best;
  };
  CHECK_THAT(tangential[at_u(40.5 / size)] / normal[at_u(40.5 / size)], WithinAbs(0.9, 1e-6));
  CHECK_THAT(tangential[at_u(0.8)] / normal[at_u(0.8)], WithinAbs(0.1, 1e-6));
  CHECK_THAT(normal[at_u(94.0 / size)], WithinRel(600.0 * depth, 1e-6));

  const char* write = std::getenv("HAPTICFIELD_WRITE_DOC_IMAGES");
  if (write == nullptr) return;
  const int panel = 384;
  cv::Mat out(panel, 2 * panel, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat mask_colour(size, size, CV_8UC3);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const int m = mu_mask.at<std::uint8_t>(j, i);
      const int soft = k_mask.at<std::uint8_t>(j, i) == 0 ? 1 : 0;
      mask_colour.at<cv::Vec3b>(j, i) = cv::Vec3b(static_cast<std::uint8_t>(soft ? 220 : 240 - m / 2),
                                                  static_cast<std::uint8_t>(soft ? 160 : 240 - m / 2),
                                                  static_cast<std::uint8_t>(soft ? 90 : 240 - m / 4));
    }
  cv::resize(mask_colour, out(cv::Rect(0, 0, panel, panel)), cv::Size(panel, panel), 0, 0, cv::INTER_NEAREST);
  cv::line(out, cv::Point(0, panel / 2), cv::Point(panel - 1, panel / 2), cv::Scalar(0, 0, 0), 1);
  cv::putText(out, "red: sandpaper mu 0.9, gray: glass mu 0.1, blue: k 600 N/m", cv::Point(6, 16),
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1);
  const auto plot = [&](const std::vector<double>& y, double top, const cv::Scalar& colour) {
    for (std::size_t i = 1; i < y.size(); ++i) {
      const auto px = [&](std::size_t k) {
        return cv::Point(panel + static_cast<int>(us[k] * panel),
                         panel - 20 - static_cast<int>(y[k] / top * (panel - 60)));
      };
      cv::line(out, px(i - 1), px(i), colour, 2);
    }
  };
  plot(normal, 3.2, cv::Scalar(200, 80, 0));
  plot(tangential, 3.2, cv::Scalar(0, 0, 200));
  cv::putText(out, "felt along v = 0.5: Fn (blue), |Ft| (red), 0..3.2 N", cv::Point(panel + 6, 16),
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1);
  const std::filesystem::path file =
      std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "docs" / "images" / "material_map.png";
  CHECK(cv::imwrite(file.string(), out));
}

// --- a model felt with its own texture ---------------------------------------

#ifdef HAPTICFIELD_TEST_HAS_IO
#include "hapticfield/io/gltf.hpp"
#include "hapticfield/io/obj.hpp"
#include "hapticfield/scenes/model_texture.hpp"

namespace {

/// A loaded mesh as a reader returns it: a flat sheet of side 0.2 m (uv 0..1)
/// with one material whose base-colour texture is picture, PNG-encoded.
io::LoadedMesh sheet_with_texture(const cv::Mat& picture) {
  io::LoadedMesh loaded;
  loaded.mesh = hapticfield::test::flat_sheet(0.2, 8);
  loaded.material_names = {"painted"};
  loaded.mesh.materials.assign(loaded.mesh.triangles.size(), 0u);
  std::vector<unsigned char> png;
  REQUIRE(cv::imencode(".png", picture, png));
  loaded.base_colour_textures = {png};
  return loaded;
}

}  // namespace

TEST_CASE("metres per uv is the median of the triangles' ratio of space to uv") {
  CHECK_THAT(metres_per_uv(hapticfield::test::flat_sheet(0.2, 8)), WithinRel(0.2, 1e-12));
  TriangleMesh stretched = hapticfield::test::flat_sheet(0.2, 8);
  for (auto& uv : stretched.uvs)
    uv *= 4.0;  // the picture repeats four times across: 5 cm per uv unit
  CHECK_THAT(metres_per_uv(stretched), WithinRel(0.05, 1e-12));
  TriangleMesh bare = hapticfield::test::flat_sheet(0.2, 2);
  bare.uvs.clear();
  CHECK_THROWS_WITH(metres_per_uv(bare), Catch::Contains("no texture coordinates"));
}

TEST_CASE("a model's base-colour texture is felt where it is drawn, at the size the uvs give it") {
  // a 64 x 64 picture: white, with a black square over columns 32.. and rows ..15 (u > 0.5, v > 0.75)
  cv::Mat picture(64, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  picture(cv::Rect(32, 0, 32, 16)).setTo(cv::Scalar(0, 0, 0));
  ModelTextureConfig config;
  config.proxy.stiffness = 1000.0;
  config.texture_gain = 1.0;
  config.tangible.size = 5;
  auto model = textured_model(sheet_with_texture(picture), config);
  // the sheet spans x, y in [-0.1, 0.1]: u = 0.5 at x = 0, v = 0.75 at y = 0.05
  const auto stroke = [&](glm::dvec3 from, glm::dvec3 step, int ticks, auto&& each) {
    model.reset();
    (void)model.force(probe_at(from + glm::dvec3{0.0, 0.0, 0.003}));
    for (int tick = 0; tick < ticks; ++tick) {
      const glm::dvec3 at = from + static_cast<double>(tick) * step;
      const glm::dvec3 f = model.force(probe_at(at, step * 1000.0));
      REQUIRE(model.last_contact().touching);
      each(at, f);
    }
  };
  // along u at v = 0.875 (inside the black square's rows): the edge at x = 0 pushes along x
  double peak_x = 0.0, peak = 0.0;
  stroke({-0.05, 0.075, -0.001}, {1e-4, 0.0, 0.0}, 1000, [&](glm::dvec3 at, glm::dvec3 f) {
    if (std::fabs(f.x) > peak) {
      peak = std::fabs(f.x);
      peak_x = at.x;
    }
  });
  INFO("peak " << peak << " N at x " << peak_x);
  CHECK(peak > 0.1);
  CHECK(std::fabs(peak_x) < 2.0 * 0.2 / 64.0);  // within two pixels (3.1 mm each) of the drawn edge
  // along u at v = 0.25 (white rows): nothing to feel
  double quiet = 0.0;
  stroke({-0.05, -0.05, -0.001}, {1e-4, 0.0, 0.0}, 1000,
         [&](glm::dvec3, glm::dvec3 f) { quiet = std::fmax(quiet, std::hypot(f.x, f.y)); });
  CHECK(quiet < 1e-9);
  // along v at u = 0.75: the square's lower edge at v = 0.75, y = 0.05
  double peak_y = 0.0;
  peak = 0.0;
  stroke({0.05, 0.0, -0.001}, {0.0, 1e-4, 0.0}, 1000, [&](glm::dvec3 at, glm::dvec3 f) {
    if (std::fabs(f.y) > peak) {
      peak = std::fabs(f.y);
      peak_y = at.y;
    }
  });
  CHECK(std::fabs(peak_y - 0.05) < 2.0 * 0.2 / 64.0);

  io::LoadedMesh no_texture = sheet_with_texture(picture);
  no_texture.base_colour_textures = {{}};
  CHECK_THROWS_WITH(textured_model(no_texture), Catch::Contains("has no base-colour texture"));
  io::LoadedMesh garbage = sheet_with_texture(picture);
  garbage.base_colour_textures = {{1, 2, 3, 4, 5}};
  CHECK_THROWS_WITH(textured_model(garbage), Catch::Contains("not a picture OpenCV can decode"));
}

TEST_CASE("an OBJ's map_Kd is its base-colour texture; a missing one is a warning, then one clear error") {
  const std::filesystem::path dir = std::filesystem::path(HAPTICFIELD_TEST_TMP) / "material_obj";
  std::filesystem::create_directories(dir);
  cv::Mat picture(32, 48, CV_8UC3, cv::Scalar(255, 255, 255));
  picture(cv::Rect(24, 0, 24, 32)).setTo(cv::Scalar(0, 0, 0));
  REQUIRE(cv::imwrite((dir / "painted.png").string(), picture));
  const auto write_text = [](const std::filesystem::path& path, const std::string& text) {
    std::FILE* f = std::fopen(path.string().c_str(), "wb");
    REQUIRE(f != nullptr);
    std::fputs(text.c_str(), f);
    std::fclose(f);
  };
  const std::string quad =
      "v -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 0.1 0\nv -0.1 0.1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  write_text(dir / "sheet.mtl", "newmtl painted\nmap_Kd painted.png\n");
  write_text(dir / "sheet.obj", "mtllib sheet.mtl\n" + quad + "usemtl painted\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
  const io::LoadedMesh loaded = io::load_obj((dir / "sheet.obj").string());
  REQUIRE(loaded.base_colour_textures.size() == loaded.material_names.size());
  const cv::Mat read = base_colour_picture(loaded);
  CHECK(read.cols == 48);
  CHECK(read.rows == 32);
  CHECK_THAT(metres_per_uv(loaded.mesh), WithinRel(0.2, 1e-12));
  ModelTextureConfig config;
  config.tangible.size = 5;
  auto model = textured_model(loaded, config);
  (void)model.force(probe_at({-0.05, 0.0, 0.003}));
  double peak = 0.0, peak_x = 0.0;
  for (int tick = 0; tick < 1000; ++tick) {  // the drawn edge is at u = 0.5, x = 0
    const glm::dvec3 at{-0.05 + 1e-4 * tick, 0.0, -0.001};
    const glm::dvec3 f = model.force(probe_at(at, {0.1, 0.0, 0.0}));
    if (std::fabs(f.x) > peak) {
      peak = std::fabs(f.x);
      peak_x = at.x;
    }
  }
  CHECK(peak > 0.1);
  CHECK(std::fabs(peak_x) < 2.0 * 0.2 / 48.0);

  write_text(dir / "lost.mtl", "newmtl painted\nmap_Kd nowhere.png\n");
  write_text(dir / "lost.obj", "mtllib lost.mtl\n" + quad + "usemtl painted\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
  const io::LoadedMesh lost = io::load_obj((dir / "lost.obj").string());
  CHECK(lost.has_warning(io::MeshWarningKind::reader));
  CHECK_THROWS_WITH(textured_model(lost), Catch::Contains("has no base-colour texture"));
}

TEST_CASE("the Duck (glTF, embedded base-colour texture) is felt with its texture, without allocating") {
  const std::filesystem::path duck =
      std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data" / "gltf" / "Duck.gltf";
  if (!std::filesystem::exists(duck)) return;  // the real files are not part of the project
  const io::LoadedMesh loaded = io::load_gltf(duck.string());
  REQUIRE(loaded.base_colour_textures.size() == loaded.material_names.size() + (loaded.material_names.empty() ? 1 : 0));
  const cv::Mat picture = base_colour_picture(loaded);
  CHECK(picture.cols > 16);
  const double metres = metres_per_uv(loaded.mesh);
  std::cout << "Duck: " << loaded.mesh.triangle_count() << " triangles, texture " << picture.cols << " x "
            << picture.rows << " px, " << metres << " m per uv unit\n";
  // the texel where the picture's image force is largest, and the point of the duck that wears it
  const TangibleImage image(to_gray(picture), TangibleConfig{});
  glm::dvec2 best_px{0.0};
  double best = 0.0;
  for (int y = 0; y < picture.rows; y += 2)
    for (int x = 0; x < picture.cols; x += 2)
      if (const double m = glm::length(image.at(x, y)); m > best) {
        best = m;
        best_px = {x, y};
      }
  const glm::dvec2 uv{(best_px.x + 0.5) / picture.cols, 1.0 - (best_px.y + 0.5) / picture.rows};
  glm::dvec3 point{0.0}, normal{0.0}, along{0.0};
  for (const TriangleIndices& t : loaded.mesh.triangles) {
    const glm::dvec2 a = loaded.mesh.uvs[t[0]], b = loaded.mesh.uvs[t[1]], c = loaded.mesh.uvs[t[2]];
    const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if (std::fabs(det) < 1e-12) continue;
    const double wb = ((uv.x - a.x) * (c.y - a.y) - (c.x - a.x) * (uv.y - a.y)) / det;
    const double wc = ((b.x - a.x) * (uv.y - a.y) - (uv.x - a.x) * (b.y - a.y)) / det;
    if (wb < 0.0 || wc < 0.0 || wb + wc > 1.0) continue;
    const glm::dvec3 pa = loaded.mesh.positions[t[0]], pb = loaded.mesh.positions[t[1]],
                     pc = loaded.mesh.positions[t[2]];
    point = (1.0 - wb - wc) * pa + wb * pb + wc * pc;
    normal = glm::normalize(glm::cross(pb - pa, pc - pa));
    along = glm::normalize(pb - pa);
    break;
  }
  REQUIRE(glm::length(normal) > 0.5);
  INFO("image force " << best << " at texel (" << best_px.x << ", " << best_px.y << ")");
  ModelTextureConfig config;
  config.proxy.stiffness = 1000.0;
  config.texture_gain = 1.0;
  auto model = textured_model(loaded, config);
  (void)model.force(probe_at(point + 0.01 * normal));
  double texture = 0.0;
  int touching = 0;
  const long allocations = hapticfield::test::count_allocations([&] {
    for (int tick = 0; tick < 400; ++tick) {  // pressed 1 mm in, rubbing +-5 mm along the triangle
      const glm::dvec3 at = point - 0.001 * normal + 0.005 * std::sin(tick * 0.05) * along;
      const glm::dvec3 f = model.force(probe_at(at, 0.25 * std::cos(tick * 0.05) * along));
      if (!model.last_contact().touching) continue;
      ++touching;
      const glm::dvec3 n = model.last_contact().normal;
      const glm::dvec3 ft = f - model.last_contact().force;  // the texture's part
      texture = std::fmax(texture, glm::length(ft - glm::dot(ft, n) * n));
    }
  });
  INFO("touching ticks " << touching << ", largest texture force " << texture << " N");
  CHECK(touching > 390);
  CHECK_THAT(texture, WithinRel(best, 0.05));  // the felt texture is the picture's own force there (gain 1 N)
  if (hapticfield::test::allocations_counted) CHECK(allocations == 0);
}

// --- a model felt with its picture's relief ----------------------------------

#include "hapticfield/scenes/model_relief.hpp"

TEST_CASE("a model's relief: a gray ramp gives Fn = k (d + h(uv)) and a lean of (k d + k h) dh/dx downhill",
          "[material][relief]") {
  // a ramp 0..255 across 52 columns on a 0.2 m sheet: h is linear in u between the first and last texel
  // centres, so bilinear reads and one-texel central differences are exact there
  constexpr int width = 52;          // 255 / 51 = 5 levels a column: the ramp is exact in 8 bits
  constexpr double side = 0.2;       // [m]
  constexpr double height = 0.0005;  // [m] at white
  constexpr double k = 1200.0;       // [N/m]
  constexpr double depth = 0.001;    // [m]
  cv::Mat ramp(32, width, CV_8UC1);
  for (int x = 0; x < width; ++x)
    ramp.col(x).setTo(static_cast<double>(x) * 255.0 / (width - 1));
  ModelTextureConfig config;
  config.proxy.stiffness = k;
  config.texture_gain = 0.0;  // the relief alone
  auto model = relief_model(sheet_with_texture(ramp), height, config);
  const double slope = height / ((width - 1.0) / width * side);  // dh/dx [m/m]
  const std::uint32_t seed = hapticfield::test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> across(1.5 / width, 1.0 - 1.5 / width);  // both differences inside
  std::uniform_real_distribution<double> along(0.1, 0.9);
  for (int i = 0; i < 300; ++i) {
    const double u = across(rng);
    const double v = along(rng);
    const glm::dvec3 at{-side / 2 + u * side, -side / 2 + v * side, 0.0};
    model.reset();
    (void)model.force(probe_at(at + glm::dvec3{0, 0, 0.001}));
    const glm::dvec3 f = model.force(probe_at(at - glm::dvec3{0, 0, depth}));
    const double h = height * (u * width - 0.5) / (width - 1.0);  // the ramp's height at u [m]
    REQUIRE_THAT(f.z, WithinRel(k * (depth + h), 1e-6));          // heights held as floats
    REQUIRE_THAT(f.x, WithinRel(-(k * depth + k * h) * slope, 1e-6));
    REQUIRE_THAT(f.y, WithinAbs(0.0, 1e-9));
  }
  // out of contact: nothing; and no allocation while stroking
  model.reset();
  CHECK(glm::length(model.force(probe_at({0.0, 0.0, 0.01}))) == 0.0);
  const long allocations = hapticfield::test::count_allocations([&] {
    for (int tick = 0; tick < 400; ++tick)
      (void)model.force(probe_at({-0.08 + 0.0004 * tick, 0.0, -depth}, {0.4, 0.0, 0.0}));
  });
  if (hapticfield::test::allocations_counted) CHECK(allocations == 0);
  CHECK_THROWS_AS(relief_model(sheet_with_texture(ramp), -0.001, config), std::invalid_argument);
}
#endif
