// Tests of the height-map readers (io/height_map.hpp, OpenCV) and of
// HeightGrid (io/height_grid.hpp): pictures and 16-bit / float depth maps
// written here with known values come back as the heights they encode,
// bottom row first; hostile files (0 x 0, 20000 x 20000 declared in a
// 33-byte file, NaN heights, 8-bit or colour depth maps, OpenEXR) fail with
// one clear error.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <opencv2/imgcodecs.hpp>

#include "hapticfield/io/height_map.hpp"
#include "io_test_util.hpp"

using namespace hapticfield;
using namespace hapticfield::io;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using io_test::expect_file_error;

namespace {

/// A PNG signature and an IHDR chunk declaring w x h (CRC left zero): the
/// header check must refuse it before any decoder sees it.
std::string png_header(std::uint32_t w, std::uint32_t h) {
  std::string s("\x89PNG\r\n\x1A\n", 8);
  const auto be32 = [&s](std::uint32_t v) {
    for (int i = 3; i >= 0; --i)
      s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  };
  be32(13);
  s += "IHDR";
  be32(w);
  be32(h);
  s += std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit gray
  be32(0);
  return s;
}

}  // namespace

TEST_CASE("height maps: a 16-bit PNG and TIFF give value x metres_per_unit, bottom row first", "[io][height]") {
  const auto dir = io_test::temp_dir("height_16");
  cv::Mat depth(3, 4, CV_16UC1);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      depth.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(1000 * y + 10 * x + 60000 * (x == 3 && y == 0));
  for (const char* ext : {".png", ".tiff"}) {
    INFO(ext);
    const std::string path = (dir / (std::string("depth") + ext)).string();
    REQUIRE(cv::imwrite(path, depth));
    DepthMapConfig config;
    config.metres_per_unit = 1e-6;  // micrometres
    config.pixel_size = 2e-4;
    const HeightGrid g = load_depth_map(path, config);
    CHECK(g.width == 4);
    CHECK(g.height == 3);
    CHECK(g.spacing_x == 2e-4);
    CHECK(g.spacing_y == 2e-4);
    REQUIRE(g.heights.size() == 12);
    // grid row j is picture row 2 - j
    CHECK_THAT(g.at(0, 0), WithinAbs(2000e-6, 1e-15));
    CHECK_THAT(g.at(1, 2), WithinAbs(10e-6, 1e-15));
    CHECK_THAT(g.at(3, 2), WithinAbs(60030e-6, 1e-12));  // the top right pixel, near full scale
    CHECK_NOTHROW(g.validate());
  }
}

TEST_CASE("height maps: a float TIFF in metres, its NaN refused", "[io][height]") {
  const auto dir = io_test::temp_dir("height_float");
  cv::Mat depth(2, 3, CV_32FC1);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      depth.at<float>(y, x) = 0.001f * static_cast<float>(x) - 0.0005f * static_cast<float>(y);
  const std::string path = (dir / "depth.tiff").string();
  REQUIRE(cv::imwrite(path, depth));
  DepthMapConfig config;
  config.metres_per_unit = 1.0;
  const HeightGrid g = load_depth_map(path, config);
  CHECK(g.width == 3);
  CHECK(g.height == 2);
  CHECK_THAT(g.at(2, 1), WithinAbs(0.002, 1e-9));   // picture row 0
  CHECK_THAT(g.at(2, 0), WithinAbs(0.0015, 1e-9));  // picture row 1
  depth.at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
  REQUIRE(cv::imwrite(path, depth));
  expect_file_error([&] { (void)load_depth_map(path, config); }, path, "column 2, row 1 is not finite");
  depth.at<float>(1, 2) = std::numeric_limits<float>::infinity();
  REQUIRE(cv::imwrite(path, depth));
  expect_file_error([&] { (void)load_depth_map(path, config); }, path, "is not finite");
}

TEST_CASE("height maps: a picture's gray level x mm_per_level, dark high on request, blur", "[io][height]") {
  const auto dir = io_test::temp_dir("height_picture");
  cv::Mat picture(20, 20, CV_8UC1, cv::Scalar(0));
  picture(cv::Rect(10, 0, 10, 20)).setTo(200);  // the right half at level 200
  const std::string path = (dir / "step.png").string();
  REQUIRE(cv::imwrite(path, picture));
  PictureHeightConfig config;
  config.mm_per_level = 0.01;  // 200 levels: 2 mm
  config.pixel_size = 1e-4;
  const HeightGrid g = load_height_picture(path, config);
  CHECK(g.width == 20);
  CHECK(g.height == 20);
  CHECK_THAT(g.at(0, 5), WithinAbs(0.0, 1e-15));
  CHECK_THAT(g.at(15, 5), WithinAbs(0.002, 1e-12));
  config.dark_is_high = true;
  const HeightGrid d = load_height_picture(path, config);
  CHECK_THAT(d.at(0, 5), WithinAbs(0.00255, 1e-12));
  CHECK_THAT(d.at(15, 5), WithinAbs(0.00055, 1e-12));
  config.dark_is_high = false;
  config.blur_sigma = 2.0;
  const HeightGrid b = load_height_picture(path, config);
  CHECK(b.at(9, 5) > 0.0);
  CHECK(b.at(9, 5) < 0.001);  // the step's foot, softened
  CHECK(b.at(10, 5) > 0.001);
  CHECK_THAT(b.at(0, 5), WithinAbs(0.0, 1e-6));  // far from the step: unchanged
  CHECK_THAT(b.at(19, 5), WithinAbs(0.002, 1e-6));

  SECTION("the same from gray levels in memory") {
    GrayImage gray(2, 2, 100.0);
    gray.at(1, 0) = 0.0;  // top right
    const HeightGrid m = height_grid_from_gray(gray, PictureHeightConfig{});
    CHECK_THAT(m.at(1, 1), WithinAbs(0.0, 1e-15));
    CHECK_THAT(m.at(1, 0), WithinAbs(0.001, 1e-15));
    CHECK_THROWS_AS(height_grid_from_gray(GrayImage{}, PictureHeightConfig{}), std::invalid_argument);
  }
  SECTION("bad settings") {
    PictureHeightConfig bad;
    bad.mm_per_level = 0.0;
    CHECK_THROWS_AS(load_height_picture(path, bad), std::invalid_argument);
    bad = {};
    bad.blur_sigma = -1.0;
    CHECK_THROWS_AS(load_height_picture(path, bad), std::invalid_argument);
    DepthMapConfig dbad;
    dbad.metres_per_unit = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(load_depth_map(path, dbad), std::invalid_argument);
  }
}

TEST_CASE("height maps: hostile files fail with one clear error", "[io][height][hostile]") {
  const auto dir = io_test::temp_dir("height_hostile");
  SECTION("a header declaring 0 x 0") {
    const auto p = io_test::write(dir / "zero.png", png_header(0, 0));
    expect_file_error([&] { (void)load_depth_map(p); }, p, "declares 0 x 0 px");
    expect_file_error([&] { (void)load_height_picture(p); }, p, "declares 0 x 0 px");
  }
  SECTION("fewer than 2 x 2 px: the error names the file") {
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{1, 5}, std::pair{7, 1}}) {
      const std::string size = std::to_string(w) + " x " + std::to_string(h) + " px";
      const std::string p = (dir / ("thin_" + std::to_string(w) + "x" + std::to_string(h) + ".png")).string();
      REQUIRE(cv::imwrite(p, cv::Mat(h, w, CV_16UC1, cv::Scalar(5))));
      expect_file_error([&] { (void)load_depth_map(p); }, p, size + "; a height map needs at least 2 x 2 px");
      expect_file_error([&] { (void)load_height_picture(p); }, p, size + "; a height map needs at least 2 x 2 px");
    }
    CHECK_THROWS_WITH(height_grid_from_depth(cv::Mat(1, 1, CV_32FC1, cv::Scalar(0.5)), "one.tiff"),
                      Contains("'one.tiff'") && Contains("1 x 1 px"));
  }
  SECTION("20000 x 20000 px (400 Mpx) declared in 33 bytes is refused from the header") {
    const auto p = io_test::write(dir / "huge.png", png_header(20000, 20000));
    expect_file_error([&] { (void)load_depth_map(p); }, p, "larger than the limit of 100000000 px");
    expect_file_error([&] { (void)load_height_picture(p); }, p, "larger than the limit of 100000000 px");
  }
  SECTION("a limit of one's own") {
    cv::Mat small(10, 10, CV_16UC1, cv::Scalar(5));
    const std::string p = (dir / "small.png").string();
    REQUIRE(cv::imwrite(p, small));
    DepthMapConfig config;
    config.max_pixels = 99;
    expect_file_error([&] { (void)load_depth_map(p, config); }, p, "limit of 99 px");
  }
  SECTION("an 8-bit picture or a colour picture as a depth map") {
    const std::string p8 = (dir / "gray8.png").string();
    REQUIRE(cv::imwrite(p8, cv::Mat(4, 4, CV_8UC1, cv::Scalar(7))));
    expect_file_error([&] { (void)load_depth_map(p8); }, p8, "8-bit levels");
    const std::string p3 = (dir / "colour16.png").string();
    REQUIRE(cv::imwrite(p3, cv::Mat(4, 4, CV_16UC3, cv::Scalar(7, 7, 7))));
    expect_file_error([&] { (void)load_depth_map(p3); }, p3, "3 channels");
  }
  SECTION("OpenEXR is refused by name") {
    const auto p = io_test::write(dir / "depth.EXR", "v/1\x01");
    expect_file_error([&] { (void)load_depth_map(p); }, p, "OpenEXR");
  }
  SECTION("not a picture, and a truncated one") {
    const auto p = io_test::write(dir / "text.png", "not a picture");
    expect_file_error([&] { (void)load_depth_map(p); }, p, "cannot decode");
    cv::Mat depth(64, 64, CV_16UC1, cv::Scalar(300));
    std::vector<unsigned char> bytes;
    REQUIRE(cv::imencode(".png", depth, bytes));
    const auto q = io_test::write(dir / "cut.png", std::string(bytes.begin(), bytes.begin() + 60));
    expect_file_error([&] { (void)load_depth_map(q); }, q, "cut.png");
  }
  SECTION("a missing file") {
    const std::string p = (dir / "absent.png").string();
    expect_file_error([&] { (void)load_depth_map(p); }, p, "no such file");
  }
}

TEST_CASE("HeightGrid::validate names the first problem", "[io][height]") {
  HeightGrid g{2, 2, 1e-3, 1e-3, {0.0, 0.1, 0.2, 0.3}};
  CHECK_NOTHROW(g.validate());
  CHECK(g.at(1, 1) == 0.3);
  HeightGrid empty{0, 0, 1e-3, 1e-3, {}};
  CHECK_THROWS_WITH(empty.validate(), Contains("size must be positive"));
  HeightGrid nan = g;
  nan.heights[2] = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(nan.validate(), Contains("column 0, row 1 is not finite"));
  HeightGrid short_ = g;
  short_.heights.pop_back();
  CHECK_THROWS_WITH(short_.validate(), Contains("3 heights for 2 x 2"));
  HeightGrid spacing = g;
  spacing.spacing_y = 0.0;
  CHECK_THROWS_WITH(spacing.validate(), Contains("spacings"));
}
