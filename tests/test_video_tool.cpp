// tangible_video --probes run as a user runs it, on opencv-doc's vtest.avi:
// the temporal denoiser's flicker cut at static edges and its response at
// moving edges, measured through the tool's own output at frame mid-times
// over the whole clip. The points are chosen with OpenCV alone (the clip's
// per-pixel temporal spread and the mean frame's gradient), not with the
// library. Skips with a warning when opencv-doc is absent.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "child_process.hpp"

namespace {

namespace fs = std::filesystem;
using hapticfield::testing::Child;

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "video_tool";

std::string vtest_clip() {
  for (const char* d : {"/usr/share/doc/opencv-doc/examples/data", "/usr/share/opencv4/samples/data"})
    if (fs::exists(fs::path(d) / "vtest.avi")) return (fs::path(d) / "vtest.avi").string();
  return {};
}

/// What OpenCV alone says about a clip: its frame count and rate, the
/// gradient of its mean gray frame [levels/px], the per-pixel temporal
/// standard deviation of the gray level, and the largest departure of each
/// frame, blurred over 9 x 9 px, from the mean frame blurred the same way
/// [levels] (a passer-by shows there even when brief).
struct ClipStatistics {
  int frames = 0;
  double fps = 0;
  cv::Mat gradient;   ///< |grad| of the mean frame smoothed with sigma 2 px [levels/px], CV_64F
  cv::Mat spread;     ///< temporal standard deviation [gray levels], CV_64F
  cv::Mat departure;  ///< max over frames of |blurred frame - blurred mean| [gray levels], CV_32F
};

ClipStatistics clip_statistics(const std::string& clip) {
  ClipStatistics s;
  cv::Mat frame, gray, sum, squares;
  const auto each_frame = [&](const auto& use) {
    cv::VideoCapture capture(clip, cv::CAP_FFMPEG);
    REQUIRE(capture.isOpened());
    s.fps = capture.get(cv::CAP_PROP_FPS);
    while (capture.read(frame)) {
      cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
      gray.convertTo(gray, CV_32F);
      use(gray);
    }
  };
  each_frame([&](const cv::Mat& g) {
    if (sum.empty()) {
      sum = cv::Mat::zeros(g.size(), CV_64F);
      squares = cv::Mat::zeros(g.size(), CV_64F);
    }
    cv::accumulate(g, sum);
    cv::accumulateSquare(g, squares);
    ++s.frames;
  });
  REQUIRE(s.frames > 10);
  const cv::Mat mean = sum / s.frames;
  cv::Mat variance = squares / s.frames - mean.mul(mean);
  cv::sqrt(cv::max(variance, 0.0), s.spread);
  cv::Mat blurred, gx, gy;
  cv::GaussianBlur(mean, blurred, {0, 0}, 2.0);
  cv::Sobel(blurred, gx, CV_64F, 1, 0, 3, 1.0 / 8.0);  // 1/8: levels per pixel
  cv::Sobel(blurred, gy, CV_64F, 0, 1, 3, 1.0 / 8.0);
  cv::magnitude(gx, gy, s.gradient);
  cv::Mat background, smooth, difference;
  mean.convertTo(background, CV_32F);
  cv::blur(background, background, {9, 9});
  s.departure = cv::Mat::zeros(mean.size(), CV_32F);
  each_frame([&](const cv::Mat& g) {
    cv::blur(g, smooth, {9, 9});
    cv::absdiff(smooth, background, difference);
    s.departure = cv::max(s.departure, difference);
  });
  return s;
}

/// Up to `count` points, strongest gradient first, at least `spacing` px
/// apart, among those where `keep(x, y)`.
template <class Keep>
std::vector<cv::Point> strongest(const ClipStatistics& s, int margin, int spacing, std::size_t count, Keep keep) {
  struct Candidate {
    double g;
    cv::Point p;
  };
  std::vector<Candidate> candidates;
  for (int y = margin; y < s.gradient.rows - margin; ++y)
    for (int x = margin; x < s.gradient.cols - margin; ++x)
      if (keep(x, y)) candidates.push_back({s.gradient.at<double>(y, x), {x, y}});
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.g > b.g; });
  std::vector<cv::Point> points;
  for (const Candidate& c : candidates) {
    if (points.size() >= count) break;
    if (std::none_of(points.begin(), points.end(), [&](const cv::Point& p) {
          return std::abs(p.x - c.p.x) < spacing && std::abs(p.y - c.p.y) < spacing;
        }))
      points.push_back(c.p);
  }
  return points;
}

/// Runs tangible_video --probes with `denoise`; the forces, row by row in
/// the probes' order, as (fx, fy).
std::vector<cv::Vec2d> tool_forces(const std::string& clip, const std::string& probes, const std::string& denoise) {
  const std::string forces = (tmp / ("forces_" + denoise + ".csv")).string();
  Child child(HAPTICFIELD_TOOL_TANGIBLE_VIDEO, {clip, "--denoise", denoise, "--probes", probes, "--forces", forces},
              tmp, "probes_" + denoise, false);
  REQUIRE(child.wait(std::chrono::seconds(120)));
  CAPTURE(child.out(), child.err());
  REQUIRE(child.status() == 0);
  std::ifstream in(forces);
  std::string line;
  REQUIRE(std::getline(in, line));
  REQUIRE(line == "t,x,y,fx,fy");
  std::vector<cv::Vec2d> rows;
  while (std::getline(in, line)) {
    double t = 0, x = 0, y = 0, fx = 0, fy = 0;
    REQUIRE(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &x, &y, &fx, &fy) == 5);
    rows.push_back({fx, fy});
  }
  return rows;
}

double percentile(std::vector<double> v, double q) {
  const auto i = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + i, v.end());
  return v[static_cast<std::size_t>(i)];
}

}  // namespace

TEST_CASE(
    "tangible_video --denoise temporal through the tool: less flicker at static edges of vtest.avi, "
    "moving edges kept",
    "[video][real][denoise]") {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  const std::string clip = vtest_clip();
  if (clip.empty()) {
    WARN("SKIPPED: opencv-doc's vtest.avi is not installed (apt-get install opencv-doc)");
    return;
  }
  fs::create_directories(tmp);
  const ClipStatistics s = clip_statistics(clip);
  // Static: within 12 px (the 17 px mask's reach and the denoiser's motion
  // window) no frame departs from the mean by 6 levels or more: nobody passes
  // near, not even for a few frames (a small temporal spread alone lets a
  // brief passer-by in: 2.0x at such points, the heads passing by included).
  cv::Mat departure_near;
  cv::dilate(s.departure, departure_near, cv::Mat::ones(25, 25, CV_8U));
  const std::vector<cv::Point> still =
      strongest(s, 20, 8, 150, [&](int x, int y) { return departure_near.at<float>(y, x) < 6.0f; });
  // Moving: people walk across the point (a spread above 20 levels there).
  const std::vector<cv::Point> moving =
      strongest(s, 20, 8, 150, [&](int x, int y) { return s.spread.at<double>(y, x) > 20.0; });
  REQUIRE(still.size() >= 40);
  REQUIRE(moving.size() >= 100);
  std::vector<cv::Point> points = still;
  points.insert(points.end(), moving.begin(), moving.end());

  // Probes at every frame's mid-time (k + 1/2) / fps over the whole clip.
  const std::string probes = (tmp / "probes.csv").string();
  {
    std::ofstream out(probes);
    out.precision(17);
    out << "t,x,y\n";
    for (int k = 0; k + 1 < s.frames; ++k)
      for (const cv::Point& p : points)
        out << (k + 0.5) / s.fps << ',' << p.x << ',' << p.y << '\n';
  }
  const std::vector<cv::Vec2d> none = tool_forces(clip, probes, "none");
  const std::vector<cv::Vec2d> temporal = tool_forces(clip, probes, "temporal");
  const std::size_t n = points.size(), times = static_cast<std::size_t>(s.frames - 1);
  REQUIRE(none.size() == times * n);
  REQUIRE(temporal.size() == times * n);
  const auto at = [n](const std::vector<cv::Vec2d>& f, std::size_t k, std::size_t i) { return f[k * n + i]; };

  // The clip fades in from zero force over the default fade (100 ms): the
  // step from the mid-time of frame 0 (inside the fade) to that of frame 1
  // is the whole force, in both modes. Flicker is measured from the first
  // step after the fade, and shown with that step too.
  const double fade = 0.1;
  const auto first_after_fade = static_cast<std::size_t>(std::ceil(fade * s.fps + 0.5));  // (k - 1/2) / fps >= fade
  double none2 = 0, temporal2 = 0, start_step2 = 0, mean_force = 0;
  for (std::size_t k = 1; k < times; ++k)
    for (std::size_t i = 0; i < still.size(); ++i) {
      const double a = cv::norm(at(none, k, i) - at(none, k - 1, i));
      const double b = cv::norm(at(temporal, k, i) - at(temporal, k - 1, i));
      if (k < first_after_fade) {
        start_step2 += b * b;
        continue;
      }
      none2 += a * a;
      temporal2 += b * b;
      mean_force += cv::norm(at(none, k, i));
    }
  const double steps = static_cast<double>((times - first_after_fade) * still.size());
  const double flicker_none = std::sqrt(none2 / steps), flicker_temporal = std::sqrt(temporal2 / steps);
  const double ratio = flicker_none / flicker_temporal;
  const double with_start =
      std::sqrt((none2 + start_step2) / (steps + static_cast<double>(still.size() * (first_after_fade - 1)))) /
      std::sqrt((temporal2 + start_step2) / (steps + static_cast<double>(still.size() * (first_after_fade - 1))));

  // Moving edges: an undenoised force above 0.05 that changed by a quarter
  // since the mid-time before (an edge passing), after the fade.
  std::vector<double> errors;
  for (std::size_t k = first_after_fade; k < times; ++k)
    for (std::size_t i = still.size(); i < n; ++i) {
      const cv::Vec2d f = at(none, k, i);
      const double size = cv::norm(f);
      if (size <= 0.05 || cv::norm(f - at(none, k - 1, i)) <= 0.25 * size) continue;
      errors.push_back(cv::norm(at(temporal, k, i) - f) / size);
    }
  REQUIRE(errors.size() >= 500);
  const double moving_mean = std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size());
  const double moving_p90 = percentile(errors, 0.9);

  INFO(s.frames << " frames at " << s.fps << " fps; " << still.size() << " static edge points (mean |F| "
                << mean_force / steps << "): flicker none " << flicker_none << ", temporal " << flicker_temporal
                << ", cut " << ratio << "x (" << with_start << "x with the start's fade-in step); " << errors.size()
                << " moving edge samples at " << moving.size() << " points: error mean " << moving_mean << ", p90 "
                << moving_p90);
  // Measured: 4.35x (6.4e-4 / 1.5e-4; 1.00x with the start's step), moving edges mean 0.007, p90 0.018.
  CHECK(ratio >= 3.0);
  CHECK(moving_p90 <= 0.25);
  CHECK(moving_mean <= 0.1);
}
