// Tests of gray conversion and picture loading.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/image.hpp"

using namespace hapticfield;

namespace {

std::string tmp_path(const std::string& name) {
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  return (std::filesystem::path(HAPTICFIELD_TEST_TMP) / name).string();
}

cv::Mat random_bgr(int width, int height, unsigned seed) {
  cv::theRNG().state = seed;
  cv::Mat m(height, width, CV_8UC3);
  cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(256));
  return m;
}

}  // namespace

TEST_CASE("paper weights: Y = 0.3 R + 0.59 G + 0.11 B, not rounded") {
  cv::Mat pixel(1, 1, CV_8UC3, cv::Scalar(7, 100, 201));  // B, G, R
  const GrayImage g = to_gray(pixel, GrayWeights::paper);
  CHECK(g.at(0, 0) == Approx(0.3 * 201 + 0.59 * 100 + 0.11 * 7).epsilon(1e-15));
  CHECK(g.at(0, 0) != std::round(g.at(0, 0)));  // 119.07: kept in floating point
  const GrayImage b = to_gray(pixel, GrayWeights::bt601);
  CHECK(b.at(0, 0) == Approx(0.299 * 201 + 0.587 * 100 + 0.114 * 7).epsilon(1e-15));
}

TEST_CASE("BT.601 weights agree with cv::cvtColor to its rounding") {
  // cvtColor rounds to whole levels with 14-bit fixed-point weights
  // (4899, 9617, 1868) / 16384: 0.5 level plus at most 255 x 5e-5.
  const cv::Mat bgr = random_bgr(64, 48, 5);
  cv::Mat reference;
  cv::cvtColor(bgr, reference, cv::COLOR_BGR2GRAY);
  const GrayImage g = to_gray(bgr, GrayWeights::bt601);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      REQUIRE(std::abs(g.at(x, y) - reference.at<unsigned char>(y, x)) <= 0.5 + 0.013);
}

TEST_CASE("1-, 3- and 4-channel, 8- and 16-bit pictures convert alike") {
  const cv::Mat bgr = random_bgr(32, 24, 9);
  const GrayImage reference = to_gray(bgr);

  cv::Mat bgra;
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  std::vector<cv::Mat> planes;
  cv::split(bgra, planes);
  cv::randu(planes[3], 0, 256);  // alpha is ignored whatever it holds
  cv::merge(planes, bgra);
  const GrayImage from_bgra = to_gray(bgra);

  cv::Mat bgr16;
  bgr.convertTo(bgr16, CV_16U, 257.0);  // 255 -> 65535 exactly
  const GrayImage from_16 = to_gray(bgr16);

  cv::Mat one_channel(24, 32, CV_8UC1, cv::Scalar(77));
  const GrayImage from_gray = to_gray(one_channel);

  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      REQUIRE(from_bgra.at(x, y) == reference.at(x, y));
      REQUIRE(from_16.at(x, y) == Approx(reference.at(x, y)).epsilon(1e-12));
      REQUIRE(from_gray.at(x, y) == 77.0);
    }
}

TEST_CASE("inversion is 255 - Y") {
  GrayImage g(3, 1);
  g.at(0, 0) = 0.0;
  g.at(1, 0) = 100.25;
  g.at(2, 0) = 255.0;
  const GrayImage inv = inverted(g);
  CHECK(inv.at(0, 0) == 255.0);
  CHECK(inv.at(1, 0) == 154.75);
  CHECK(inv.at(2, 0) == 0.0);
}

TEST_CASE("loading keeps 16-bit depth and alpha") {
  const cv::Mat bgr = random_bgr(20, 10, 3);
  cv::Mat bgr16;
  bgr.convertTo(bgr16, CV_16U, 257.0);
  const std::string p16 = tmp_path("sixteen.png");
  REQUIRE(cv::imwrite(p16, bgr16));
  const cv::Mat loaded = load_image(p16);
  CHECK(loaded.depth() == CV_16U);
  const GrayImage a = load_gray(p16);
  const GrayImage b = to_gray(bgr);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x)
      REQUIRE(a.at(x, y) == Approx(b.at(x, y)).epsilon(1e-12));

  cv::Mat bgra;
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  const std::string p4 = tmp_path("four.png");
  REQUIRE(cv::imwrite(p4, bgra));
  CHECK(load_image(p4).channels() == 4);
  CHECK(load_gray(p4).at(3, 4) == b.at(3, 4));
}

TEST_CASE("bad pictures give a clear ImageError") {
  CHECK_THROWS_WITH(load_image(tmp_path("does-not-exist.png")), Catch::Contains("no such file"));
  CHECK_THROWS_WITH(load_image(HAPTICFIELD_TEST_TMP), Catch::Contains("not a regular file"));

  const std::string corrupt = tmp_path("corrupt.png");
  {
    std::ofstream out(corrupt, std::ios::binary);
    out << "\x89PNG\r\n\x1a\n this is not really a picture";
  }
  CHECK_THROWS_WITH(load_image(corrupt), Catch::Contains("cannot decode"));
  CHECK_THROWS_AS(load_gray(corrupt), ImageError);

  const std::string empty = tmp_path("empty.png");
  { std::ofstream out(empty, std::ios::binary); }
  CHECK_THROWS_WITH(load_gray(empty), Catch::Contains("cannot decode"));

  CHECK_THROWS_WITH(to_gray(cv::Mat()), Catch::Contains("empty"));
  CHECK_THROWS_WITH(to_gray(cv::Mat(4, 4, CV_32FC1, cv::Scalar(0.5))), Catch::Contains("8- or 16-bit"));
  CHECK_THROWS_WITH(to_gray(cv::Mat(4, 4, CV_8UC2, cv::Scalar::all(1))), Catch::Contains("1, 3 or 4 channels"));

  // a 1 x 1 picture loads; it is the kernels that refuse it (test_kernels)
  const std::string tiny = tmp_path("tiny.png");
  REQUIRE(cv::imwrite(tiny, cv::Mat(1, 1, CV_8UC1, cv::Scalar(9))));
  const GrayImage one = load_gray(tiny);
  CHECK(one.width() == 1);
  CHECK(one.at(0, 0) == 9.0);
}

namespace {

/// A PNG of 8 bytes of signature and an IHDR chunk that declares width x
/// height px of 8-bit gray, followed by a truncated IDAT: 45 bytes that a
/// decoder would answer by allocating width x height bytes.
std::string crafted_png(const std::string& name, std::uint32_t width, std::uint32_t height) {
  const std::string path = tmp_path(name);
  std::ofstream out(path, std::ios::binary);
  const auto be32 = [&out](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8)
      out.put(static_cast<char>((v >> s) & 0xFF));
  };
  out.write("\x89PNG\r\n\x1a\n", 8);
  be32(13);
  out.write("IHDR", 4);
  be32(width);
  be32(height);
  out.write("\x08\x00\x00\x00\x00", 5);  // 8-bit gray, deflate, no filter, no interlace
  be32(0);                               // CRC (never reached)
  be32(100);
  out.write("IDAT", 4);
  out.write("\x78\x9c", 2);
  return path;
}

}  // namespace

TEST_CASE("the picture size is read from the header, every format OpenCV writes") {
  const cv::Mat picture = random_bgr(123, 45, 7);
  cv::Mat gray;
  cv::cvtColor(picture, gray, cv::COLOR_BGR2GRAY);
  struct Case {
    std::string name;
    cv::Mat mat;
  };
  const std::vector<Case> cases = {{"size.png", picture},  {"size.jpg", picture}, {"size.bmp", picture},
                                   {"size.tiff", picture}, {"size.ppm", picture}, {"size.pgm", gray},
                                   {"size.pbm", gray},     {"size.pam", picture}};
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const std::string path = tmp_path(c.name);
    REQUIRE(cv::imwrite(path, c.mat));
    const std::optional<PictureSize> size = read_picture_size(path);
    REQUIRE(size.has_value());
    CHECK(size->width == 123);
    CHECK(size->height == 45);
    // the limit is inclusive: exactly 123 x 45 px loads, one pixel less refuses
    CHECK(load_image(path, 123 * 45).cols == 123);
    CHECK_THROWS_WITH(load_image(path, 123 * 45 - 1),
                      Catch::Contains("123 x 45 px") && Catch::Contains("limit of 5534 px") && Catch::Contains(c.name));
    CHECK_THROWS_AS(load_gray(path, GrayWeights::paper, 100), ImageError);
  }
  // a format the header reader does not parse is checked after decoding
  const std::string webp = tmp_path("size.webp");
  if (cv::imwrite(webp, picture)) {
    CHECK_FALSE(read_picture_size(webp).has_value());
    CHECK_THROWS_WITH(load_image(webp, 1000), Catch::Contains("123 x 45 px"));
    CHECK(load_image(webp).cols == 123);
  }
}

TEST_CASE("a small file that declares a huge picture fails before decoding") {
  // 20000 x 20000 px in 45 bytes: decoding would allocate 400 MB for the
  // 8-bit plane alone (and a tangible image many times that).
  const std::string huge = crafted_png("huge.png", 20000, 20000);
  REQUIRE(std::filesystem::file_size(huge) < 64);
  CHECK_THROWS_AS(load_image(huge), ImageError);
  CHECK_THROWS_WITH(load_gray(huge), Catch::Contains("huge.png") && Catch::Contains("20000 x 20000 px") &&
                                         Catch::Contains("limit of 100000000 px"));
  // the largest PNG dimensions (2^31 - 1 each) do not overflow the product
  CHECK_THROWS_WITH(load_image(crafted_png("widest.png", 0x7fffffff, 0x7fffffff)),
                    Catch::Contains("2147483647 x 2147483647 px"));
  // raising the limit lets the header pass; the truncated data then fails to decode
  CHECK_THROWS_WITH(load_image(crafted_png("small.png", 20, 20), 400), Catch::Contains("cannot decode"));
  // zero sizes are malformed headers
  CHECK_THROWS_WITH(load_image(crafted_png("zero.png", 0, 20)), Catch::Contains("declares 0 x 20 px"));
  // a Netpbm text header declaring 1e9 x 1e9 px
  const std::string pgm = tmp_path("huge.pgm");
  {
    std::ofstream out(pgm, std::ios::binary);
    out << "P5\n# a comment\n1000000000 1000000000\n255\n\x01\x02";
  }
  CHECK_THROWS_WITH(load_image(pgm), Catch::Contains("1000000000 x 1000000000 px"));
}
