// The tangible-images paper's section 5, reproduced: force noise against
// mask size on a noise picture, the effect of resolution on the smallest
// feature felt, and linearity in contrast. Measurements on synthetic
// pictures are compared with the closed-form laws of mask_choice.hpp.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "hapticfield/kernels.hpp"

using namespace hapticfield;

namespace {

/// Number of points along row y where the force attracts the HIP (fx turns
/// from pointing right to pointing left), between columns x0 and x1.
int attractors(const TangibleImage& image, int x0, int x1, int y) {
  int count = 0;
  double previous = image.at_pixel(x0, y).x;
  for (int x = x0 + 1; x <= x1; ++x) {
    const double f = image.at_pixel(x, y).x;
    if (f < -1e-12 && previous > 1e-12) ++count;                     // + then -
    if (f < -1e-12 && std::abs(previous) <= 1e-12 && x - 2 >= x0 &&  // + then 0 then -
        image.at_pixel(x - 2, y).x > 1e-12)
      ++count;
    previous = f;
  }
  return count;
}

/// White picture with two 1 px dark lines, columns a and a + separation.
GrayImage two_lines(int width, int height, int a, int separation) {
  GrayImage g(width, height, 255.0);
  for (int y = 0; y < height; ++y) {
    g.at(a, y) = 0.0;
    g.at(a + separation, y) = 0.0;
  }
  return g;
}

}  // namespace

TEST_CASE("section 5: force noise falls as 1 / sqrt(3 h (h + 1)) with mask size") {
  // uniform noise over [0, 255]: sigma = 255 / sqrt(12) gray levels
  std::mt19937 rng(2008);
  std::uniform_real_distribution<double> level(0.0, 255.0);
  GrayImage noise(2048, 2048);
  for (int y = 0; y < noise.height(); ++y)
    for (int x = 0; x < noise.width(); ++x)
      noise.at(x, y) = level(rng);
  const double sigma = 255.0 / std::sqrt(12.0);
  for (int m : {5, 9, 17, 33, 65}) {
    CAPTURE(m);
    const double predicted = prewitt_noise_std(m, sigma);
    const glm::dvec2 measured = prewitt_force_noise(noise, m);
    CHECK(measured.x == Approx(predicted).epsilon(0.10));
    CHECK(measured.y == Approx(predicted).epsilon(0.10));
  }
  // m = 5: 1 / (3 sqrt 6) = 0.136; m = 65: 1 / (3 sqrt 1056) = 0.0103
  CHECK(prewitt_noise_std(5, sigma) == Approx(1.0 / (3.0 * std::sqrt(6.0))));
  CHECK(prewitt_noise_std(65, sigma) == Approx(1.0 / (3.0 * std::sqrt(1056.0))));
}

TEST_CASE("section 5: the smallest separation felt grows with the mask, shrinks with resolution") {
  for (int m = 5; m <= 65; m += 4) {
    CAPTURE(m);
    const int h = m / 2;
    for (int d = 1; d <= 2 * h + 4; ++d) {
      CAPTURE(d);
      const GrayImage picture = two_lines(4 * h + d + 20, m + 2, 2 * h + 10, d);
      TangibleConfig o;
      o.size = m;
      o.border = Border::clamp;
      const TangibleImage image(picture, o);
      const int n = attractors(image, h, picture.width() - 1 - h, picture.height() / 2);
      if (d <= h + 1)
        REQUIRE(n == 1);  // one line, at the midpoint
      else if (d < m - 1)
        REQUIRE(n == 3);  // both lines and a phantom between
      else
        REQUIRE(n == 2);  // two lines, cleanly
    }
    CHECK(prewitt_min_separation_px(m) == m - 1);
  }
  // two lines 2 mm apart: the largest mask that separates them doubles with
  // each doubling of resolution
  CHECK(largest_separating_prewitt(2.0, 2.0) == 5);
  CHECK(largest_separating_prewitt(2.0, 4.0) == 9);
  CHECK(largest_separating_prewitt(2.0, 8.0) == 17);
  CHECK(largest_separating_prewitt(2.0, 16.0) == 33);
  CHECK(largest_separating_prewitt(2.0, 6.4) == 13);
  CHECK(largest_separating_prewitt(0.25, 4.0) == 0);
  CHECK_THROWS_AS(largest_separating_prewitt(-1.0, 4.0), std::invalid_argument);
  CHECK_THROWS_AS(prewitt_noise_std(4, 1.0), std::invalid_argument);
}

TEST_CASE("section 5: the force is linear in contrast") {
  // a gray step of contrast c (gray levels 128 +- 127.5 c) at every mask
  for (int m : {3, 17, 65}) {
    double sum_c = 0.0, sum_f = 0.0, sum_cc = 0.0, sum_cf = 0.0, sum_ff = 0.0;
    int n = 0;
    for (double c = 0.1; c <= 1.0001; c += 0.1) {
      GrayImage g(200, 100, 127.5 + 127.5 * c);
      for (int y = 0; y < 100; ++y)
        for (int x = 100; x < 200; ++x)
          g.at(x, y) = 127.5 - 127.5 * c;
      const TangibleImage image(g, {MaskKind::prewitt, m});
      const double f = image.at(100.0, 50.0).x;
      sum_c += c, sum_f += f, sum_cc += c * c, sum_cf += c * f, sum_ff += f * f;
      ++n;
    }
    const double slope = (n * sum_cf - sum_c * sum_f) / (n * sum_cc - sum_c * sum_c);
    const double intercept = (sum_f - slope * sum_c) / n;
    const double r =
        (n * sum_cf - sum_c * sum_f) / std::sqrt((n * sum_cc - sum_c * sum_c) * (n * sum_ff - sum_f * sum_f));
    CAPTURE(m);
    CHECK(slope == Approx(1.0).epsilon(1e-12));  // full contrast = a black/white edge = 1
    CHECK(intercept == Approx(0.0).margin(1e-12));
    CHECK(r == Approx(1.0).epsilon(1e-12));
  }
}
