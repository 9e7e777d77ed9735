// Tangible video: the cost of preparing a frame (gray, denoise, scene cut,
// the O(1) kernel's tables) at 1280 x 720 and 1920 x 1080 against the frame
// period and against rebuilding the same force planes per frame with
// cv::filter2D / cv::sepFilter2D; the per-tick cost of the video field
// against the still-picture field; and the force flicker that denoising
// removes on a real compressed clip (opencv-doc's vtest.avi, when present).
// All on one core (cv::setNumThreads(1)), ratios against baselines measured
// in the same run.
//
//   bench_video [--frames N] [--ticks N] [--clip PATH] [--plots DIR]
#include <hapticfield/video.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace hf = hapticfield;
using Clock = std::chrono::steady_clock;

namespace {

struct Stats {
  double mean = 0.0, p99 = 0.0, worst = 0.0;
};

Stats summarise(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()),
          v[static_cast<std::size_t>(0.99 * static_cast<double>(v.size() - 1))], v.back()};
}

double since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

volatile double sink = 0.0;

/// A moving synthetic scene with codec-like noise: shapes drifting right by
/// 3 px per frame over a textured background, fresh noise each frame.
cv::Mat synthetic_frame(cv::Size size, int k) {
  cv::Mat m(size, CV_8UC3);
  for (int y = 0; y < size.height; ++y) {
    auto* row = m.ptr<cv::Vec3b>(y);
    for (int x = 0; x < size.width; ++x) {
      const auto v = static_cast<unsigned char>(128 + 70 * std::sin((x + 3 * k) * 0.02) * std::cos(y * 0.015));
      row[x] = {v, static_cast<unsigned char>(v / 2 + 40), static_cast<unsigned char>(255 - v)};
    }
  }
  cv::circle(m, {size.width / 3 + 3 * k, size.height / 2}, size.height / 5, cv::Scalar(20, 20, 20), cv::FILLED);
  cv::Mat noise(size, CV_8UC3);
  cv::randn(noise, cv::Scalar::all(0), cv::Scalar::all(4));
  m += noise;
  return m;
}

void bench_prepare(cv::Size size, int frames) {
  std::vector<cv::Mat> input;
  for (int k = 0; k < 8; ++k)
    input.push_back(synthetic_frame(size, k));
  const int m = 17;
  struct Route {
    const char* name;
    std::vector<double> ms;
  };
  std::vector<Route> routes = {{"gray + tables, no denoising (ours)", {}},
                               {"gray + temporal denoising + tables (ours)", {}},
                               {"gray + spatial (bilateral) + tables (ours)", {}},
                               {"gray + both + tables (ours)", {}},
                               {"gray + temporal + direct kernel, no tables (ours)", {}},
                               {"gray + 2 x cv::filter2D (CV_32F, 17 x 17)", {}},
                               {"gray + 2 x cv::sepFilter2D (CV_32F)", {}}};
  hf::PrepareConfig base;
  base.tangible.size = m;
  std::vector<hf::FramePreparer> preparers;
  for (hf::DenoiseMode mode :
       {hf::DenoiseMode::none, hf::DenoiseMode::temporal, hf::DenoiseMode::spatial, hf::DenoiseMode::both}) {
    hf::PrepareConfig c = base;
    c.denoise.mode = mode;
    preparers.emplace_back(c);
  }
  {
    hf::PrepareConfig c = base;
    c.denoise.mode = hf::DenoiseMode::temporal;
    c.tangible.kernel = hf::KernelChoice::direct;  // O(m^2) per lookup, nothing to build
    preparers.emplace_back(c);
  }
  // The same planes through OpenCV: the Prewitt x mask (column - centre) on the inverted gray.
  cv::Mat ramp(m, 1, CV_32F), ones(m, 1, CV_32F, cv::Scalar(1.0f));
  for (int i = 0; i < m; ++i)
    ramp.at<float>(i) = static_cast<float>(i - m / 2);
  cv::Mat kx = ones * ramp.t(), ky = ramp * ones.t();
  cv::Mat gray, inv, fx, fy;
  for (int round = 0; round < frames + 2; ++round) {  // two warm-up rounds, interleaved routes
    const cv::Mat& frame = input[static_cast<std::size_t>(round) % input.size()];
    for (std::size_t r = 0; r < routes.size(); ++r) {
      const auto t0 = Clock::now();
      if (r < 5) {
        auto f = preparers[r].prepare(frame, round, round / 30.0);
        sink = sink + f->image.at(10.0, 10.0).x;
      } else {
        hf::FramePreparer::to_gray32(frame, gray);
        inv = 255.0f - gray;
        if (r == 5) {
          cv::filter2D(inv, fx, CV_32F, kx);
          cv::filter2D(inv, fy, CV_32F, ky);
        } else {
          cv::sepFilter2D(inv, fx, CV_32F, ramp, ones);
          cv::sepFilter2D(inv, fy, CV_32F, ones, ramp);
        }
        sink = sink + fx.at<float>(10, 10) + fy.at<float>(10, 10);
      }
      if (round >= 2) routes[r].ms.push_back(since(t0));
    }
  }
  std::printf("\n### Preparing a frame, %d x %d px, Prewitt %d x %d, 1 thread, %d frames\n\n", size.width, size.height,
              m, m, frames);
  const Stats temporal = summarise(routes[1].ms);
  std::printf(
      "| route | mean [ms] | p99 [ms] | worst [ms] | share of a 30 fps period (mean / p99) | vs temporal (ours) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (const Route& r : routes) {
    const Stats s = summarise(r.ms);
    std::printf("| %s | %.2f | %.2f | %.2f | %.0f%% / %.0f%% | %.2fx |\n", r.name, s.mean, s.p99, s.worst,
                100.0 * s.mean / 33.333, 100.0 * s.p99 / 33.333, s.mean / temporal.mean);
  }
}

/// The previous temporal denoiser, kept as the baseline: a per-pixel running
/// average a += 0.25 (g - a) that takes g at once where |g - a| > 12 levels.
void previous_temporal(cv::Mat& gray, cv::Mat& average, bool new_scene) {
  if (new_scene || average.size() != gray.size()) {
    gray.copyTo(average);
    return;
  }
  for (int y = 0; y < gray.rows; ++y) {
    float* g = gray.ptr<float>(y);
    float* a = average.ptr<float>(y);
    for (int x = 0; x < gray.cols; ++x) {
      const float d = g[x] - a[x];
      const float next = (d > 12.0f || d < -12.0f) ? g[x] : a[x] + 0.25f * d;
      a[x] = next;
      g[x] = next;
    }
  }
}

/// The temporal denoiser alone (gray frame in, denoised frame out), ours
/// against the previous per-pixel one, interleaved in the same run.
void bench_denoise(cv::Size size, int frames) {
  std::vector<cv::Mat> input;
  for (int k = 0; k < 8; ++k) {
    cv::Mat gray;
    hf::FramePreparer::to_gray32(synthetic_frame(size, k), gray);
    input.push_back(gray);
  }
  hf::FrameDenoiser ours{hf::DenoiseConfig{}};
  cv::Mat average, work;
  std::vector<double> ms_ours, ms_previous;
  for (int round = 0; round < frames + 2; ++round) {  // two warm-up rounds
    const cv::Mat& frame = input[static_cast<std::size_t>(round) % input.size()];
    frame.copyTo(work);
    auto t0 = Clock::now();
    ours.apply(work, round == 0);
    if (round >= 2) ms_ours.push_back(since(t0));
    sink = sink + work.at<float>(10, 10);
    frame.copyTo(work);
    t0 = Clock::now();
    previous_temporal(work, average, round == 0);
    if (round >= 2) ms_previous.push_back(since(t0));
    sink = sink + work.at<float>(10, 10);
  }
  const Stats a = summarise(ms_ours), b = summarise(ms_previous);
  std::printf("\n### Temporal denoising alone, %d x %d px, 1 thread, %d frames\n\n", size.width, size.height, frames);
  std::printf("| denoiser | mean [ms] | p99 [ms] | vs previous |\n|---|---|---|---|\n");
  std::printf("| motion-adaptive, 7 x 7 motion measure (ours) | %.2f | %.2f | %.2fx |\n", a.mean, a.p99,
              a.mean / b.mean);
  std::printf("| previous per-pixel threshold | %.2f | %.2f | 1.00x |\n", b.mean, b.p99);
}

void bench_decode(const std::string& path, int frames) {
  hf::VideoSource source(path);
  cv::Mat frame;
  long index = 0;
  std::vector<double> ms;
  for (int i = 0; i < frames; ++i) {
    const auto t0 = Clock::now();
    if (!source.read(frame, index)) break;
    ms.push_back(since(t0));
  }
  if (ms.empty()) return;
  const Stats s = summarise(ms);
  std::printf("\ndecoding %s (%d x %d px): mean %.2f ms, p99 %.2f ms per frame (%zu frames)\n", path.c_str(),
              source.width(), source.height(), s.mean, s.p99, ms.size());
}

void bench_ticks(const std::string& clip, int ticks, hf::KernelChoice kernel) {
  // The still-picture field on the first frame, against the video field
  // paused mid-way between frames 3 and 4, after the fade-in at the start
  // (two lookups and a blend per tick).
  hf::VideoSource first(clip);
  cv::Mat frame;
  long index = 0;
  (void)first.read(frame, index);
  hf::TangibleConfig options;
  options.border = hf::Border::fade;
  options.kernel = kernel;
  const hf::PlaneMapping mapping = hf::PlaneMapping::fit(frame.cols, frame.rows, 80.0);
  hf::TangibleImageField still(hf::TangibleImage(hf::to_gray(frame), options), mapping, 1.0);
  hf::VideoFieldConfig config;
  config.prepare.tangible = options;
  config.playback.start = 3.5 / first.fps();
  config.fade = 0.0;  // steady state: no fade-in at the start
  hf::VideoField video(std::make_unique<hf::VideoSource>(clip), mapping, config);
  video.playback().pause();
  hf::Probe probe;
  for (int i = 0; i < 5000 && video.statistics().published == 0; ++i) {
    probe.time = i * 1e-3;
    (void)video.force(probe);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const double radius = 0.025;  // [m]; the HIP circles at 0.1 m/s
  std::vector<double> a_ns, b_ns;
  for (int round = 0; round < 10; ++round) {
    for (int which = 0; which < 2; ++which) {
      for (int i = 0; i < ticks / 10; ++i) {
        const double phase = (round * (ticks / 10) + i) * 1e-3 * 0.1 / radius;
        probe.position = {radius * std::cos(phase), radius * std::sin(phase), 0.0};
        probe.time += 1e-3;
        const auto t0 = Clock::now();
        const glm::dvec3 f = which == 0 ? still.force(probe) : video.force(probe);
        const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
        sink = sink + f.x;
        (which == 0 ? a_ns : b_ns).push_back(ns);
      }
    }
  }
  const Stats a = summarise(a_ns), b = summarise(b_ns);
  const char* name = kernel == hf::KernelChoice::direct ? "direct kernel" : "O(1) kernel";
  std::printf("\n### Per tick, %d x %d px, Prewitt 17 (%s), %d ticks each, interleaved\n\n", frame.cols, frame.rows,
              name, ticks);
  std::printf(
      "| field | mean [ns] | p99 [ns] | worst [ns] | mean / still | p99 / still |\n|---|---|---|---|---|---|\n");
  std::printf("| TangibleImageField (still picture, baseline) | %.0f | %.0f | %.0f | 1.00x | 1.00x |\n", a.mean, a.p99,
              a.worst);
  std::printf("| VideoField (clock, live window, blend of 2 frames) | %.0f | %.0f | %.0f | %.2fx | %.2fx |\n", b.mean,
              b.p99, b.worst, b.mean / a.mean, b.p99 / a.p99);
}

/// Force flicker at static points: per grid point, the RMS frame-to-frame
/// change of the normalised force; the median over points (moving people
/// in a street scene do not dominate it).
void bench_flicker(const std::string& clip, const std::string& plots) {
  std::printf(
      "\n### Force flicker on %s (frame-to-frame RMS change of the normalised force, median over a "
      "24 x 18 grid)\n\n| denoise | m = 9 | m = 17 | m = 33 |\n|---|---|---|---|\n",
      clip.c_str());
  // fx over time at every grid point, per mode, m = 17
  std::vector<std::vector<std::vector<double>>> traces;
  std::vector<double> none_rms;  // m = 17, per grid point
  for (hf::DenoiseMode mode :
       {hf::DenoiseMode::none, hf::DenoiseMode::temporal, hf::DenoiseMode::spatial, hf::DenoiseMode::both}) {
    std::printf("| %s |", hf::to_string(mode));
    for (int m : {9, 17, 33}) {
      hf::VideoSource source(clip);
      hf::PrepareConfig c;
      c.tangible.size = m;
      c.denoise.mode = mode;
      hf::VideoTimeline timeline(source, c, 0.0);
      const int gx = 24, gy = 18;
      std::vector<double> sum2(gx * gy, 0.0);
      std::vector<glm::dvec2> previous(gx * gy);
      std::vector<std::vector<double>> trace(gx * gy);
      int n = 0;
      for (long k = 0; k < 200; ++k) {
        const double t = k / source.fps();
        for (int j = 0; j < gy; ++j)
          for (int i = 0; i < gx; ++i) {
            const double x = (i + 0.5) * source.width() / gx, y = (j + 0.5) * source.height() / gy;
            const glm::dvec2 f = timeline.at(t, x, y);
            const int p = j * gx + i;
            if (k > 0) sum2[p] += glm::dot(f - previous[p], f - previous[p]);
            if (m == 17) trace[p].push_back(f.x);
            previous[p] = f;
          }
        if (k > 0) ++n;
        if (timeline.ended()) break;
      }
      std::vector<double> rms;
      for (double s : sum2)
        rms.push_back(std::sqrt(s / n));
      if (m == 17 && mode == hf::DenoiseMode::none) none_rms = rms;
      std::nth_element(rms.begin(), rms.begin() + static_cast<long>(rms.size() / 2), rms.end());
      std::printf(" %.5f |", rms[rms.size() / 2]);
      if (m == 17) traces.push_back(trace);
    }
    std::printf("\n");
  }
  if (plots.empty()) return;
  std::filesystem::create_directories(plots);
  // The grid point of median flicker without denoising: a typical static point.
  std::vector<std::size_t> order(none_rms.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::nth_element(order.begin(), order.begin() + static_cast<long>(order.size() / 2), order.end(),
                   [&](std::size_t a, std::size_t b) { return none_rms[a] < none_rms[b]; });
  const std::size_t point = order[order.size() / 2];
  std::vector<std::vector<double>> shown;
  for (const auto& mode_traces : traces)
    shown.push_back(mode_traces[point]);
  const int w = 900, h = 300, mg = 40;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  double lo = 1e9, hi = -1e9;
  for (const auto& t : shown)
    for (double v : t)
      lo = std::min(lo, v), hi = std::max(hi, v);
  if (hi <= lo) hi = lo + 1e-6;
  const cv::Scalar colours[4] = {{0, 0, 220}, {200, 0, 0}, {0, 150, 0}, {0, 0, 0}};
  for (std::size_t c = 0; c < shown.size(); ++c)
    for (std::size_t i = 1; i < shown[c].size(); ++i) {
      const auto pt = [&](std::size_t k) {
        return cv::Point(mg + static_cast<int>((w - 2 * mg) * static_cast<double>(k) / (shown[c].size() - 1)),
                         h - mg - static_cast<int>((h - 2 * mg) * (shown[c][k] - lo) / (hi - lo)));
      };
      cv::line(img, pt(i - 1), pt(i), colours[c], 1, cv::LINE_AA);
    }
  char title[200];
  std::snprintf(title, sizeof title,
                "fx at a static point of the clip, 200 frames, m = 17 (range %.4f..%.4f): none red, "
                "temporal blue, spatial green, both black",
                lo, hi);
  cv::putText(img, title, {mg, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0}, 1, cv::LINE_AA);
  cv::imwrite(plots + "/flicker.png", img);
  std::printf("\nwrote %s/flicker.png\n", plots.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  hf::quiet_video_logs(false);
  cv::setNumThreads(1);
  int frames = 30, ticks = 200000;
  std::string clip = "/usr/share/doc/opencv-doc/examples/data/vtest.avi";
  std::string plots;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--frames")
      frames = std::max(1, std::atoi(argv[i + 1]));
    else if (a == "--ticks")
      ticks = std::max(1000, std::atoi(argv[i + 1]));
    else if (a == "--clip")
      clip = argv[i + 1];
    else if (a == "--plots")
      plots = argv[i + 1];
  }
  std::printf("bench_video: 1 OpenCV thread; a 30 fps frame period is 33.3 ms, 60 fps 16.7 ms\n");
  bench_prepare({1280, 720}, frames);
  bench_prepare({1920, 1080}, frames);
  bench_denoise({1280, 720}, frames);
  bench_denoise({1920, 1080}, frames);
  // A 1280 x 720 MJPG clip written here, for decoding and ticks.
  const std::string hd = (std::filesystem::temp_directory_path() / "bench_video_720p.avi").string();
  {
    cv::VideoWriter w(hd, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, {1280, 720});
    for (int k = 0; k < 40; ++k)
      w.write(synthetic_frame({1280, 720}, k));
  }
  bench_decode(hd, 40);
  bench_ticks(hd, ticks, hf::KernelChoice::automatic);
  bench_ticks(hd, ticks / 4, hf::KernelChoice::direct);
  if (std::filesystem::exists(clip)) {
    bench_decode(clip, 100);
    bench_flicker(clip, plots);
  } else {
    std::printf("\n(no %s: the flicker measurement on a real clip is skipped; apt-get install opencv-doc)\n",
                clip.c_str());
  }
  std::filesystem::remove(hd);
  return 0;
}
