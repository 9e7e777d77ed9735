// Tests of the tangible-image kernels: masks, direct and O(1) kernels,
// interpolation, borders, force maps and the field.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/kernels.hpp"

using namespace hapticfield;

namespace {

/// A seeded picture with smooth shapes and noise, gray levels in [0, 255].
GrayImage test_picture(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-20.0, 20.0);
  GrayImage g(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double shape = 128.0 + 90.0 * std::sin(x * 0.11) * std::cos(y * 0.07) + (x > width / 2 ? 20.0 : -20.0);
      g.at(x, y) = std::clamp(shape + noise(rng), 0.0, 255.0);
    }
  return g;
}

/// Black/white step: white left of column edge, black from it on.
GrayImage step_picture(int width, int height, int edge) {
  GrayImage g(width, height, 255.0);
  for (int y = 0; y < height; ++y)
    for (int x = edge; x < width; ++x)
      g.at(x, y) = 0.0;
  return g;
}

cv::Mat weights_mat(const Mask<>& mask, bool y) {
  cv::Mat k(mask.size(), mask.size(), CV_64FC1);
  for (int r = 0; r < mask.size(); ++r)
    for (int c = 0; c < mask.size(); ++c)
      k.at<double>(r, c) = y ? mask.y(r, c) : mask.x(r, c);
  return k;
}

int cv_border(Border b) {
  return b == Border::reflect ? cv::BORDER_REFLECT_101 : cv::BORDER_REPLICATE;
}

struct MaskCase {
  MaskKind kind;
  int size;
};

const std::vector<MaskCase> all_masks = {
    {MaskKind::prewitt, 3}, {MaskKind::prewitt, 5},  {MaskKind::prewitt, 17},  {MaskKind::prewitt, 33},
    {MaskKind::sobel, 3},   {MaskKind::sobel, 5},    {MaskKind::sobel, 7},     {MaskKind::scharr, 3},
    {MaskKind::roberts, 2}, {MaskKind::gaussian, 5}, {MaskKind::gaussian, 17}, {MaskKind::emboss, 3},
    {MaskKind::emboss, 9},  {MaskKind::emboss, 33},
};

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
constexpr double infinity = std::numeric_limits<double>::infinity();

}  // namespace

TEST_CASE("every mask kind has a name and a default size that it accepts") {
  std::set<std::string> names;
  for (const MaskKind kind : mask_kinds) {
    names.insert(to_string(kind));
    CHECK_NOTHROW(validate_mask_size(kind, default_mask_size(kind)));
  }
  CHECK(names.size() == mask_kinds.size());
  CHECK(names.count("?") == 0);
  CHECK(default_mask_size(MaskKind::roberts) == 2);
  CHECK(default_mask_size(MaskKind::scharr) == 3);
  CHECK(default_mask_size(MaskKind::prewitt) == TangibleConfig{}.size);
  std::set<std::string> borders;
  for (const Border b : border_kinds)
    borders.insert(to_string(b));
  CHECK(borders.size() == border_kinds.size());
  CHECK(borders.count("?") == 0);
}

TEST_CASE("Prewitt weights are column - centre, y the transpose") {
  const auto m = Mask<5>::prewitt();
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) {
      CHECK(m.x(r, c) == c - 2);
      CHECK(m.y(r, c) == r - 2);
    }
  // 255 x (sum of positive weights) = 255 x 5 rows x (1 + 2)
  CHECK(m.step_response() == 255.0 * 15.0);
  STATIC_REQUIRE(sizeof(Mask<129>) > 129 * 129 * sizeof(double));  // fixed storage at compile time
}

TEST_CASE("Sobel weights equal OpenCV's getDerivKernels") {
  for (int size : {3, 5, 7, 9, 15, 31}) {
    CAPTURE(size);
    cv::Mat kx;
    cv::Mat ky;
    cv::getDerivKernels(kx, ky, 1, 0, size, false, CV_64F);
    const auto m = Mask<>::sobel(size);
    for (int r = 0; r < size; ++r)
      for (int c = 0; c < size; ++c)
        REQUIRE(m.x(r, c) == Approx(kx.at<double>(c) * ky.at<double>(r)));
  }
  const auto scharr = Mask<3>::scharr();
  cv::Mat kx;
  cv::Mat ky;
  cv::getDerivKernels(kx, ky, 1, 0, cv::FILTER_SCHARR, false, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      CHECK(scharr.x(r, c) == Approx(kx.at<double>(c) * ky.at<double>(r)));
}

TEST_CASE("the direct kernel equals cv::filter2D on the inverted image") {
  const GrayImage gray = test_picture(97, 83, 7);
  const GrayImage inv = inverted(gray);
  const cv::Mat inv_mat = to_mat(inv);
  std::mt19937 rng(11);
  for (const MaskCase& mc : all_masks) {
    for (Border border : {Border::clamp, Border::reflect, Border::suspend}) {
      CAPTURE(to_string(mc.kind), mc.size, to_string(border));
      const auto mask = Mask<>::make(mc.kind, mc.size, 2.5);
      const DirectKernel<> kernel(inv, mask, border);
      cv::Mat fx;
      cv::Mat fy;
      cv::filter2D(inv_mat, fx, CV_64F, weights_mat(mask, false), cv::Point(-1, -1), 0.0, cv_border(border));
      cv::filter2D(inv_mat, fy, CV_64F, weights_mat(mask, true), cv::Point(-1, -1), 0.0, cv_border(border));
      const ImageForce<DirectKernel<>> sampler(kernel);
      for (int i = 0; i < 200; ++i) {
        const int x = std::uniform_int_distribution<int>(0, gray.width() - 1)(rng);
        const int y = std::uniform_int_distribution<int>(0, gray.height() - 1)(rng);
        if (!sampler.in_domain(x, y)) continue;  // suspend: only where the mask fits
        const glm::dvec2 f = kernel.at_pixel(x, y);
        REQUIRE(f.x == Approx(fx.at<double>(y, x) / mask.step_response()).margin(1e-12));
        REQUIRE(f.y == Approx(fy.at<double>(y, x) / mask.step_response()).margin(1e-12));
      }
    }
  }
}

TEST_CASE("compile-time and run-time mask sizes give the same kernel") {
  const GrayImage inv = inverted(test_picture(40, 40, 3));
  const DirectKernel<7> fixed(inv, Mask<7>::sobel(), Border::clamp);
  const DirectKernel<> dynamic(inv, Mask<>::sobel(7), Border::clamp);
  for (int y = 0; y < 40; y += 3)
    for (int x = 0; x < 40; x += 3)
      REQUIRE(fixed.at_pixel(x, y) == dynamic.at_pixel(x, y));
}

TEST_CASE("the O(1) integral kernel equals the direct kernel to 1e-9 of full scale") {
  const GrayImage gray = test_picture(300, 280, 5);
  const GrayImage inv = inverted(gray);
  std::mt19937 rng(13);
  for (MaskKind kind : {MaskKind::prewitt, MaskKind::emboss}) {
    for (int size : {3, 5, 17, 33, 65, 129}) {
      for (Border border : {Border::suspend, Border::clamp, Border::reflect}) {
        CAPTURE(to_string(kind), size, to_string(border));
        const DirectKernel<> direct(inv, Mask<>::make(kind, size), border);
        const IntegralKernel fast(inv, kind, size, border);
        const ImageForce<IntegralKernel> sampler(fast);
        for (int i = 0; i < 300; ++i) {
          const int x = std::uniform_int_distribution<int>(0, gray.width() - 1)(rng);
          const int y = std::uniform_int_distribution<int>(0, gray.height() - 1)(rng);
          if (!sampler.in_domain(x, y)) continue;
          const glm::dvec2 a = direct.at_pixel(x, y);
          const glm::dvec2 b = fast.at_pixel(x, y);
          REQUIRE(std::abs(a.x - b.x) <= 1e-9);
          REQUIRE(std::abs(a.y - b.y) <= 1e-9);
        }
      }
    }
  }
}

TEST_CASE("the O(1) kernel rounds levels outside [0, 255] as the direct kernel sees them") {
  // Negative levels and levels on a half step take the tables' other
  // rounding branch; the force still equals the direct kernel's.
  GrayImage inv(90, 70);
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> level(-60.0, 320.0);
  for (int y = 0; y < inv.height(); ++y)
    for (int x = 0; x < inv.width(); ++x)
      inv.at(x, y) = (x + y) % 7 == 0 ? std::floor(level(rng)) + 0.5 : level(rng);
  for (MaskKind kind : {MaskKind::prewitt, MaskKind::emboss})
    for (Border border : {Border::suspend, Border::clamp, Border::reflect}) {
      CAPTURE(to_string(kind), to_string(border));
      const DirectKernel<> direct(inv, Mask<>::make(kind, 9), border);
      const IntegralKernel fast(inv, kind, 9, border);
      const ImageForce<IntegralKernel> sampler(fast);
      for (int y = 0; y < inv.height(); y += 3)
        for (int x = 0; x < inv.width(); x += 3) {
          if (!sampler.in_domain(x, y)) continue;
          REQUIRE(std::abs(direct.at_pixel(x, y).x - fast.at_pixel(x, y).x) <= 1e-9);
          REQUIRE(std::abs(direct.at_pixel(x, y).y - fast.at_pixel(x, y).y) <= 1e-9);
        }
    }
}

TEST_CASE("the O(1) kernel is exact on 8-bit gray and on colour through the paper's or BT.601 weights") {
  // Integer tables hold P D exactly (D = 1, 100, 1000), so the O(1) force
  // equals the direct kernel to the direct kernel's own double rounding.
  cv::theRNG().state = 21;
  cv::Mat colour(150, 170, CV_8UC3);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(256));
  cv::GaussianBlur(colour, colour, cv::Size(0, 0), 2.0);  // photograph-like: smooth plus edges
  cv::Mat eight;
  cv::cvtColor(colour, eight, cv::COLOR_BGR2GRAY);
  struct Picture {
    const char* name;
    GrayImage gray;
  };
  const std::vector<Picture> pictures = {{"8-bit gray", to_gray(eight)},
                                         {"colour, paper weights", to_gray(colour, GrayWeights::paper)},
                                         {"colour, BT.601", to_gray(colour, GrayWeights::bt601)}};
  std::mt19937 rng(17);
  for (const Picture& p : pictures) {
    const GrayImage inv = inverted(p.gray);
    for (MaskKind kind : {MaskKind::prewitt, MaskKind::emboss}) {
      for (int size : {3, 17, 33, 65, 129}) {
        for (Border border : {Border::suspend, Border::clamp, Border::reflect}) {
          CAPTURE(p.name, to_string(kind), size, to_string(border));
          const DirectKernel<> direct(inv, Mask<>::make(kind, size), border);
          const IntegralKernel fast(inv, kind, size, border);
          const ImageForce<IntegralKernel> sampler(fast);
          // 12-byte cells where the force bound fits 31 bits (see integral_kernel.hpp)
          const bool narrow = std::string(p.name) == "8-bit gray" ||
                              (std::string(p.name) == "colour, paper weights" && size <= 65) || size <= 17;
          CHECK(fast.bytes_per_cell() == (narrow ? 12u : 24u));
          double worst = 0.0;
          for (int i = 0; i < 400; ++i) {
            const int x = std::uniform_int_distribution<int>(0, inv.width() - 1)(rng);
            const int y = std::uniform_int_distribution<int>(0, inv.height() - 1)(rng);
            if (!sampler.in_domain(x, y)) continue;
            const glm::dvec2 a = direct.at_pixel(x, y);
            const glm::dvec2 b = fast.at_pixel(x, y);
            worst = std::max({worst, std::abs(a.x - b.x), std::abs(a.y - b.y)});
          }
          CHECK(worst <= 1e-13);
        }
      }
    }
  }
}

TEST_CASE("a black/white step edge gives magnitude 1 toward black, for every mask") {
  const GrayImage step = step_picture(64, 48, 32);  // black from column 32 on
  for (const MaskCase& mc : all_masks) {
    CAPTURE(to_string(mc.kind), mc.size);
    const TangibleImage image(step, {mc.kind, mc.size, 3.0, Border::suspend, 8.0, KernelChoice::direct});
    const glm::dvec2 f = image.at(32.0, 24.0);
    CHECK(f.x == Approx(1.0).epsilon(1e-12));
    CHECK(f.y == Approx(0.0).margin(1e-12));
    // The edge turned by 90 degrees: black below row 24 points down (+y).
    GrayImage turned(48, 64, 255.0);
    for (int y = 24; y < 64; ++y)
      for (int x = 0; x < 48; ++x)
        turned.at(x, y) = 0.0;
    const TangibleImage down(turned, {mc.kind, mc.size, 3.0, Border::suspend, 8.0, KernelChoice::direct});
    CHECK(down.at(20.0, 24.0).y == Approx(1.0).epsilon(1e-12));
    CHECK(down.at(20.0, 24.0).x == Approx(0.0).margin(1e-12));
  }
}

TEST_CASE("contrast scales the force linearly") {
  const GrayImage gray = test_picture(120, 90, 9);
  const TangibleImage full(gray, {});
  for (double contrast : {0.25, 0.5, 0.8}) {
    GrayImage low(gray.width(), gray.height());
    for (int y = 0; y < gray.height(); ++y)
      for (int x = 0; x < gray.width(); ++x)
        low.at(x, y) = 128.0 + contrast * (gray.at(x, y) - 128.0);
    const TangibleImage scaled(low, {});
    for (double x = 10.3; x < 110.0; x += 7.9) {
      const glm::dvec2 a = full.at(x, 45.6);
      const glm::dvec2 b = scaled.at(x, 45.6);
      REQUIRE(b.x == Approx(contrast * a.x).margin(1e-12));
      REQUIRE(b.y == Approx(contrast * a.y).margin(1e-12));
    }
  }
}

TEST_CASE("forces are continuous between pixel centres") {
  const GrayImage gray = test_picture(200, 150, 21);
  for (MaskKind kind : {MaskKind::prewitt, MaskKind::sobel, MaskKind::roberts}) {
    for (Border border : {Border::suspend, Border::clamp, Border::reflect, Border::fade}) {
      CAPTURE(to_string(kind), to_string(border));
      TangibleConfig o;
      o.mask = kind;
      o.size = kind == MaskKind::roberts ? 2 : (kind == MaskKind::sobel ? 5 : 9);
      o.border = border;
      const TangibleImage image(gray, o);
      std::mt19937 rng(3);
      std::uniform_real_distribution<double> ux(-0.5, 199.5);
      std::uniform_real_distribution<double> uy(-0.5, 149.5);
      for (int i = 0; i < 3000; ++i) {
        const double x = ux(rng);
        const double y = uy(rng);
        const glm::dvec2 a = image.at(x, y);
        const glm::dvec2 b = image.at(x + 1e-3, y + 1e-3);
        // two neighbouring pixel forces differ by at most 2, so 1e-3 px moves
        // the interpolated force by at most 2 x 2e-3
        REQUIRE(std::abs(a.x - b.x) <= 4e-3);
        REQUIRE(std::abs(a.y - b.y) <= 4e-3);
      }
      // at a pixel centre the interpolation returns that pixel's force exactly
      CHECK(image.at(100.0, 75.0) == image.at_pixel(100, 75));
    }
  }
}

TEST_CASE("border policies") {
  const GrayImage gray = test_picture(60, 50, 2);
  TangibleConfig o;
  o.size = 9;  // anchor 4: the mask fits for pixel centres 4 .. width - 5

  SECTION("suspend: the kernel's force where the mask fits, faded out over fade_px beyond") {
    o.border = Border::suspend;
    o.fade_px = 4.0;
    const TangibleImage image(gray, o);
    const glm::dvec2 last = image.at(4.0, 20.0);  // last full-mask column
    CHECK(last != glm::dvec2{0.0});
    CHECK(image.at(3.0, 20.0) == last * 0.75);  // 1 px beyond: 1 - 1/4 of the edge force
    CHECK(image.at(2.0, 20.0) == last * 0.5);
    CHECK(image.at(0.0, 20.0) == glm::dvec2{0.0});   // 4 px beyond: nothing
    CHECK(image.at(59.0, 20.0) == glm::dvec2{0.0});  // last full-mask column 55, row 45
    CHECK(image.at(20.0, 49.0) == glm::dvec2{0.0});
    CHECK(image.at(20.0, 47.0) == image.at(20.0, 45.0) * 0.5);
    // across a corner the distance is Euclidean: (3, 3) is sqrt(2) px from (4, 4)
    CHECK(image.at(3.0, 3.0).x == Approx(image.at(4.0, 4.0).x * (1.0 - std::sqrt(2.0) / 4.0)));
    CHECK(image.at_pixel(3, 20) == image.at(3.0, 20.0));
  }
  SECTION("clamp and reflect: the kernel up to the picture's edge, faded out over fade_px outside") {
    for (Border b : {Border::clamp, Border::reflect}) {
      o.border = b;
      const TangibleImage image(gray, o);  // fade_px 10
      const glm::dvec2 edge = image.at(0.0, 20.0);
      CHECK(edge != glm::dvec2{0.0});
      CHECK(image.at(-0.5, 20.0) == edge * 0.95);
      CHECK(image.at(-5.0, 20.0) == edge * 0.5);
      CHECK(image.at(-10.0, 20.0) == glm::dvec2{0.0});
      CHECK(image.at(59.0, 20.0) != glm::dvec2{0.0});  // (reflect mirrors a corner's patch: 0 there)
      CHECK(image.at(64.0, 20.0) == image.at(59.0, 20.0) * 0.5);
    }
  }
  SECTION("fade: a linear ramp over the last k pixels") {
    o.border = Border::fade;
    o.fade_px = 10.0;
    const TangibleImage faded(gray, o);
    o.border = Border::suspend;
    const TangibleImage hard(gray, o);
    // anchor 4 is the last full-mask column; 5 px inside is half way up the ramp
    CHECK(faded.at(4.0, 25.0) == glm::dvec2{0.0});
    CHECK(faded.at(9.0, 25.0).x == Approx(0.5 * hard.at(9.0, 25.0).x));
    CHECK(faded.at(14.0, 25.0) == hard.at(14.0, 25.0));
    CHECK(faded.at(30.0, 25.0) == hard.at(30.0, 25.0));
  }
}

namespace {

/// Real photographs to stroke: the shipped one, and any found in installed
/// packages (OpenCV samples, scikit-image data).
std::vector<std::string> real_photographs() {
  std::vector<std::string> found = {std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png"};
  // opencv-doc installs the samples under /usr/share/doc; older packages
  // under /usr/share/opencv4. One folder is enough.
  const char* folders[] = {"/usr/share/doc/opencv-doc/examples/data", "/usr/share/opencv4/samples/data"};
  for (const char* folder : folders) {
    const std::size_t before = found.size();
    for (const char* name : {"fruits.jpg", "baboon.jpg", "building.jpg"})
      if (std::filesystem::exists(std::filesystem::path(folder) / name))
        found.push_back((std::filesystem::path(folder) / name).string());
    if (found.size() > before) break;
  }
  for (const char* c : {"/usr/lib/python3/dist-packages/skimage/data/astronaut.png",
                        "/usr/lib/python3/dist-packages/skimage/data/camera.png"})
    if (std::filesystem::exists(c)) found.emplace_back(c);
  if (found.size() == 1)
    WARN("only examples/data/coffee.png is stroked: no OpenCV sample or scikit-image pictures are installed");
  return found;
}

}  // namespace

TEST_CASE("leaving a real photograph is never a step, for every border policy and mask size") {
  // A HIP crossing the edge at 0.64 px per sample (a servo tick). Outside the
  // kernel's domain the force must change by less than the force JND, 7% of
  // the largest force in the picture, per sample. Where the kernel itself
  // varies (an oblique exit slides along the edge; the fade band lies over
  // the picture) the bound is that variation plus 7%: R below is the same
  // field with the policy's fades removed, evaluated at the nearest domain
  // point, so |F1 - F0| <= |R1 - R0| + 7% is exactly "the border policy
  // adds no more than the JND".
  constexpr double step_px = 0.64;
  constexpr double jnd = 0.07;
  for (const std::string& path : real_photographs()) {
    const GrayImage gray = load_gray(path);
    const double w = gray.width();
    const double h = gray.height();
    for (const Border border : {Border::suspend, Border::clamp, Border::reflect, Border::fade}) {
      for (const MaskCase mc : std::vector<MaskCase>{{MaskKind::prewitt, 3},
                                                     {MaskKind::prewitt, 5},
                                                     {MaskKind::prewitt, 17},
                                                     {MaskKind::prewitt, 33},
                                                     {MaskKind::prewitt, 65},
                                                     {MaskKind::sobel, 5},
                                                     {MaskKind::gaussian, 9}}) {
        CAPTURE(path, to_string(border), to_string(mc.kind), mc.size);
        TangibleConfig o{mc.kind, mc.size, 0.0, border};
        const TangibleImage image(gray, o);
        o.border = border == Border::fade ? Border::suspend : border;  // same domain, no fade
        const TangibleImage raw(gray, o);
        const double largest = force_map(image).max_magnitude();
        REQUIRE(largest > 0.0);
        // the kernel's domain: pixel centres where it is evaluated
        const double lo = needs_full_mask(border) ? mc.size / 2 : 0.0;
        const double x_hi = w - 1 - lo;
        const double y_hi = h - 1 - lo;
        const auto nearest = [&](double x, double y) {
          return raw.at(std::clamp(x, lo, x_hi), std::clamp(y, lo, y_hi));
        };
        struct Stroke {
          double x, y, dx, dy;
          bool fixed_exit;  // leaves through a point (perpendicular or corner): R is constant outside
        };
        std::vector<Stroke> strokes;
        const double inset = mc.size + 2.0 * default_fade_px;  // start inside every band
        for (int k = 1; k <= 5; ++k) {
          const double fx = k / 6.0;
          strokes.push_back({w - 1 - inset, fx * h, 1, 0, true});  // out through the right edge
          strokes.push_back({inset, fx * h, -1, 0, true});         // left
          strokes.push_back({fx * w, h - 1 - inset, 0, 1, true});  // bottom
          strokes.push_back({fx * w, inset, 0, -1, true});         // top
        }
        for (const double sx : {-1.0, 1.0})
          for (const double sy : {-1.0, 1.0}) {
            const double cx = sx > 0 ? x_hi : lo;  // the domain's corner
            const double cy = sy > 0 ? y_hi : lo;
            const double d = 2.0 * inset;
            strokes.push_back({cx - sx * d, cy - sy * d, sx * std::sqrt(0.5), sy * std::sqrt(0.5), true});
            // oblique: 30 degrees to the edge, through the side near the corner
            strokes.push_back({cx - sx * 3 * d, cy - sy * d, sx * std::cos(0.5236), sy * std::sin(0.5236), false});
          }
        double worst_fixed = 0.0;
        double worst_excess = 0.0;
        for (const Stroke& st : strokes) {
          glm::dvec2 f0 = image.at(st.x, st.y);
          glm::dvec2 r0 = nearest(st.x, st.y);
          bool was_outside = false;
          for (int i = 1; i < 4 * static_cast<int>(inset + default_fade_px) + 400; ++i) {
            const double x = st.x + step_px * i * st.dx;
            const double y = st.y + step_px * i * st.dy;
            const glm::dvec2 f1 = image.at(x, y);
            const glm::dvec2 r1 = nearest(x, y);
            const double step = glm::length(f1 - f0) / largest;
            const bool outside = x < lo || x > x_hi || y < lo || y > y_hi;
            // both samples outside: only the fade acts (the crossing step is bounded below)
            if (st.fixed_exit && outside && was_outside) worst_fixed = std::max(worst_fixed, step);
            was_outside = outside;
            worst_excess = std::max(worst_excess, step - glm::length(r1 - r0) / largest);
            f0 = f1;
            r0 = r1;
          }
          REQUIRE(f0 == glm::dvec2{0.0});  // every stroke ends beyond the band
        }
        CHECK(worst_fixed <= jnd);
        CHECK(worst_excess <= jnd);
      }
    }
  }
}

TEST_CASE("mirror symmetry: flipping the picture flips fx and keeps fy") {
  const GrayImage gray = test_picture(81, 61, 17);
  GrayImage mirrored(81, 61);
  for (int y = 0; y < 61; ++y)
    for (int x = 0; x < 81; ++x)
      mirrored.at(80 - x, y) = gray.at(x, y);
  for (const MaskCase& mc : all_masks) {
    if (mc.kind == MaskKind::roberts) continue;  // even size: its anchor is not symmetric
    CAPTURE(to_string(mc.kind), mc.size);
    TangibleConfig o{mc.kind, mc.size, 2.0, Border::reflect, 8.0, KernelChoice::automatic};
    const TangibleImage a(gray, o);
    const TangibleImage b(mirrored, o);
    for (double x = 0.0; x <= 80.0; x += 3.7) {
      const glm::dvec2 fa = a.at(x, 30.3);
      const glm::dvec2 fb = b.at(80.0 - x, 30.3);
      REQUIRE(fb.x == Approx(-fa.x).margin(1e-12));
      REQUIRE(fb.y == Approx(fa.y).margin(1e-12));
    }
  }
}

TEST_CASE("the O(1) Prewitt map equals the per-pixel kernel map") {
  const GrayImage gray = test_picture(150, 110, 23);
  for (int size : {3, 17, 65}) {
    for (Border border : {Border::suspend, Border::clamp, Border::reflect, Border::fade}) {
      CAPTURE(size, to_string(border));
      TangibleConfig o;
      o.size = size;
      o.border = border;
      o.kernel = KernelChoice::direct;
      const ForceMap reference = force_map(TangibleImage(gray, o));
      const ForceMap fast = prewitt_force_map(gray, size, border);
      REQUIRE(fast.width == reference.width);
      REQUIRE(fast.height == reference.height);
      for (std::size_t i = 0; i < fast.fx.size(); ++i) {
        REQUIRE(fast.fx[i] == Approx(reference.fx[i]).margin(1e-6));
        REQUIRE(fast.fy[i] == Approx(reference.fy[i]).margin(1e-6));
      }
    }
  }
}

TEST_CASE("the integer Prewitt map is exact on 8-bit and colour pictures, and falls back to double") {
  // 8-bit gray and the paper's colour weights take the exact 32-bit route
  // (see force_map.hpp); the floats then differ from the direct kernel's
  // double result by the float rounding alone.
  cv::theRNG().state = 5;
  cv::Mat colour(120, 160, CV_8UC3);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(256));
  cv::GaussianBlur(colour, colour, cv::Size(0, 0), 1.5);
  cv::Mat eight;
  cv::cvtColor(colour, eight, cv::COLOR_BGR2GRAY);
  GrayImage spoilt = to_gray(colour, GrayWeights::paper);
  spoilt.at(80, 70) += 0.3;  // one level the sampled rows do not see: not an integer in any fixed point
  REQUIRE(detail::guess_fixed_point_scale(spoilt) == 100.0);
  const std::vector<GrayImage> pictures = {to_gray(eight), to_gray(colour, GrayWeights::paper), spoilt};
  for (std::size_t p = 0; p < pictures.size(); ++p) {
    for (int size : {3, 17, 65, 129}) {
      if (size > pictures[p].height()) continue;
      for (Border border : {Border::suspend, Border::clamp, Border::reflect, Border::fade}) {
        CAPTURE(p, size, to_string(border));
        TangibleConfig o;
        o.size = size;
        o.border = border;
        o.kernel = KernelChoice::direct;
        const ForceMap reference = force_map(TangibleImage(pictures[p], o));
        const ForceMap fast = prewitt_force_map(pictures[p], size, border);
        double worst = 0.0;
        for (std::size_t i = 0; i < fast.fx.size(); ++i) {
          const double tol_x = 1.2e-7 * std::abs(reference.fx[i]);  // float rounding (twice in suspend's margin)
          const double tol_y = 1.2e-7 * std::abs(reference.fy[i]);
          worst = std::max(
              {worst, std::abs(fast.fx[i] - reference.fx[i]) - tol_x, std::abs(fast.fy[i] - reference.fy[i]) - tol_y});
        }
        if (p < 2)
          CHECK(worst <= 1e-12);  // exact up to float rounding
        else
          CHECK(worst <= 1e-6);  // the double route, as for any picture
      }
    }
  }
}

TEST_CASE("the AVX2 and baseline builds of a map band give the same planes") {
  if (!detail::has_avx2()) {
    WARN("this CPU has no AVX2: only the baseline band runs");
    return;
  }
  const GrayImage gray = test_picture(200, 90, 3);
  GrayImage levels = gray;
  for (int y = 0; y < levels.height(); ++y)
    for (int x = 0; x < levels.width(); ++x)
      levels.at(x, y) = std::round(gray.at(x, y));
  for (const GrayImage* g : {&gray, static_cast<const GrayImage*>(&levels)}) {
    for (double d : {0.0, 1.0}) {
      if (d > 0.0 && g == &gray) continue;  // the integer route needs integer levels
      ForceMap a{g->width(), g->height(), std::vector<float>(g->pixels().size()),
                 std::vector<float>(g->pixels().size())};
      ForceMap b = a;
      const detail::PrewittBand band{
          g, 8, Border::reflect, 10.0, 1e-3, d, 0, g->width() - 1, g->height() - 1, 0, g->height() - 1, &a};
      REQUIRE(detail::prewitt_band_baseline(band));
      detail::PrewittBand other = band;
      other.map = &b;
      REQUIRE(detail::prewitt_band_avx2(other));
      double worst = 0.0;
      for (std::size_t i = 0; i < a.fx.size(); ++i)
        worst = std::max({worst, std::abs(double(a.fx[i]) - b.fx[i]), std::abs(double(a.fy[i]) - b.fy[i])});
      CAPTURE(d);
      CHECK(worst <= (d > 0.0 ? 0.0 : 1e-6));  // integers: identical; double: FMA contraction may differ
    }
  }
}

TEST_CASE("every instruction-set route of the Prewitt map gives OpenCV's sepFilter2D planes, to the bit alike") {
  // Oracle: sepFilter2D in double on the inverted picture (box across the
  // derivative, ramp along it), normalised by the step response. Widths
  // that are no multiple of 8 or 16 exercise the vector loops' tails.
  std::vector<detail::MapSimd> routes{detail::MapSimd::baseline};
  if (detail::has_avx2()) routes.push_back(detail::MapSimd::avx2);
  if (detail::has_avx512()) routes.push_back(detail::MapSimd::avx512);
  cv::theRNG().state = 9;
  cv::Mat colour(67, 203, CV_8UC3);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(256));
  cv::GaussianBlur(colour, colour, cv::Size(0, 0), 1.2);
  cv::Mat eight;
  cv::cvtColor(colour, eight, cv::COLOR_BGR2GRAY);
  GrayImage rounded = test_picture(37, 41, 12);
  for (double& v : const_cast<std::vector<double>&>(rounded.pixels()))
    v = std::round(v);
  const std::vector<GrayImage> pictures = {to_gray(eight), to_gray(colour, GrayWeights::paper), rounded,
                                           test_picture(90, 45, 13)};
  for (std::size_t p = 0; p < pictures.size(); ++p) {
    const GrayImage& gray = pictures[p];
    cv::Mat inverted;
    cv::subtract(cv::Scalar::all(gray_full_scale), to_mat(gray), inverted);
    for (int size : {3, 5, 17, 33}) {
      if (size > std::min(gray.width(), gray.height())) continue;
      const int h = size / 2;
      cv::Mat ramp(1, size, CV_64F);
      const cv::Mat ones(1, size, CV_64F, cv::Scalar(1.0));
      for (int c = 0; c < size; ++c)
        ramp.at<double>(c) = c - h;
      const double step = gray_full_scale * size * h * (h + 1) / 2.0;
      for (Border border : border_kinds) {
        CAPTURE(p, size, to_string(border));
        const int cv_b = needs_full_mask(border) ? cv::BORDER_REPLICATE : cv_border(border);
        cv::Mat fx;
        cv::Mat fy;
        cv::sepFilter2D(inverted, fx, CV_64F, ramp, ones, cv::Point(-1, -1), 0.0, cv_b);
        cv::sepFilter2D(inverted, fy, CV_64F, ones, ramp, cv::Point(-1, -1), 0.0, cv_b);
        ForceMap first;
        for (const detail::MapSimd simd : routes) {
          CAPTURE(static_cast<int>(simd));
          ForceMap map;
          detail::prewitt_force_map_on(simd, gray, size, border, map, default_fade_px, 1);
          if (simd == routes.front()) first = map;
          REQUIRE(map.fx == first.fx);  // the same planes, bit for bit
          REQUIRE(map.fy == first.fy);
          double worst = 0.0;
          for (int y = 0; y < gray.height(); ++y)
            for (int x = 0; x < gray.width(); ++x) {
              // suspend and fade: only where the mask lies inside and no fade applies
              const int inside = std::min({x - h, gray.width() - 1 - h - x, y - h, gray.height() - 1 - h - y});
              if (needs_full_mask(border) && inside < (border == Border::fade ? default_fade_px : 0.0)) continue;
              worst = std::max({worst, std::abs(map.fx[map.index(x, y)] - fx.at<double>(y, x) / step),
                                std::abs(map.fy[map.index(x, y)] - fy.at<double>(y, x) / step)});
            }
          CHECK(worst <= 1e-6);
        }
      }
    }
  }
}

TEST_CASE("a map whose planes are aligned differently gets the same values on every route") {
  // The vector routes write 32- or 64-byte blocks with non-temporal stores
  // when fx and fy share their alignment, ordinary stores otherwise: find
  // an fy allocation whose 64-byte phase differs from fx's.
  GrayImage gray = test_picture(301, 40, 17);
  for (double& v : const_cast<std::vector<double>&>(gray.pixels()))
    v = std::round(v);
  const std::size_t n = gray.pixels().size();
  ForceMap reference{gray.width(), gray.height(), std::vector<float>(n), std::vector<float>(n)};
  const detail::PrewittBand base{
      &gray,     5, Border::reflect, 10.0, 1e-3, 1.0, 0, gray.width() - 1, gray.height() - 1, 0, gray.height() - 1,
      &reference};
  REQUIRE(detail::prewitt_band(base, detail::MapSimd::baseline));
  for (const detail::MapSimd simd : {detail::MapSimd::avx2, detail::MapSimd::avx512}) {
    ForceMap map{gray.width(), gray.height(), std::vector<float>(n), {}};
    std::vector<std::vector<float>> spacers;
    for (int attempt = 0; attempt < 64; ++attempt) {
      map.fy = std::vector<float>(n);
      if (((reinterpret_cast<std::uintptr_t>(map.fx.data()) ^ reinterpret_cast<std::uintptr_t>(map.fy.data())) & 63u) !=
          0)
        break;
      spacers.emplace_back(static_cast<std::size_t>(attempt % 7 + 1) * 4);
    }
    if (((reinterpret_cast<std::uintptr_t>(map.fx.data()) ^ reinterpret_cast<std::uintptr_t>(map.fy.data())) & 63u) ==
        0)
      WARN("the allocator gave fx and fy the same 64-byte phase every time");
    CAPTURE(static_cast<int>(simd));
    detail::PrewittBand band = base;
    band.map = &map;
    REQUIRE(detail::prewitt_band(band, simd));  // the widest route the CPU runs, at most simd
    CHECK(map.fx == reference.fx);
    CHECK(map.fy == reference.fy);
  }
}

TEST_CASE("each route's level check catches a level that is not an integer or leaves [0, 255]") {
  // One bad level among exact integers, placed inside a vector block and in
  // the scalar tail: the integer band must report it (the map then takes the
  // double route), whatever the instruction set.
  std::vector<detail::MapSimd> routes{detail::MapSimd::baseline};
  if (detail::has_avx2()) routes.push_back(detail::MapSimd::avx2);
  if (detail::has_avx512()) routes.push_back(detail::MapSimd::avx512);
  GrayImage levels = test_picture(75, 40, 21);
  for (double& v : const_cast<std::vector<double>&>(levels.pixels()))
    v = std::round(v);
  for (const double bad : {100.3, 256.0, -1.0, 255.001, std::numeric_limits<double>::quiet_NaN()}) {
    for (const int column : {20, 73}) {
      GrayImage g = levels;
      g.at(column, 19) = bad;
      for (const detail::MapSimd simd : routes) {
        CAPTURE(bad, column, static_cast<int>(simd));
        ForceMap map{g.width(), g.height(), std::vector<float>(g.pixels().size()),
                     std::vector<float>(g.pixels().size())};
        const detail::PrewittBand band{
            &g, 4, Border::clamp, 10.0, 1e-3, 1.0, 0, g.width() - 1, g.height() - 1, 0, g.height() - 1, &map};
        CHECK_FALSE(detail::prewitt_band(band, simd));
      }
    }
  }
  for (const detail::MapSimd simd : routes) {  // and the clean picture passes
    ForceMap map{levels.width(), levels.height(), std::vector<float>(levels.pixels().size()),
                 std::vector<float>(levels.pixels().size())};
    const detail::PrewittBand band{
        &levels, 4, Border::clamp, 10.0, 1e-3, 1.0, 0, levels.width() - 1, levels.height() - 1, 0, levels.height() - 1,
        &map};
    CHECK(detail::prewitt_band(band, simd));
  }
}

TEST_CASE("the Prewitt map computed in bands on several threads equals one thread's") {
  const GrayImage gray = test_picture(257, 301, 33);
  for (Border border : {Border::suspend, Border::reflect, Border::fade}) {
    const ForceMap one = prewitt_force_map(gray, 17, border);
    for (int threads : {2, 3, 8}) {
      const ForceMap many = prewitt_force_map(gray, 17, border, default_fade_px, threads);
      REQUIRE(many.fx.size() == one.fx.size());
      // each band restarts its running sums, so only rounding may differ
      for (std::size_t i = 0; i < one.fx.size(); ++i) {
        REQUIRE(many.fx[i] == Approx(one.fx[i]).margin(1e-6));
        REQUIRE(many.fy[i] == Approx(one.fy[i]).margin(1e-6));
      }
    }
  }
  CHECK_THROWS_AS(prewitt_force_map(gray, 17, Border::clamp, default_fade_px, 0), std::invalid_argument);
}

TEST_CASE("a reused force map holds no stale values") {
  const GrayImage gray = test_picture(90, 70, 31);
  ForceMap reused;
  prewitt_force_map(test_picture(120, 100, 32), 5, Border::clamp, reused);  // larger, no zero border
  for (Border border : {Border::suspend, Border::fade, Border::reflect}) {
    prewitt_force_map(gray, 9, border, reused);
    const ForceMap fresh = prewitt_force_map(gray, 9, border);
    REQUIRE(reused.width == 90);
    REQUIRE(reused.height == 70);
    REQUIRE(reused.fx == fresh.fx);
    REQUIRE(reused.fy == fresh.fy);
  }
}

TEST_CASE("degenerate masks are refused at construction, every factory is normalisable") {
  // sigma <= 0.026 px: every off-centre weight underflows to 0, the step
  // response is 0 and forces would be 0 / 0 = NaN.
  for (double sigma : {0.01, 0.025, 0.049, 1e-300}) {
    CAPTURE(sigma);
    CHECK_THROWS_WITH(Mask<>::gaussian(sigma, 5), Catch::Contains("at least 0.05") && Catch::Contains("sigma"));
    CHECK_THROWS_AS(Mask<5>::gaussian(sigma), std::invalid_argument);
    CHECK_THROWS_AS(TangibleImage(test_picture(40, 30, 1), {MaskKind::gaussian, 5, sigma}), std::invalid_argument);
  }
  CHECK_THROWS_AS(Mask<>::gaussian(infinity, 5), std::invalid_argument);
  // At the smallest allowed sigma the mask is a central difference, finite
  // and normalised: a black/white step still gives magnitude 1.
  const Mask<> thin = Mask<>::gaussian(min_gaussian_sigma, 5);
  CHECK(std::isnormal(thin.step_response()));
  const TangibleImage image(step_picture(40, 30, 20), {MaskKind::gaussian, 5, min_gaussian_sigma, Border::clamp,
                                                       default_fade_px, KernelChoice::direct});
  CHECK(image.at_pixel(20, 15).x == Approx(1.0).epsilon(1e-12));
  // Huge sigmas are flat Gaussians (Prewitt-like), never degenerate.
  CHECK(std::isnormal(Mask<>::gaussian(1e200, 129).step_response()));
  // Every factory at every allowed size: finite weights, a positive normal step response.
  for (MaskKind kind : {MaskKind::prewitt, MaskKind::sobel, MaskKind::scharr, MaskKind::roberts, MaskKind::gaussian,
                        MaskKind::emboss}) {
    for (int size = 2; size <= max_mask_size; ++size) {
      bool allowed = true;
      try {
        validate_mask_size(kind, size);
      } catch (const std::invalid_argument&) {
        allowed = false;
      }
      if (!allowed) continue;
      CAPTURE(to_string(kind), size);
      const Mask<> mask = Mask<>::make(kind, size);
      CHECK(std::isnormal(mask.step_response()));
      CHECK(mask.step_response() > 0.0);
      bool finite = true;
      for (double w : mask.x_weights())
        finite = finite && std::isfinite(w);
      CHECK(finite);
    }
  }
}

TEST_CASE("bad input: a clear error at setup, zero force at run time") {
  const GrayImage gray = test_picture(40, 30, 1);
  SECTION("mask size even or out of range") {
    CHECK_THROWS_WITH(Mask<>::prewitt(4), Catch::Contains("size 4 px is not allowed"));
    CHECK_THROWS_AS(Mask<>::prewitt(1), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::prewitt(131), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::prewitt(-3), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::sobel(33), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::scharr(5), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::roberts(3), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::gaussian(0.0, 5), std::invalid_argument);
    CHECK_THROWS_AS(Mask<>::gaussian(not_a_number, 5), std::invalid_argument);
    CHECK_THROWS_AS(Mask<5>::prewitt(7), std::invalid_argument);
    CHECK_THROWS_AS(TangibleImage(gray, {MaskKind::prewitt, 8}), std::invalid_argument);
    CHECK_THROWS_AS(IntegralKernel(inverted(gray), MaskKind::sobel, 3, Border::clamp), std::invalid_argument);
    CHECK_THROWS_AS(prewitt_force_map(gray, 6, Border::clamp), std::invalid_argument);
  }
  SECTION("empty, 1x1 and smaller-than-mask images") {
    CHECK_THROWS_WITH(TangibleImage(GrayImage{}, {}), Catch::Contains("empty"));
    CHECK_THROWS_WITH(TangibleImage(GrayImage(1, 1, 0.0), {MaskKind::prewitt, 3}),
                      Catch::Contains("smaller than the 3 x 3 mask"));
    CHECK_THROWS_WITH(TangibleImage(gray, {MaskKind::prewitt, 33}), Catch::Contains("smaller than the 33 x 33"));
    CHECK_THROWS_AS(prewitt_force_map(GrayImage(2, 2), 3, Border::clamp), std::invalid_argument);
    CHECK_THROWS_AS(GrayImage(0, 5), std::invalid_argument);
  }
  SECTION("bad fade width") {
    TangibleConfig o;
    o.size = 3;
    o.fade_px = 0.0;
    CHECK_THROWS_AS(TangibleImage(gray, o), std::invalid_argument);
  }
  SECTION("NaN / Inf probes and probes outside the picture give zero force") {
    const TangibleImage image(gray, {MaskKind::prewitt, 3, 0.0, Border::clamp});
    for (double bad : {not_a_number, infinity, -infinity}) {
      CHECK(image.at(bad, 10.0) == glm::dvec2{0.0});
      CHECK(image.at(10.0, bad) == glm::dvec2{0.0});
    }
    CHECK(image.at(-1.0 - default_fade_px, 10.0) == glm::dvec2{0.0});  // beyond the fade band
    CHECK(image.at(39.0 + default_fade_px, 10.0) == glm::dvec2{0.0});
    CHECK(image.at(10.0, 1e300) == glm::dvec2{0.0});
    CHECK(image.at(-1e300, -1e300) == glm::dvec2{0.0});
    TangibleImageField<> field(image, PlaneMapping(1.0, {20.0, 15.0}), 2.0);
    Probe probe;
    probe.position = {not_a_number, 0.0, 0.0};
    CHECK(field.force(probe) == glm::dvec3{0.0});
    probe.position = {1.0, 1.0, 0.0};  // 1 m away: far outside the picture
    CHECK(field.force(probe) == glm::dvec3{0.0});
    CHECK_THROWS_AS(TangibleImageField<>(image, PlaneMapping(1.0), -1.0), std::invalid_argument);
    CHECK_THROWS_AS(TangibleImageField<>(image, PlaneMapping(1.0), not_a_number), std::invalid_argument);
  }
}

TEST_CASE("TangibleImageField maps the picture into the device frame") {
  const GrayImage step = step_picture(64, 48, 32);  // black right of column 32
  // 1 px/mm, pixel (32, 24) at the device origin
  TangibleImageField<> field(TangibleImage(step, {MaskKind::prewitt, 5}), PlaneMapping(1.0, {32.0, 24.0}), 1.5);
  Probe probe;  // at the origin: on the edge
  const glm::dvec3 f = field.force(probe);
  CHECK(f.x == Approx(1.5));  // 1.5 N toward black (device +x)
  CHECK(f.y == Approx(0.0).margin(1e-12));
  CHECK(f.z == 0.0);
  probe.position = {-0.020, 0.0, 0.0};  // 20 mm left: flat white
  CHECK(field.force(probe) == glm::dvec3{0.0});

  // image +y (down) is device -y
  GrayImage turned(48, 64, 255.0);
  for (int y = 32; y < 64; ++y)
    for (int x = 0; x < 48; ++x)
      turned.at(x, y) = 0.0;
  AnyField any =
      TangibleImageField<>(TangibleImage(turned, {MaskKind::sobel, 3}), PlaneMapping(1.0, {24.0, 32.0}), 1.0);
  CHECK(any.force(Probe{}).y == Approx(-1.0));
  // composition: clamp to 0.4 N keeps the direction
  auto clamped = clamp(std::move(any), 0.4);
  CHECK(clamped.force(Probe{}).y == Approx(-0.4));
}

TEST_CASE("force queries never allocate") {
  const GrayImage gray = test_picture(200, 200, 4);
  TangibleImageField<> integral(TangibleImage(gray, {MaskKind::prewitt, 33}), PlaneMapping(2.0, {100.0, 100.0}), 1.0);
  AnyField direct = TangibleImageField<>(TangibleImage(gray, {MaskKind::gaussian, 9, 2.0, Border::fade}),
                                         PlaneMapping(2.0, {100.0, 100.0}), 1.0);
  Probe probe;
  glm::dvec3 total{0.0};
  const long allocations = test::count_allocations([&] {
    for (int i = 0; i < 10000; ++i) {
      probe.position = {0.05 * std::sin(i * 0.01), 0.05 * std::cos(i * 0.013), 0.0};
      total += integral.force(probe) + direct.force(probe);
    }
  });
  CHECK(allocations == 0);
  CHECK(is_finite(total));
}
