// Per-query and full-map cost of the tangible-image kernels on a picture of
// the paper's size (1000 x 1504), as ratios against baselines measured in
// the same run: the direct kernel at m = 5 for queries, OpenCV's filter2D
// and sepFilter2D for the full map.
//
//   bench_tangible [IMAGE] [--queries N] [--maps N]
#include <hapticfield/kernels.hpp>
#include <hapticfield/offline/tick_budget.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace hf = hapticfield;
using Clock = std::chrono::steady_clock;

namespace {

struct Stats {
  double mean = 0.0;   // [ns]
  double p99 = 0.0;    // [ns]
  double worst = 0.0;  // [ns]
};

Stats summarise(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  Stats s;
  s.mean = std::accumulate(samples.begin(), samples.end(), 0.0) / samples.size();
  s.p99 = samples[static_cast<std::size_t>(0.99 * (samples.size() - 1))];
  s.worst = samples.back();
  return s;
}

volatile double sink = 0.0;

/// Query positions: random over the picture (cold caches), or a HIP tracing
/// circles at 100 mm/s on a 6.4 px/mm picture (0.64 px per 1 ms tick, as in
/// a servo loop).
std::vector<glm::dvec2> query_points(int width, int height, int count, bool trajectory) {
  std::vector<glm::dvec2> points;
  points.reserve(count);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(0.0, width - 1.0);
  std::uniform_real_distribution<double> uy(0.0, height - 1.0);
  const double radius = 0.3 * std::min(width, height);  // [px]
  const double step = 0.64 / radius;                    // [rad per tick]
  for (int i = 0; i < count; ++i) {
    if (trajectory)
      points.push_back({width / 2.0 + radius * std::cos(i * step), height / 2.0 + radius * std::sin(i * step)});
    else
      points.push_back({ux(rng), uy(rng)});
  }
  return points;
}

/// Times each query alone through the tick-budget harness
/// (offline/tick_budget.hpp): a query is a tick whose probe sits at a pixel;
/// mean from an untimed pass, p99 and worst timed one by one, the clock's
/// own cost subtracted.
template <class Source>
Stats time_queries(const Source& source, const std::vector<glm::dvec2>& points) {
  std::vector<hf::Probe> probes(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    probes[i].position = {points[i].x, points[i].y, 0.0};
  auto query = [&source](const hf::Probe& p) noexcept {
    const glm::dvec2 f = source.at(p.position.x, p.position.y);
    return glm::dvec3{f.x, f.y, 0.0};
  };
  hf::offline::TickBudgetConfig config;
  config.warmup = 0;
  config.allocation_count = nullptr;
  const hf::offline::TickBudgetReport r = hf::offline::measure_tick_budget(query, probes, config);
  return {r.mean_ns, r.p99_ns, r.worst_ns};
}

/// The cost of reading the clock twice [ns] (the harness subtracts it).
double clock_cost() {
  hf::offline::TickBudgetConfig config;
  config.warmup = 0;
  config.allocation_count = nullptr;
  return hf::offline::measure_tick_cost(
             100000, [] {}, config)
      .clock_overhead_ns;
}

/// Runs every contender once to warm up, then once per round, rounds times,
/// so that load from elsewhere on the machine falls on all of them alike.
std::vector<Stats> time_rounds(int rounds, const std::vector<std::function<void()>>& contenders) {
  std::vector<std::vector<double>> samples(contenders.size());
  for (const auto& contender : contenders)
    contender();  // warm-up: first-touch page faults, caches
  for (int round = 0; round < rounds; ++round)
    for (std::size_t i = 0; i < contenders.size(); ++i) {
      const auto t0 = Clock::now();
      contenders[i]();
      samples[i].push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
    }
  std::vector<Stats> out;
  for (auto& s : samples)
    out.push_back(summarise(std::move(s)));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png";
  int queries = 200000;
  int map_runs = 30;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--queries" && i + 1 < argc)
      queries = std::atoi(argv[++i]);
    else if (a == "--maps" && i + 1 < argc)
      map_runs = std::atoi(argv[++i]);
    else
      path = a;
  }
  // The paper's picture size: 1000 x 1504 px.
  cv::Mat photo;
  cv::resize(hf::load_image(path), photo, cv::Size(1504, 1000), 0, 0, cv::INTER_CUBIC);
  const hf::GrayImage gray = hf::to_gray(photo);
  const double clock_ns = clock_cost();
  std::printf("picture %s resized to %d x %d px; clock read cost %.1f ns (subtracted)\n\n", path.c_str(), gray.width(),
              gray.height(), clock_ns);

  // --- per query: direct vs O(1) --------------------------------------------
  for (const bool trajectory : {true, false}) {
    const auto points = query_points(gray.width(), gray.height(), queries, trajectory);
    const std::vector<glm::dvec2> few(points.begin(), points.begin() + queries / 10);
    hf::TangibleConfig o;
    o.kernel = hf::KernelChoice::direct;
    o.size = 5;
    const hf::TangibleImage baseline_image(gray, o);
    (void)time_queries(baseline_image, points);  // warm-up pass, not reported
    const Stats baseline = time_queries(baseline_image, points);
    std::printf("Per-query cost, %s (bilinear: up to 4 pixel kernels); baseline = direct m=5, %.0f ns mean\n",
                trajectory ? "HIP tracing a circle at 0.64 px/tick" : "random positions (cold caches)", baseline.mean);
    std::printf(
        "| m | direct mean / p99 / worst [ns] | O(1) mean / p99 / worst [ns] | direct / O(1) (mean) | "
        "O(1) / direct m=5 (mean) | O(1) worst, share of 1 ms |\n|---|---|---|---|---|---|\n");
    for (int m : {3, 5, 17, 33, 65, 129}) {
      o.size = m;
      o.kernel = hf::KernelChoice::direct;
      const Stats direct = time_queries(hf::TangibleImage(gray, o), m >= 33 ? few : points);
      o.kernel = hf::KernelChoice::integral;
      const Stats fast = time_queries(hf::TangibleImage(gray, o), points);
      std::printf("| %d | %.0f / %.0f / %.0f | %.1f / %.0f / %.0f | %.1fx | %.2fx | %.3f%% |\n", m, direct.mean,
                  direct.p99, direct.worst, fast.mean, fast.p99, fast.worst, direct.mean / fast.mean,
                  fast.mean / baseline.mean, 100.0 * fast.worst / 1e6);
    }
    std::printf("\n");
  }

  // --- full map at m = 17: ours vs OpenCV --------------------------------------
  const int m = 17;
  cv::Mat gray32;
  hf::to_mat(gray).convertTo(gray32, CV_32F);
  cv::Mat kx(m, m, CV_32F);
  cv::Mat ky(m, m, CV_32F);
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c) {
      kx.at<float>(r, c) = static_cast<float>(c - m / 2);
      ky.at<float>(r, c) = static_cast<float>(r - m / 2);
    }
  cv::Mat ramp(1, m, CV_32F);
  cv::Mat ones(1, m, CV_32F, cv::Scalar(1.0f));
  for (int c = 0; c < m; ++c)
    ramp.at<float>(c) = static_cast<float>(c - m / 2);
  cv::Mat inv;
  cv::Mat fx;
  cv::Mat fy;
  // The same in double precision: the route that gives the same planes as ours to 1e-6.
  const cv::Mat gray64 = hf::to_mat(gray);
  cv::Mat ramp64;
  cv::Mat ones64;
  ramp.convertTo(ramp64, CV_64F);
  ones.convertTo(ones64, CV_64F);
  cv::Mat inv64;
  cv::Mat fx64;
  cv::Mat fy64;
  hf::ForceMap map;
  // The same picture with every level raised by 1/3: not an integer in any
  // fixed point, so prewitt_force_map takes its double route.
  hf::GrayImage fractional = gray;
  for (int y = 0; y < fractional.height(); ++y)
    for (int x = 0; x < fractional.width(); ++x)
      fractional.at(x, y) = std::min(255.0, gray.at(x, y) + 1.0 / 3.0);
  const auto opencv_threads = cv::getNumThreads();
  const int hardware_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const std::vector<Stats> r = time_rounds(
      map_runs, {
                    [&] {
                      hf::prewitt_force_map(gray, m, hf::Border::reflect,
                                            map);  // into a reused map, as OpenCV reuses fx, fy
                      sink = map.fx[map.fx.size() / 2];
                    },
                    [&] {
                      hf::prewitt_force_map(gray, m, hf::Border::reflect, map, hf::default_fade_px, hardware_threads);
                      sink = map.fx[map.fx.size() / 2];
                    },
                    [&] {
                      hf::prewitt_force_map(fractional, m, hf::Border::reflect, map);
                      sink = map.fx[map.fx.size() / 2];
                    },
                    [&] {
                      cv::setNumThreads(1);
                      cv::subtract(cv::Scalar::all(255.0), gray32, inv);
                      cv::filter2D(inv, fx, CV_32F, kx);
                      cv::filter2D(inv, fy, CV_32F, ky);
                    },
                    [&] {
                      cv::setNumThreads(1);
                      cv::subtract(cv::Scalar::all(255.0), gray32, inv);
                      cv::sepFilter2D(inv, fx, CV_32F, ramp, ones);
                      cv::sepFilter2D(inv, fy, CV_32F, ones, ramp);
                    },
                    [&] {
                      cv::setNumThreads(1);
                      cv::subtract(cv::Scalar::all(255.0), gray64, inv64);
                      cv::sepFilter2D(inv64, fx64, CV_64F, ramp64, ones64);
                      cv::sepFilter2D(inv64, fy64, CV_64F, ones64, ramp64);
                      fx64.convertTo(fx, CV_32F);
                      fy64.convertTo(fy, CV_32F);
                    },
                    [&] {
                      cv::setNumThreads(opencv_threads);
                      cv::subtract(cv::Scalar::all(255.0), gray32, inv);
                      cv::sepFilter2D(inv, fx, CV_32F, ramp, ones);
                      cv::sepFilter2D(inv, fy, CV_32F, ones, ramp);
                    },
                });
  const Stats& ours = r[0];
  std::printf("Full force map (fx and fy planes), m = %d, reflect border, %d interleaved rounds\n", m, map_runs);
  std::printf(
      "| route | mean [ms] | worst [ms] | speed-up of ours (mean) | speed-up of ours (worst) "
      "|\n|---|---|---|---|---|\n");
  const auto row = [&](const char* name, const Stats& s) {
    std::printf("| %s | %.2f | %.2f | %.1fx | %.1fx |\n", name, s.mean / 1e6, s.worst / 1e6, s.mean / ours.mean,
                s.worst / ours.worst);
  };
  std::printf("| prewitt_force_map, 1 thread (ours) | %.2f | %.2f | 1.0x | 1.0x |\n", ours.mean / 1e6,
              ours.worst / 1e6);
  row("prewitt_force_map, all threads (ours)", r[1]);
  row("prewitt_force_map, 1 thread, non-integer levels (double route)", r[2]);
  row("2 x cv::filter2D (CV_32F, 1 thread)", r[3]);
  row("2 x cv::sepFilter2D (CV_32F, 1 thread)", r[4]);
  row("2 x cv::sepFilter2D (CV_64F, 1 thread, then to float)", r[5]);
  row("2 x cv::sepFilter2D (CV_32F, all threads)", r[6]);
  std::printf("\nOur map on all %d threads against OpenCV's sepFilter2D on all threads: %.1fx (mean), %.1fx (worst)\n",
              hardware_threads, r[6].mean / r[1].mean, r[6].worst / r[1].worst);
  std::printf("Map route: %s; AVX2 build in use: %s\n",
              hf::detail::guess_fixed_point_scale(gray) > 0.0 ? "exact 32-bit integers" : "double",
              hf::detail::has_avx2() ? "yes" : "no");
  return 0;
}
