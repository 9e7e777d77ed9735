// Per-query and full-map cost of the tangible-image kernels on a picture of
// the paper's size (1000 x 1504), as ratios against baselines measured in
// the same run: the direct kernel at m = 5 for queries, OpenCV's filter2D
// and sepFilter2D for the full map.
//
// The map is also set against the memory floor of the same run: the time to
// read the picture and write the two float planes with nothing else.
//
//   bench_tangible [IMAGE] [--queries N] [--maps N] [--floor-only]
#include <hapticfield/kernels.hpp>
#include <hapticfield/servo/tick_budget.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <vector>

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define BENCH_X86 1
#else
#define BENCH_X86 0
#endif

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
/// (servo/tick_budget.hpp): a query is a tick whose probe sits at a pixel;
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

// --- memory floor --------------------------------------------------------------
// The least any full map can cost: read every gray level of the picture (a
// double, as GrayImage stores it: 8 bytes) and write the two float planes
// (4 + 4 bytes), with no arithmetic worth the name. Several ways of moving
// those bytes; the fastest one in the run is the floor.

/// One float per plane from each level: a plain loop the compiler vectorises.
void floor_loop(const double* __restrict in, std::size_t n, float* __restrict fx, float* __restrict fy) {
  for (std::size_t i = 0; i < n; ++i) {
    const float v = static_cast<float>(in[i]);
    fx[i] = v;
    fy[i] = v;
  }
}

#if BENCH_X86
/// The same with non-temporal stores (no read of the output lines before
/// they are written), as the map's AVX2 route writes.
__attribute__((target("avx2"))) void floor_stream(const double* __restrict in, std::size_t n, float* __restrict fx,
                                                  float* __restrict fy) {
  std::size_t i = 0;
  while (i < n && (reinterpret_cast<std::uintptr_t>(fx + i) & 31u) != 0) {
    fx[i] = static_cast<float>(in[i]);
    fy[i] = static_cast<float>(in[i]);
    ++i;
  }
  const bool same_phase = ((reinterpret_cast<std::uintptr_t>(fx) ^ reinterpret_cast<std::uintptr_t>(fy)) & 31u) == 0;
  if (same_phase)
    for (; i + 8 <= n; i += 8) {
      const __m128 lo = _mm256_cvtpd_ps(_mm256_loadu_pd(in + i));
      const __m128 hi = _mm256_cvtpd_ps(_mm256_loadu_pd(in + i + 4));
      const __m256 v = _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
      _mm256_stream_ps(fx + i, v);
      _mm256_stream_ps(fy + i, v);
    }
  for (; i < n; ++i) {
    fx[i] = static_cast<float>(in[i]);
    fy[i] = static_cast<float>(in[i]);
  }
  _mm_sfence();
}
#endif

/// The picture's bytes copied as they are: its first half into fx, its
/// second into fy (8 bytes a pixel in, 4 + 4 out), by the C library.
void floor_memcpy(const double* in, std::size_t n, float* fx, float* fy) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(in);
  std::memcpy(fx, bytes, n * sizeof(float));
  std::memcpy(fy, bytes + n * sizeof(float), n * sizeof(float));
}

/// A summing read of the picture, then the planes filled by memset.
void floor_read_memset(const double* __restrict in, std::size_t n, float* fx, float* fy) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += in[i];
    s1 += in[i + 1];
    s2 += in[i + 2];
    s3 += in[i + 3];
  }
  for (; i < n; ++i)
    s0 += in[i];
  sink = s0 + s1 + s2 + s3;
  std::memset(fx, 0, n * sizeof(float));
  std::memset(fy, 0, n * sizeof(float));
}

/// The map at m = 17 against the memory floor, for square pictures of
/// 1, 4 and 16 Mpx (8 to 128 MB of doubles: at and beyond the last-level
/// cache), one thread. Contenders run in interleaved rounds.
void floor_table(const cv::Mat& photo, int rounds) {
  const int m = 17;
  std::printf(
      "Full map against the memory floor (read the picture's doubles, write the fx and fy float planes; "
      "fastest of: vectorised loop%s, memcpy, read + memset), m = %d, reflect border, 1 thread, %d interleaved "
      "rounds\n",
      BENCH_X86 && hf::detail::has_avx2() ? ", non-temporal AVX2 loop" : "", m, rounds);
  std::printf(
      "| picture | map mean / worst [ms] | floor mean / worst [ms] (fastest way) | map / floor (mean) | "
      "map / floor (worst) | loop / NT loop / memcpy / read+memset, mean [ms] |\n|---|---|---|---|---|---|\n");
  for (const int side : {1024, 2048, 4096}) {
    cv::Mat resized;
    cv::resize(photo, resized, cv::Size(side, side), 0, 0, cv::INTER_CUBIC);
    const hf::GrayImage gray = hf::to_gray(resized);
    const std::size_t n = gray.pixels().size();
    const double* in = gray.pixels().data();
    std::vector<float> fx(n);
    std::vector<float> fy(n);
    hf::ForceMap map;
    std::vector<std::function<void()>> contenders{
        [&] {
          hf::prewitt_force_map(gray, m, hf::Border::reflect, map);
          sink = map.fx[n / 2];
        },
        [&] {
          floor_loop(in, n, fx.data(), fy.data());
          sink = fx[n / 2];
        },
        [&] {
          floor_memcpy(in, n, fx.data(), fy.data());
          sink = fx[n / 2];
        },
        [&] {
          floor_read_memset(in, n, fx.data(), fy.data());
          sink = fx[n / 2];
        },
    };
#if BENCH_X86
    const bool stream = hf::detail::has_avx2();
    if (stream)
      contenders.push_back([&] {
        floor_stream(in, n, fx.data(), fy.data());
        sink = fx[n / 2];
      });
#else
    const bool stream = false;
#endif
    const std::vector<Stats> r = time_rounds(rounds, contenders);
    static const char* const names[] = {"map", "loop", "memcpy", "read+memset", "NT loop"};
    std::size_t best = 1;
    for (std::size_t i = 2; i < r.size(); ++i)
      if (r[i].mean < r[best].mean) best = i;
    const Stats& map_t = r[0];
    const Stats& floor_t = r[best];
    char nt[32] = "-";
    if (stream) std::snprintf(nt, sizeof nt, "%.2f", r[4].mean / 1e6);
    std::printf(
        "| %d x %d (%.0f Mpx, %.0f MB in + %.0f MB out) | %.2f / %.2f | %.2f / %.2f (%s) | %.2fx | %.2fx | "
        "%.2f / %s / %.2f / %.2f |\n",
        side, side, n / 1048576.0, n * 8.0 / 1048576.0, n * 8.0 / 1048576.0, map_t.mean / 1e6, map_t.worst / 1e6,
        floor_t.mean / 1e6, floor_t.worst / 1e6, names[best], map_t.mean / floor_t.mean, map_t.worst / floor_t.worst,
        r[1].mean / 1e6, nt, r[2].mean / 1e6, r[3].mean / 1e6);
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png";
  int queries = 200000;
  int map_runs = 30;
  bool floor_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--queries" && i + 1 < argc)
      queries = std::atoi(argv[++i]);
    else if (a == "--maps" && i + 1 < argc)
      map_runs = std::atoi(argv[++i]);
    else if (a == "--floor-only")
      floor_only = true;
    else
      path = a;
  }
  // The paper's picture size: 1000 x 1504 px.
  cv::Mat photo;
  cv::resize(hf::load_image(path), photo, cv::Size(1504, 1000), 0, 0, cv::INTER_CUBIC);
  if (floor_only) {
    floor_table(hf::load_image(path), map_runs);
    return 0;
  }
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
  std::printf("\n");
  floor_table(hf::load_image(path), map_runs);
  return 0;
}
