// bench_vibration: the cost of the vibration path and its latency in wall
// time. Prints Markdown tables.
//
//   bench_vibration [--hatt FILE] [--seconds S]
//
// 1. Render cost of one audio block: a HaTT model (10 kHz, the toolkit-shaped
//    test file or --hatt FILE) on the audio side at 10 and 48 kHz, against a
//    sine (ToneSource) rendered in the same run; as a share of the block's
//    real-time length.
// 2. The tap's cost in the servo tick, through the tick-budget harness
//    (servo/tick_budget.hpp): contact(plane, HaTT texture) with and without
//    tap(..., ring), ratio of the means.
// 3. Latency, wall clock: a 1 kHz servo thread (absolute deadlines) toggles
//    the contact every 50 ms through tap(); the audio thread
//    (VibrationStream, NullSink, paced on the monotonic clock) renders
//    blocks; a contact onset's latency is from the tick's wake to the first
//    frame that carries it, at the time that frame is due (block start +
//    index / rate). A sound card adds its buffer (period x periods frames)
//    on top: docs/vibration.md.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "hapticfield/core.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/pacer.hpp"
#include "hapticfield/servo/tick_budget.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/vibration.hpp"
#include "tick_cost.hpp"

using namespace hapticfield;
using namespace hapticfield::vibration;

namespace {

struct ForceFollower {
  [[nodiscard]] double next(const ContactState& c) noexcept { return c.touching ? c.normal_force : 0.0; }
};

/// A field that gives no force: the contact is in the probe's normal_force.
struct Nothing {
  [[nodiscard]] glm::dvec3 force(const Probe&) const noexcept { return glm::dvec3{0.0}; }
};

RendererConfig config(double rate, double delay) {
  RendererConfig c;
  c.playout.sample_rate = rate;
  c.playout.delay = delay;
  c.limit = 1e6;
  return c;
}

/// Mean and worst render time of one block [ns], with the ring fed one
/// contact sample per millisecond of audio.
template <class R>
bench::Cost block_cost(ContactRing<>& ring, R& r, std::size_t block, long blocks) {
  std::vector<float> buf(block);
  double audio_time = 0.0, next_tick = 0.0;
  const double dt = static_cast<double>(block) / r.sample_rate();
  return bench::measure(blocks, [&] {
    audio_time += dt;
    while (next_tick <= audio_time) {
      ring.try_push({next_tick, 0.1, 1.5, 0});
      next_tick += 1e-3;
    }
    r.render(buf);
  });
}

/// Wraps a renderer: notes when each contact onset first reaches the output.
template <class R>
struct OnsetProbe {
  R* renderer;
  std::vector<std::int64_t>* onsets;
  std::atomic<std::size_t>* count;
  bool on{false};
  SteadyClock clock;
  void render(std::span<float> out) noexcept {
    const std::int64_t start = clock.now();
    renderer->render(out);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const bool now_on = out[i] > 0.5f;
      if (now_on && !on) {
        const std::size_t k = count->load(std::memory_order_relaxed);
        if (k < onsets->size()) {
          (*onsets)[k] = start + static_cast<std::int64_t>(1e9 * static_cast<double>(i) / renderer->sample_rate());
          count->store(k + 1, std::memory_order_release);
        }
      }
      on = now_on;
    }
  }
  [[nodiscard]] int channels() const noexcept { return renderer->channels(); }
  [[nodiscard]] double sample_rate() const noexcept { return renderer->sample_rate(); }
};

void latency_row(double rate, std::size_t block, double seconds) {
  const double delay = static_cast<double>(block) / rate + 0.002;
  ContactRing<> ring;
  auto r = renderer(ring, config(rate, delay), route(ForceFollower{}));
  const auto cycles = static_cast<std::size_t>(seconds * 10.0);  // one onset per 100 ms
  std::vector<std::int64_t> ticks(cycles, 0), outs(cycles, 0);
  std::atomic<std::size_t> out_count{0};
  OnsetProbe<decltype(r)> probe{&r, &outs, &out_count, false, SteadyClock{}};
  NullSink sink;
  VibrationStream stream(probe, sink, block);
  std::atomic<bool> done{false};
  std::thread servo([&] {
    SteadyClock clock;
    Pacer pacer(1'000'000);
    auto field = tap(Nothing{}, ring);
    pacer.start(clock.now());
    const std::int64_t t0 = clock.now();
    for (std::size_t tick = 0; tick < cycles * 100 + 200; ++tick) {
      const std::int64_t wake = pacer.wait(clock);
      Probe p;
      p.time = static_cast<double>(wake - t0) * 1e-9;
      const std::size_t phase = tick % 100;
      p.normal_force = phase < 50 ? 1.0 : 0.0;
      if (phase == 0 && tick / 100 < cycles) ticks[tick / 100] = wake;
      (void)field.force(p);
      pacer.finish(clock.now());
    }
    done.store(true);
  });
  stream.start();
  servo.join();
  stream.stop();
  std::vector<double> lat;
  const std::size_t n = std::min(out_count.load(), cycles);
  // the first onset may be missed while the playout seats itself: pair onsets by time
  std::size_t j = 0;
  for (std::size_t i = 0; i < cycles && j < n; ++i) {
    while (j < n && outs[j] < ticks[i])
      ++j;
    if (j < n && outs[j] - ticks[i] < 50'000'000) lat.push_back(static_cast<double>(outs[j] - ticks[i]) * 1e-6);
  }
  std::sort(lat.begin(), lat.end());
  double mean = 0.0;
  for (double v : lat)
    mean += v / static_cast<double>(lat.size());
  if (lat.empty()) {
    std::printf("| %.0f | %zu | %.2f | no onsets seen | | | | |\n", rate, block, delay * 1e3);
    return;
  }
  std::printf("| %.0f | %zu | %.2f | %zu | %.2f | %.2f | %.2f | %.2f |\n", rate, block, delay * 1e3, lat.size(), mean,
              lat[lat.size() / 2], lat.back(), mean / (delay * 1e3));
}

}  // namespace

int main(int argc, char** argv) {
  std::string hatt_file = std::string(HAPTICFIELD_SOURCE_DIR) + "/tests/data/hatt/Models_Toolkit 10kHz AR.xml";
  double seconds = 5.0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--hatt") == 0 && i + 1 < argc)
      hatt_file = argv[++i];
    else if (std::strcmp(argv[i], "--seconds") == 0 && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_vibration [--hatt FILE] [--seconds S]\n");
      return 2;
    }
  }
  if (!(seconds >= 1.0 && seconds <= 600.0)) {
    std::fprintf(stderr, "bench_vibration: --seconds must be within [1, 600]\n");
    return 2;
  }
  const texture::HattModelSet set = texture::load_hatt_model_set(hatt_file);

  // ---- 1. render cost
  std::printf("## Render cost of one audio block (HaTT model '%s', order %zu, %.0f Hz)\n\n", set.name.c_str(),
              set.ar_order, set.sample_rate);
  std::printf(
      "| audio rate [Hz] | block [frames] | source | mean [us] | p99 [us] | worst [us] | mean / block length |"
      " mean / tone |\n|---:|---:|---|---:|---:|---:|---:|---:|\n");
  for (const double rate : {10000.0, 48000.0}) {
    const std::size_t block = 256;
    const long blocks = static_cast<long>(20.0 * rate / static_cast<double>(block));  // 20 s of audio
    ContactRing<> ring_t, ring_h;
    auto tone = renderer(ring_t, config(rate, 0.01), route(ToneSource()));
    auto hatt = renderer(ring_h, config(rate, 0.01), route(HattSource<64>(set, {})));
    const bench::Cost ct = block_cost(ring_t, tone, block, blocks);
    const bench::Cost ch = block_cost(ring_h, hatt, block, blocks);
    const double length_us = 1e6 * static_cast<double>(block) / rate;
    for (const auto& [name, c] : {std::pair{"tone", ct}, std::pair{"HaTT", ch}})
      std::printf("| %.0f | %zu | %s | %.2f | %.2f | %.1f | %.4f | %.2f |\n", rate, block, name, c.mean_ns * 1e-3,
                  c.p99_ns * 1e-3, c.worst_ns * 1e-3, c.mean_ns * 1e-3 / length_us, c.mean_ns / ct.mean_ns);
  }

  // ---- 2. the tap in the servo tick (tick-budget harness)
  ContactRing<> ring;
  const PlaneConstraint plane({.stiffness = 1500.0});
  auto bare = contact(plane, texture::HattTexture<64>(set, {}));
  auto tapped = tap(contact(plane, texture::HattTexture<64>(set, {})), ring);
  offline::TickBudgetConfig tb;
  tb.ticks = 200000;
  const auto rb = offline::measure_tick_budget(bare, tb);
  std::thread drain([&] {  // keeps the ring from filling, as the audio side would
    for (int i = 0; i < 1000; ++i) {
      while (ring.try_pop()) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  const auto rt = offline::measure_tick_budget(tapped, tb);
  drain.join();
  std::printf("\n## The tap in the servo tick (tick-budget harness, %llu ticks)\n\n",
              static_cast<unsigned long long>(tb.ticks));
  std::printf(
      "| field | mean [ns] | p99 [ns] | worst [ns] | fits 1 kHz | fits 10 kHz | mean / untapped |\n"
      "|---|---:|---:|---:|---|---|---:|\n");
  for (const auto& [name, r] :
       {std::pair{"contact(plane, HaTT)", rb}, std::pair{"tap(contact(plane, HaTT), ring)", rt}})
    std::printf("| %s | %.0f | %.0f | %.0f | %s | %s | %.3f |\n", name, r.mean_ns, r.p99_ns, r.worst_ns,
                r.fits_1khz ? "yes" : "no", r.fits_10khz ? "yes" : "no", r.mean_ns / rb.mean_ns);

  // ---- 3. latency, wall clock
  std::printf("\n## Latency, contact onset in a tick -> first frame out of the renderer (wall clock, %.0f s each)\n\n",
              seconds);
  std::printf(
      "| audio rate [Hz] | block [frames] | playout delay [ms] | onsets | mean [ms] | p50 [ms] | worst [ms] |"
      " mean / delay |\n|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::size_t block : {std::size_t{64}, std::size_t{256}, std::size_t{1024}})
    latency_row(48000.0, block, seconds);
  latency_row(10000.0, 64, seconds);
  std::printf("\n(a sound card adds its buffer, period x periods frames, after the renderer)\n");
  return 0;
}
