// view_check SHOT.png SOURCE.png X,Y
// Checks a screenshot of hapticfield_view (its own --screenshot, or a grab
// of the whole X screen): the source picture appears in it at its own size
// (found by OpenCV's template matching, wherever the window is), away from
// the probe it is the picture pixel for pixel, and the pixel at picture
// position (X, Y) [px] has the cursor's colour (magenta, 255,0,255 in RGB).
// Exit 0 when all hold, 1 otherwise, with one line saying what was found.
//
// view_check SHOT.png CLIP.avi X,Y T LO,HI
// The same for a video: the clip is decoded here (cv::VideoCapture, apart
// from the viewer), the screenshot must show frame floor(T * fps) and no
// other frame as closely, and the viewer's video time T [s] must be in
// [LO, HI].
//
// view_check --make-clip OUT.avi
// Writes the test clip: 30 frames of 400 x 300 px at 10 fps (MJPG), a
// white square on a gradient moving 12 px right per frame.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace {

int make_clip(const char* path) {
  cv::VideoWriter w(path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(400, 300));
  if (!w.isOpened()) {
    std::fprintf(stderr, "view_check: cannot write %s\n", path);
    return 1;
  }
  w.set(cv::VIDEOWRITER_PROP_QUALITY, 100);
  for (int k = 0; k < 30; ++k) {
    cv::Mat f(300, 400, CV_8UC3);
    for (int y = 0; y < 300; ++y)
      f.row(y).setTo(cv::Scalar(40 + y / 3, 60, 140 - y / 3));
    cv::rectangle(f, cv::Rect(10 + 12 * k, 20, 40, 40), cv::Scalar::all(255), cv::FILLED);
    w.write(f);
  }
  return 0;
}

/// Mean |difference| of `region` and `source` away from the probe, the worst channel [levels].
double difference(const cv::Mat& region, const cv::Mat& source, const cv::Mat& mask) {
  cv::Mat diff;
  cv::absdiff(region, source, diff);
  const cv::Scalar mean_diff = cv::mean(diff, mask);
  return std::max({mean_diff[0], mean_diff[1], mean_diff[2]});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--make-clip") return make_clip(argv[2]);
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr,
                 "usage: view_check SHOT.png SOURCE.png X,Y | SHOT.png CLIP.avi X,Y T LO,HI | --make-clip OUT.avi\n");
    return 2;
  }
  const bool video = argc == 6;
  const cv::Mat shot = cv::imread(argv[1], cv::IMREAD_COLOR);
  double px = 0.0, py = 0.0, t = 0.0, lo = 0.0, hi = 0.0;
  std::vector<cv::Mat> frames;
  double fps = 0.0;
  if (video) {
    cv::VideoCapture capture(argv[2]);
    fps = capture.get(cv::CAP_PROP_FPS);
    for (cv::Mat f; capture.read(f);)
      frames.push_back(f.clone());
    if (std::sscanf(argv[4], "%lf", &t) != 1 || std::sscanf(argv[5], "%lf,%lf", &lo, &hi) != 2 || frames.empty() ||
        !(fps > 0.0)) {
      std::fprintf(stderr, "view_check: cannot decode %s, or bad T '%s' or LO,HI '%s'\n", argv[2], argv[4], argv[5]);
      return 1;
    }
  } else {
    frames.push_back(cv::imread(argv[2], cv::IMREAD_COLOR));
  }
  const long expected = video ? static_cast<long>(std::floor(t * fps + 1e-9)) : 0;
  if (expected < 0 || expected >= static_cast<long>(frames.size())) {
    std::printf("view_check: FAIL: video time %.4f s is frame %ld, outside the clip's %zu frames\n", t, expected,
                frames.size());
    return 1;
  }
  const cv::Mat source = frames[static_cast<std::size_t>(expected)];
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
  cv::Mat mask(source.size(), CV_8U, cv::Scalar(255));
  cv::circle(mask, cv::Point(static_cast<int>(std::lround(px)), static_cast<int>(std::lround(py))), 132, cv::Scalar(0),
             cv::FILLED);
  const double worst_channel = difference(region, source, mask);
  // a video: no other frame may match as well (the frames differ visibly)
  long best_frame = expected;
  double runner_up = HUGE_VAL;
  for (std::size_t k = 0; video && k < frames.size(); ++k) {
    if (static_cast<long>(k) == expected) continue;
    const double d = difference(region, frames[k], mask);
    runner_up = std::min(runner_up, d);
    if (d <= worst_channel) best_frame = static_cast<long>(k);
  }
  const bool frame_ok = !video || (best_frame == expected && runner_up > worst_channel + 0.5 && t >= lo && t <= hi);
  // the cursor at the probe
  const cv::Point probe = at + cv::Point(static_cast<int>(std::lround(px)), static_cast<int>(std::lround(py)));
  bool cursor = false;
  cv::Vec3b seen{};
  if (probe.x >= 0 && probe.y >= 0 && probe.x < shot.cols && probe.y < shot.rows) {
    seen = shot.at<cv::Vec3b>(probe);
    cursor = seen == cv::Vec3b(255, 0, 255);  // BGR
  }
  const bool ok = best > 0.95 && worst_channel < 2.0 && cursor && frame_ok;
  std::printf(
      "view_check: %s: picture at %d,%d (correlation %.4f), mean |difference| away from the probe %.3f "
      "levels, pixel at the probe (%d,%d) RGB %d,%d,%d%s\n",
      ok ? "ok" : "FAIL", at.x, at.y, best, worst_channel, probe.x, probe.y, seen[2], seen[1], seen[0],
      cursor ? " (the cursor)" : " (not the cursor)");
  if (video)
    std::printf(
        "view_check: video time %.4f s (expected in [%.4f, %.4f]) is frame %ld at %.3f fps; the closest frame is "
        "%ld, the next closest differs by %.3f levels\n",
        t, lo, hi, expected, fps, best_frame, runner_up);
  return ok ? 0 : 1;
}
