// shape_check SHOT.png R_MM D_MM
// Checks a picture of the 3D view of a sphere (hapticfield_view --shape,
// its --screenshot or a grab of the X screen; servo_demo --snapshot): the
// largest connected region of surface-coloured pixels (blue over red by
// 12 levels or more: the shaded surface, not the background, the panel or
// the markers) is a disc of the radius the pinhole projection gives,
// rho = f R / sqrt(D^2 - R^2) with f = 300 px / tan(20 deg) (the view's
// documented camera: 40 degree vertical field of view over 600 px), R the
// sphere's radius and D the camera's distance from its centre, within 2 px;
// it fills the disc (95 %, the markers and the arrow cover the rest); and
// the proxy (pure magenta) and HIP (pure green) markers are drawn inside
// it. Exit 0 when all hold, 1 otherwise, with one line saying what was
// found. Independent of where the view is in the picture.
//
// shape_check --ball SHOT.png R_MM D_MM
// Checks the tool's ball (hapticfield_view --radius R_MM) seen on the
// optical axis at depth D_MM: the pixels of its colour (magenta shaded:
// blue = red > 0, green 0; nothing else in the view has it) span a disc of
// the radius the pinhole projection gives, within 2 px, and cover 90 % to
// 102 % of its area (the HIP's ring, over the ball, takes up to 5 %).
//
// shape_check --make-sphere OUT.obj
// Writes a UV sphere of radius 1 (128 x 64, 16 128 triangles) as OBJ.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "uv_sphere.hpp"

namespace {

double focal_px() {
  return 300.0 / std::tan(20.0 * std::numbers::pi / 180.0);
}

int check_ball(const char* path, const char* r_mm, const char* d_mm) {
  const cv::Mat shot = cv::imread(path, cv::IMREAD_COLOR);
  const double radius = std::atof(r_mm), distance = std::atof(d_mm);
  if (shot.empty() || !(radius > 0.0) || !(distance > radius)) {
    std::fprintf(stderr, "shape_check: cannot read %s, or bad R '%s' or D '%s'\n", path, r_mm, d_mm);
    return 1;
  }
  const double rho = focal_px() * radius / std::sqrt(distance * distance - radius * radius);
  int count = 0, left = shot.cols, right = -1, top = shot.rows, bottom = -1;
  for (int y = 0; y < shot.rows; ++y)
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
      if (c[1] != 0 || c[0] != c[2] || c[0] == 0) continue;
      ++count;
      left = std::min(left, x), right = std::max(right, x), top = std::min(top, y), bottom = std::max(bottom, y);
    }
  const double fill = count / (std::numbers::pi * rho * rho);
  const double width = right - left + 1, height = bottom - top + 1;
  const bool ok = count > 0 && std::abs(width / 2.0 - rho) <= 2.0 && std::abs(height / 2.0 - rho) <= 2.0 &&
                  fill >= 0.90 && fill <= 1.02;
  std::printf(
      "shape_check: %s: the tool's ball %gx%g px at %d,%d (expected diameter %.1f px), %d px: %.3f of pi rho^2\n",
      ok ? "ok" : "FAIL", width, height, left, top, 2.0 * rho, count, fill);
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--make-sphere") {
    std::ofstream out(argv[2]);
    out << hapticfield::test::to_obj(hapticfield::test::uv_sphere(1.0, 128, 64));
    return out ? 0 : 1;
  }
  if (argc == 5 && std::string(argv[1]) == "--ball") return check_ball(argv[2], argv[3], argv[4]);
  if (argc != 4) {
    std::fprintf(stderr, "usage: shape_check SHOT.png R_MM D_MM | --ball SHOT.png R_MM D_MM | --make-sphere OUT.obj\n");
    return 2;
  }
  const cv::Mat shot = cv::imread(argv[1], cv::IMREAD_COLOR);
  const double radius = std::atof(argv[2]), distance = std::atof(argv[3]);
  if (shot.empty() || !(radius > 0.0) || !(distance > radius)) {
    std::fprintf(stderr, "shape_check: cannot read %s, or bad R '%s' or D '%s'\n", argv[1], argv[2], argv[3]);
    return 1;
  }
  const double focal = focal_px();
  const double rho = focal * radius / std::sqrt(distance * distance - radius * radius);
  cv::Mat surface(shot.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < shot.rows; ++y)
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
      surface.at<std::uint8_t>(y, x) = (c[0] >= 40 && c[0] - c[2] >= 12) ? 255 : 0;
    }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(surface, labels, stats, centroids, 8);
  int best = 0;
  for (int k = 1; k < n; ++k)
    if (best == 0 || stats.at<int>(k, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = k;
  if (best == 0) {
    std::printf("shape_check: FAIL: no surface pixels in %s\n", argv[1]);
    return 1;
  }
  const cv::Rect box(stats.at<int>(best, cv::CC_STAT_LEFT), stats.at<int>(best, cv::CC_STAT_TOP),
                     stats.at<int>(best, cv::CC_STAT_WIDTH), stats.at<int>(best, cv::CC_STAT_HEIGHT));
  const double area = stats.at<int>(best, cv::CC_STAT_AREA);
  const double fill = area / (std::numbers::pi * rho * rho);
  // the markers: exact colours inside the disc's box
  int magenta = 0, green = 0;
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x) {
      const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
      magenta += c == cv::Vec3b(255, 0, 255);
      green += c == cv::Vec3b(0, 255, 0);
    }
  const bool size_ok = std::abs(box.width / 2.0 - rho) <= 2.0 && std::abs(box.height / 2.0 - rho) <= 2.0;
  const bool fill_ok = fill >= 0.95 && fill <= 1.02;
  const bool marks_ok = magenta >= 20 && green >= 20;
  const bool ok = size_ok && fill_ok && marks_ok;
  std::printf(
      "shape_check: %s: surface disc %dx%d px at %d,%d (expected diameter %.1f px), fills %.3f of pi rho^2; "
      "%d proxy (magenta) and %d HIP (green) pixels on it\n",
      ok ? "ok" : "FAIL", box.width, box.height, box.x, box.y, 2.0 * rho, fill, magenta, green);
  return ok ? 0 : 1;
}
