// view_check SHOT.png SOURCE.png X,Y
// Checks a screenshot of hapticfield_view (its own --screenshot, or a grab
// of the whole X screen): the source picture appears in it at its own size
// (found by OpenCV's template matching, wherever the window is), away from
// the probe it is the picture pixel for pixel, and the pixel at picture
// position (X, Y) [px] has the cursor's colour (magenta, 255,0,255 in RGB).
// Exit 0 when all hold, 1 otherwise, with one line saying what was found.
#include <cmath>
#include <cstdio>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: view_check SHOT.png SOURCE.png X,Y\n");
    return 2;
  }
  const cv::Mat shot = cv::imread(argv[1], cv::IMREAD_COLOR);
  const cv::Mat source = cv::imread(argv[2], cv::IMREAD_COLOR);
  double px = 0.0, py = 0.0;
  if (shot.empty() || source.empty() || std::sscanf(argv[3], "%lf,%lf", &px, &py) != 2) {
    std::fprintf(stderr, "view_check: cannot read %s or %s, or bad X,Y '%s'\n", argv[1], argv[2], argv[3]);
    return 1;
  }
  if (shot.cols < source.cols || shot.rows < source.rows) {
    std::printf("view_check: FAIL: the screenshot (%dx%d) is smaller than the picture (%dx%d)\n", shot.cols, shot.rows,
                source.cols, source.rows);
    return 1;
  }
  // where is the picture? (normalised correlation; the cursor and arrow
  // cover a small part of it)
  cv::Mat score;
  cv::matchTemplate(shot, source, score, cv::TM_CCOEFF_NORMED);
  double best = 0.0;
  cv::Point at;
  cv::minMaxLoc(score, nullptr, &best, nullptr, &at);
  // away from the probe (cursor 10 px, arrow at most 120 px), the picture
  const cv::Mat region = shot(cv::Rect(at, source.size()));
  cv::Mat diff;
  cv::absdiff(region, source, diff);
  cv::Mat mask(source.size(), CV_8U, cv::Scalar(255));
  cv::circle(mask, cv::Point(static_cast<int>(std::lround(px)), static_cast<int>(std::lround(py))), 132, cv::Scalar(0),
             cv::FILLED);
  const cv::Scalar mean_diff = cv::mean(diff, mask);
  const double worst_channel = std::max({mean_diff[0], mean_diff[1], mean_diff[2]});
  // the cursor at the probe
  const cv::Point probe = at + cv::Point(static_cast<int>(std::lround(px)), static_cast<int>(std::lround(py)));
  bool cursor = false;
  cv::Vec3b seen{};
  if (probe.x >= 0 && probe.y >= 0 && probe.x < shot.cols && probe.y < shot.rows) {
    seen = shot.at<cv::Vec3b>(probe);
    cursor = seen == cv::Vec3b(255, 0, 255);  // BGR
  }
  const bool ok = best > 0.95 && worst_channel < 2.0 && cursor;
  std::printf(
      "view_check: %s: picture at %d,%d (correlation %.4f), mean |difference| away from the probe %.3f "
      "levels, pixel at the probe (%d,%d) RGB %d,%d,%d%s\n",
      ok ? "ok" : "FAIL", at.x, at.y, best, worst_channel, probe.x, probe.y, seen[2], seen[1], seen[0],
      cursor ? " (the cursor)" : " (not the cursor)");
  return ok ? 0 : 1;
}
