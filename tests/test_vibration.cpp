// Tests of the vibration room: the SPSC ring, tap(field, ring), the playout
// (drain, delay, interpolate, silence), the sources (tone, signal, texture,
// HaTT at its own rate against the model's closed-form spectrum), the
// renderer's routing, latency in samples through a manual pull, and the
// sinks: null, WAV (libsndfile), ALSA's null and file plugins. Nothing here
// depends on the machine's speed: audio is pulled by hand or counted.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/texture/psd.hpp"
#include "hapticfield/vibration.hpp"
#ifdef HAPTICFIELD_TEST_ALSA
#include "hapticfield/vibration/alsa_sink.hpp"
#endif
#ifdef HAPTICFIELD_TEST_WAV
#include "hapticfield/vibration/wav_sink.hpp"
#endif

using namespace hapticfield;
using namespace hapticfield::vibration;
using Catch::Matchers::WithinAbs;

namespace {

const std::filesystem::path data_dir = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "tests" / "data" / "hatt";
/// The real toolkit files live beside the project, never in it.
const std::filesystem::path real_hatt_dir =
    std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data" / "hatt" / "10000Hz";
const std::filesystem::path tmp_dir = HAPTICFIELD_TEST_TMP;

/// Outputs the interpolated normal force: makes the playout visible.
struct ForceFollower {
  [[nodiscard]] double next(const ContactState& c) noexcept { return c.touching ? c.normal_force : 0.0; }
};

/// A constraint-free field that pushes back along +z with 2 N.
struct Push {
  [[nodiscard]] glm::dvec3 force(const Probe&) const noexcept { return {0.0, 0.0, 2.0}; }
};

ContactSample sample(double t, double force, double speed = 0.05, std::uint32_t material = 0) {
  return {t, speed, force, material};
}

RendererConfig config(double rate, double delay, int channels = 1) {
  RendererConfig c;
  c.playout.sample_rate = rate;
  c.playout.delay = delay;
  c.channels = channels;
  c.limit = 100.0;  // ForceFollower plays newtons: do not clip them
  return c;
}

/// Servo at 1 kHz and audio blocks of `block` frames on one simulated
/// timeline: each block is rendered when its first frame is due, after the
/// ticks up to that time were pushed. force_at(tick) gives each tick's |Fc|.
template <class Renderer, class ForceAt>
std::vector<float> co_simulate(ContactRing<>& ring, Renderer& r, double rate, std::size_t block, double seconds,
                               ForceAt force_at) {
  std::vector<float> out;
  std::vector<float> buf(block * static_cast<std::size_t>(r.channels()));
  long tick = 0;
  const auto blocks = static_cast<long>(seconds * rate / static_cast<double>(block));
  for (long b = 0; b < blocks; ++b) {
    const double now = static_cast<double>(b) * static_cast<double>(block) / rate;
    while (static_cast<double>(tick) * 1e-3 <= now + 1e-12) {
      ring.try_push(sample(static_cast<double>(tick) * 1e-3, force_at(tick)));
      ++tick;
    }
    r.render(buf);
    out.insert(out.end(), buf.begin(), buf.end());
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

// --------------------------------------------------------------------- ring

TEST_CASE("SpscRing: order, full ring refused and counted, empty ring gives nothing") {
  rt::SpscRing<int, 4> ring;
  CHECK_FALSE(ring.try_pop().has_value());
  for (int i = 0; i < 4; ++i)
    CHECK(ring.try_push(i));
  CHECK_FALSE(ring.try_push(99));
  CHECK(ring.rejected() == 1);
  CHECK(ring.size() == 4);
  for (int i = 0; i < 4; ++i)
    CHECK(ring.try_pop().value() == i);
  CHECK_FALSE(ring.try_pop().has_value());
}

TEST_CASE("SpscRing: one producer and one consumer thread, every value once and in order") {
  static rt::SpscRing<std::uint64_t, 64> ring;
  constexpr std::uint64_t n = 200000;
  std::thread producer([] {
    for (std::uint64_t i = 0; i < n;)
      if (ring.try_push(i)) ++i;
  });
  std::uint64_t expected = 0;
  bool in_order = true;
  while (expected < n)
    if (const auto v = ring.try_pop()) in_order = in_order && (*v == expected++);
  producer.join();
  CHECK(in_order);
}

// ---------------------------------------------------------------------- tap

TEST_CASE("tap: the force is unchanged and each tick pushes its contact (|Fc|, tangential speed, material)") {
  ContactRing<> ring;
  const PlaneConstraint plane({.stiffness = 1000.0});
  auto field = tap(contact(plane), ring, {.material = 7});
  auto bare = contact(plane);
  Probe p;
  p.position = {0.0, 0.0, -0.002};
  p.velocity = {0.03, 0.04, -0.5};  // tangential speed 0.05 m/s; the normal part is not sliding
  p.time = 0.125;
  CHECK(field.force(p) == bare.force(p));
  const auto s = ring.try_pop();
  REQUIRE(s.has_value());
  CHECK(s->time == 0.125);
  CHECK_THAT(s->normal_force, WithinAbs(2.0, 1e-12));
  CHECK_THAT(s->speed, WithinAbs(0.05, 1e-12));
  CHECK(s->material == 7);
  p.position.z = 0.01;  // off the surface: no contact
  CHECK(field.force(p) == glm::dvec3{0.0});
  CHECK(ring.try_pop()->normal_force == 0.0);
}

TEST_CASE("tap: a field that reports no contact sends |F| and the full speed") {
  ContactRing<> ring;
  auto field = tap(Push{}, ring);
  Probe p;
  p.velocity = {0.0, 0.0, 0.1};
  (void)field.force(p);
  const auto s = ring.try_pop();
  CHECK(s->normal_force == 2.0);
  CHECK(s->speed == 0.1);
}

TEST_CASE("tap: a full ring drops and counts, never blocks, and a tick allocates nothing") {
  ContactRing<8> ring;
  auto field = tap(Push{}, ring);
  Probe p;
  long allocations = test::count_allocations([&] {
    for (int i = 0; i < 20; ++i)
      (void)field.force(p);
  });
  CHECK(field.dropped() == 12);
  if (test::allocations_counted) CHECK(allocations == 0);
}

// ------------------------------------------------------------------ playout

TEST_CASE("playout: the contact is played `delay` behind the newest tick, linearly interpolated") {
  ContactRing<> ring;
  const double rate = 10000.0, delay = 0.005;
  auto r = renderer(ring, config(rate, delay), route(ForceFollower{}));
  // a ramp of |Fc|: 0.001 N per ms, so the played force tells the played time
  const auto out = co_simulate(ring, r, rate, 10, 0.2, [](long tick) { return 0.001 * static_cast<double>(tick); });
  // frame j (time j / rate) plays contact time j / rate - delay: force = that time in seconds
  for (std::size_t j = 1000; j < out.size(); j += 37)
    CHECK_THAT(out[j], WithinAbs(static_cast<double>(j) / rate - delay, 2e-6));
  CHECK(r.statistics().resyncs == 0);
  CHECK(r.statistics().held == 0);
}

TEST_CASE("playout: any frame count per call plays the same contact, within the servo's half tick") {
  const double rate = 48000.0, delay = 0.012;
  std::vector<std::vector<float>> outs;
  for (std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{48}, std::size_t{333}}) {
    ContactRing<> ring;
    auto r = renderer(ring, config(rate, delay), route(ForceFollower{}));
    outs.push_back(co_simulate(ring, r, rate, block, 0.3,
                               [](long tick) { return 1.0 + std::sin(0.01 * static_cast<double>(tick)); }));
  }
  // The newest tick at a block's start lags the block by 0 to 1 ms depending
  // on the block size, so the play time settles within half a tick of the
  // same place: |d force / dt| <= 10 N/s here, so 0.5 ms is 5e-3 N.
  for (const auto& o : outs)
    for (std::size_t j = 0; j < 14000; j += 101)
      CHECK_THAT(o[j], WithinAbs(outs[0][j], 5e-3));
}

TEST_CASE("playout: when the servo side stops, the last state is held for `hold`, then silence") {
  ContactRing<> ring;
  RendererConfig c = config(10000.0, 0.003);
  c.playout.hold = 0.01;
  auto r = renderer(ring, c, route(ForceFollower{}));
  const auto out = co_simulate(ring, r, 10000.0, 10, 0.2, [](long tick) { return tick < 100 ? 1.0 : 1.0; });
  CHECK(out.back() == 1.0f);
  std::vector<float> more(10 * 50);  // 50 ms with no new tick
  r.render(more);
  CHECK(more[0] == 1.0f);
  CHECK(more.back() == 0.0f);
  CHECK(std::count(more.begin(), more.end(), 1.0f) < 10 * (3 + 10) + 20);  // delay + hold, then nothing
  CHECK(r.statistics().held > 0);
}

TEST_CASE("playout: a loop that restarts (time goes back) is played from its new start") {
  ContactRing<> ring;
  auto r = renderer(ring, config(10000.0, 0.003), route(ForceFollower{}));
  (void)co_simulate(ring, r, 10000.0, 10, 0.5, [](long) { return 1.0; });
  std::vector<float> buf(10);
  for (int i = 0; i < 100; ++i) {  // the new run: time from 0 again, force 2
    ring.try_push(sample(i * 1e-3, 2.0));
    r.render(buf);
  }
  CHECK(buf.back() == 2.0f);
  CHECK(r.statistics().resyncs >= 1);
}

TEST_CASE("latency in samples: a contact step at a tick reaches the output `delay` later, within one tick") {
  for (const double rate : {10000.0, 48000.0}) {
    for (const std::size_t block : {std::size_t{16}, std::size_t{64}, std::size_t{256}}) {
      const double delay = static_cast<double>(block) / rate + 0.002;
      ContactRing<> ring;
      auto r = renderer(ring, config(rate, delay), route(ForceFollower{}));
      const long step_tick = 300;
      const auto out = co_simulate(ring, r, rate, block, 0.5, [](long tick) { return tick >= step_tick ? 1.0 : 0.0; });
      const auto first = std::find_if(out.begin(), out.end(), [](float v) { return v > 0.0f; }) - out.begin();
      const auto half = std::find_if(out.begin(), out.end(), [](float v) { return v >= 0.5f; }) - out.begin();
      const double step_frame = static_cast<double>(step_tick) * 1e-3 * rate;
      const double latency_half = (static_cast<double>(half) - step_frame) / rate;
      std::cout << "latency: " << rate << " Hz, block " << block << ", delay " << delay * 1e3
                << " ms: first sample out after " << (static_cast<double>(first) - step_frame) / rate * 1e3
                << " ms, half the step after " << latency_half * 1e3 << " ms (" << half - static_cast<long>(step_frame)
                << " samples)\n";
      CHECK(latency_half >= delay - 0.0015);
      CHECK(latency_half <= delay + 0.0005);
    }
  }
}

// ------------------------------------------------------------------ sources

TEST_CASE("sources: a tone follows the speed; routes play only their material, into their channel") {
  ContactRing<> ring;
  ToneConfig low{.frequency = 100.0, .amplitude = 0.5, .full_speed = 0.1};
  ToneConfig high{.frequency = 300.0, .amplitude = 0.5, .full_speed = 0.1};
  auto r = renderer(ring, config(8000.0, 0.004, 2), route(ToneSource(low), 1, 0), route(ToneSource(high), 2, 1));
  std::vector<float> buf(2 * 8);
  for (int i = 0; i < 400; ++i) {
    ring.try_push({i * 1e-3, 0.05, 1.0, 1});  // material 1 at half the full speed
    r.render(buf);
  }
  double peak0 = 0.0, peak1 = 0.0;
  for (int i = 0; i < 400; ++i) {
    ring.try_push({(400 + i) * 1e-3, 0.05, 1.0, 1});
    r.render(buf);
    for (std::size_t k = 0; k < 8; ++k)
      peak0 = std::max(peak0, std::fabs(double(buf[2 * k]))),
      peak1 = std::max(peak1, std::fabs(double(buf[2 * k + 1])));
  }
  CHECK_THAT(peak0, WithinAbs(0.25, 0.002));  // 0.5 x 0.05 / 0.1
  CHECK(peak1 == 0.0);
}

TEST_CASE("sources: a recorded signal at the recorded speed plays back sample for sample") {
  std::vector<float> signal(100);
  for (std::size_t i = 0; i < signal.size(); ++i)
    signal[i] = static_cast<float>(std::sin(0.3 * static_cast<double>(i)));
  SignalSource s(signal, {.sample_rate = 8000.0, .recorded_speed = 0.1});
  s.prepare(8000.0);
  const ContactState c{0.1, 1.0, 0, true};
  for (std::size_t i = 1; i < 250; ++i)
    CHECK_THAT(s.next(c), WithinAbs(signal[i % signal.size()], 1e-6));
  SignalSource twice(signal, {.sample_rate = 8000.0, .recorded_speed = 0.1});
  twice.prepare(8000.0);
  const ContactState fast{0.2, 1.0, 0, true};
  for (std::size_t i = 1; i < 40; ++i)
    CHECK_THAT(twice.next(fast), WithinAbs(signal[(2 * i) % signal.size()], 1e-6));
  CHECK_THROWS_AS(SignalSource({1.0f}, {}), std::invalid_argument);
}

TEST_CASE("sources: any texture field strokes at the contact's speed, one probe step per frame") {
  struct Ridges {  // force along z = sin(2 pi x / 1 mm)
    [[nodiscard]] glm::dvec3 force(const Probe& p) const noexcept {
      return {0.0, 0.0, std::sin(2.0 * std::numbers::pi * p.position.x / 1e-3)};
    }
  };
  TextureSource<Ridges> s(Ridges{});
  s.prepare(10000.0);
  const ContactState c{0.1, 1.0, 0, true};  // 0.1 m/s over 1 mm ridges: 100 Hz
  for (int i = 1; i <= 300; ++i)
    CHECK_THAT(s.next(c), WithinAbs(std::sin(2.0 * std::numbers::pi * 100.0 * i / 10000.0), 1e-9));
  CHECK(s.next({0.1, 0.0, 0, false}) == 0.0);
}

// ------------------------------------------------- HaTT at its own rate: spectrum

namespace {
/// Median |dB| error of the audio path's Welch PSD against the model's
/// closed-form PSD (its own AR coefficients, <ARcoeff> in the file), in
/// (0, 4 kHz], with the contact held at one model's (speed, force).
double hatt_spectrum_error(const std::filesystem::path& file, double audio_rate, std::size_t which = 0) {
  const texture::HattModelSet set = texture::load_hatt_model_set(file);
  // a model with motion and force, inside the hull
  std::size_t m = which;
  for (std::size_t i = which; i < set.models.size(); ++i)
    if (set.speeds[i] > 0.0 && set.forces[i] > 0.0 && !set.models[i].ar_coeff.empty()) {
      m = i;
      break;
    }
  const texture::HattModel& model = set.models[m];
  std::vector<double> a = model.ar_coeff;
  if (a.size() == set.ar_order) a.insert(a.begin(), 1.0);
  const double speed = set.speeds[m] / set.speed_to_file;  // [m/s]
  const double force = set.forces[m];

  ContactRing<> ring;
  const double gain = 0.01;
  RendererConfig c = config(audio_rate, 0.004);
  c.limit = 1e9;  // measure, do not clip
  auto r = renderer(ring, c, route(HattSource<64>(set, {.gain = gain, .seed = 5})));
  const std::size_t block = 64;
  const std::size_t frames = std::size_t{1} << 19;
  std::vector<float> buf(block);
  std::vector<double> y;
  y.reserve(frames);
  long tick = 0;
  for (std::size_t b = 0; y.size() < frames + 4096; ++b) {
    const double now = static_cast<double>(b * block) / audio_rate;
    while (static_cast<double>(tick) * 1e-3 <= now) {
      ring.try_push({static_cast<double>(tick) * 1e-3, speed, force, 0});
      ++tick;
    }
    r.render(buf);
    if (b * block >= 4096)  // skip the onset
      for (float v : buf)
        y.push_back(static_cast<double>(v) / (gain * set.acceleration_to_si));
  }
  const std::size_t segment = audio_rate > 20000.0 ? 4096 : 1024;
  const offline::Spectrum psd = offline::welch_psd(y, audio_rate, segment);
  std::vector<double> err;
  for (std::size_t k = 1; k < psd.frequency.size() && psd.frequency[k] <= 4000.0; ++k) {
    const double model_psd = offline::arma_psd(a, {}, model.variance, 1.0, psd.frequency[k], set.sample_rate);
    err.push_back(std::fabs(10.0 * std::log10(psd.density[k] / model_psd)));
  }
  return median(err);
}
}  // namespace

TEST_CASE("HaTT on the audio path: Welch PSD against the model's closed-form PSD, 10 kHz toolkit-shaped file") {
  const double e10 = hatt_spectrum_error(data_dir / "Models_Toolkit 10kHz AR.xml", 10000.0);
  const double e48 = hatt_spectrum_error(data_dir / "Models_Toolkit 10kHz AR.xml", 48000.0);
  std::cout << "HaTT spectrum, toolkit-shaped 10 kHz file: median |dB error| up to 4 kHz = " << e10
            << " (audio at 10 kHz), " << e48 << " (audio at 48 kHz)\n";
  CHECK(e10 <= 1.5);
  CHECK(e48 <= 1.5);
}

TEST_CASE("HaTT on the audio path: the real toolkit models (skipped without ../shared/data/hatt)") {
  if (!std::filesystem::is_directory(real_hatt_dir)) {
    std::cout << "SKIPPED: no real HaTT models at " << real_hatt_dir << "\n";
    return;
  }
  for (const auto& file : texture::hatt_model_files(real_hatt_dir)) {
    const double e10 = hatt_spectrum_error(file, 10000.0, 10);
    const double e48 = hatt_spectrum_error(file, 48000.0, 10);
    std::cout << "HaTT spectrum, " << file.stem().string() << ": median |dB error| up to 4 kHz = " << e10
              << " (10 kHz audio), " << e48 << " (48 kHz audio)\n";
    CHECK(e10 <= 1.5);
    CHECK(e48 <= 1.5);
  }
}

TEST_CASE("HaTT source: silent off contact and below the velocity threshold; render allocates nothing") {
  const texture::HattModelSet set = texture::load_hatt_model_set(data_dir / "Models_Toolkit 10kHz AR.xml");
  ContactRing<> ring;
  auto r = renderer(ring, config(10000.0, 0.004), route(HattSource<64>(set, {})));
  std::vector<float> buf(10);
  long allocations = test::count_allocations([&] {
    for (int i = 0; i < 200; ++i) {
      ring.try_push({i * 1e-3, 0.0, 1.0, 0});  // pressing, not sliding
      r.render(buf);
    }
  });
  CHECK(std::all_of(buf.begin(), buf.end(), [](float v) { return v == 0.0f; }));
  if (test::allocations_counted) CHECK(allocations == 0);
}

TEST_CASE("HaTT source: a model far faster than the audio runs a bounded number of steps per frame") {
  texture::HattModelSet set = texture::load_hatt_model_set(data_dir / "Models_Toolkit 10kHz AR.xml");
  const ContactState sliding{0.1, 1.0, 0, true};
  // a file's model at the audio rates used: every model step runs (10 kHz at 8 kHz: 1.25 a frame)
  HattSource<64> own(set, {});
  own.prepare(8000.0);
  for (int i = 0; i < 8000; ++i)
    (void)own.next(sliding);
  CHECK(own.model_steps() == 10000);
  // models built in code at rates no file may declare: at most max_hatt_steps_per_sample a frame
  for (const double rate : {1e5 * 17.0 / 8.0, 1e7, 1e9, 1e12, 1e300}) {
    CAPTURE(rate);
    set.sample_rate = rate;
    HattSource<64> fast(set, {});
    fast.prepare(8000.0);
    double sum = 0.0;
    for (int i = 0; i < 8000; ++i)
      sum += fast.next(sliding);
    CHECK(fast.model_steps() == 8000u * static_cast<unsigned>(max_hatt_steps_per_sample));
    CHECK(std::isfinite(sum));
  }
}

TEST_CASE("the whole chain: tap(contact(plane, ...)) on the servo side, HaTT on the audio side") {
  const texture::HattModelSet set = texture::load_hatt_model_set(data_dir / "Models_Toolkit 10kHz AR.xml");
  ContactRing<> ring;
  auto field = tap(contact(PlaneConstraint({.stiffness = 1000.0})), ring);
  auto r = renderer(ring, config(10000.0, 0.004), route(HattSource<64>(set, {})));
  std::vector<float> buf(10);
  double energy = 0.0;
  for (int i = 0; i < 500; ++i) {
    Probe p;
    p.time = i * 1e-3;
    p.position = {0.1 * p.time, 0.0, -0.001};
    p.velocity = {0.1, 0.0, 0.0};
    (void)field.force(p);
    r.render(buf);
    for (float v : buf)
      energy += double(v) * double(v);
  }
  CHECK(energy > 0.0);
  CHECK(field.dropped() == 0);
  CHECK(r.statistics().received == 500);
}

// ------------------------------------------------------------------- sinks

TEST_CASE("stream: pull() renders one block into the sink; the thread stops cleanly") {
  ContactRing<> ring;
  auto r = renderer(ring, config(8000.0, 0.01), route(ForceFollower{}));
  NullSink sink;
  VibrationStream stream(r, sink, 80);
  CHECK(stream.pull() == 80);
  CHECK(sink.frames() == 80);
  stream.start();
  while (stream.blocks() < 4)
    std::this_thread::yield();
  stream.stop();
  CHECK(sink.frames() == 80 * stream.blocks());
  CHECK(r.statistics().frames == sink.frames());
}

#ifdef HAPTICFIELD_TEST_WAV
TEST_CASE("WAV sink: what was rendered is what the file holds (float exact, 16-bit within one step)") {
  std::filesystem::create_directories(tmp_dir);
  for (const WavFormat format : {WavFormat::float32, WavFormat::pcm16}) {
    const auto path = tmp_dir / (format == WavFormat::float32 ? "vibration_f32.wav" : "vibration_s16.wav");
    ContactRing<> ring;
    auto r = renderer(ring, config(8000.0, 0.004, 2), route(ToneSource({.frequency = 200.0}), any_material, 0),
                      route(ForceFollower{}, any_material, 1, 0.25));
    std::vector<float> rendered;
    {
      WavSink sink(path, {.sample_rate = 8000.0, .channels = 2, .format = format});
      std::vector<float> buf(2 * 8);
      for (int i = 0; i < 300; ++i) {
        ring.try_push({i * 1e-3, 0.1, 1.0 + 0.001 * i, 0});
        r.render(buf);
        rendered.insert(rendered.end(), buf.begin(), buf.end());
        CHECK(sink.write(buf) == 8);
      }
    }
    const WavData d = read_wav(path);
    CHECK(d.sample_rate == 8000.0);
    CHECK(d.channels == 2);
    REQUIRE(d.samples.size() == rendered.size());
    const double tolerance = format == WavFormat::float32 ? 0.0 : 1.0 / 32767.0;
    double worst = 0.0;
    for (std::size_t i = 0; i < rendered.size(); ++i)
      worst = std::max(worst, std::fabs(double(d.samples[i]) - double(rendered[i])));
    CHECK(worst <= tolerance);
  }
  CHECK_THROWS_AS(read_wav(tmp_dir / "no such file.wav"), FileError);
}

TEST_CASE("WAV: a recorded vibration read back drives a SignalSource") {
  std::filesystem::create_directories(tmp_dir);
  const auto path = tmp_dir / "recorded.wav";
  std::vector<float> signal(400);
  for (std::size_t i = 0; i < signal.size(); ++i)
    signal[i] = static_cast<float>(0.5 * std::sin(0.05 * static_cast<double>(i)));
  {
    WavSink sink(path, {.sample_rate = 8000.0});
    sink.write(signal);
  }
  const WavData d = read_wav(path);
  SignalSource s(d.samples, {.sample_rate = d.sample_rate, .recorded_speed = 0.05});
  s.prepare(8000.0);
  for (std::size_t i = 1; i < 100; ++i)
    CHECK_THAT(s.next({0.05, 1.0, 0, true}), WithinAbs(signal[i], 1e-7));
}
#endif

#ifdef HAPTICFIELD_TEST_ALSA
TEST_CASE("ALSA sink: the null plugin takes every frame of a stream") {
  ContactRing<> ring;
  auto r = renderer(ring, config(48000.0, 0.01), route(ToneSource()));
  AlsaSink sink({.device = "null", .sample_rate = 48000, .period_frames = 256, .periods = 2});
  VibrationStream stream(r, sink, 256);
  for (int i = 0; i < 20; ++i) {
    ring.try_push({i * 5e-3, 0.1, 1.0, 0});
    CHECK(stream.pull() == 256);
  }
  CHECK(sink.frames() == 20 * 256);
  CHECK(sink.errors() == 0);
  CHECK(sink.period_frames() > 0);
}

TEST_CASE("ALSA sink: the file plugin records exactly what was rendered (float and 16-bit)") {
  std::filesystem::create_directories(tmp_dir);
  for (const AlsaFormat format : {AlsaFormat::float32, AlsaFormat::s16}) {
    const auto raw = tmp_dir / (format == AlsaFormat::float32 ? "alsa_f32.raw" : "alsa_s16.raw");
    std::filesystem::remove(raw);
    ContactRing<> ring;
    auto r = renderer(ring, config(16000.0, 0.006), route(ToneSource({.frequency = 300.0, .amplitude = 0.8})));
    std::vector<float> rendered;
    {
      AlsaSink sink({.device = "file:'" + raw.string() + "',raw",
                     .sample_rate = 16000,
                     .format = format,
                     .period_frames = 128,
                     .periods = 4});
      std::vector<float> buf(128);
      for (int i = 0; i < 50; ++i) {
        for (int k = 0; k < 8; ++k)
          ring.try_push({(i * 8 + k) * 1e-3, 0.1, 1.0, 0});
        r.render(buf);
        rendered.insert(rendered.end(), buf.begin(), buf.end());
        CHECK(sink.write(buf) == 128);
      }
    }  // drained and closed
    std::ifstream in(raw, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (format == AlsaFormat::float32) {
      REQUIRE(bytes.size() == rendered.size() * sizeof(float));
      std::vector<float> got(rendered.size());
      std::memcpy(got.data(), bytes.data(), bytes.size());
      CHECK(got == rendered);
    } else {
      REQUIRE(bytes.size() == rendered.size() * sizeof(std::int16_t));
      std::vector<std::int16_t> got(rendered.size());
      std::memcpy(got.data(), bytes.data(), bytes.size());
      int worst = 0;
      for (std::size_t i = 0; i < got.size(); ++i)
        worst = std::max(worst, std::abs(got[i] - static_cast<int>(std::lrint(rendered[i] * 32767.0f))));
      CHECK(worst == 0);
    }
  }
}

TEST_CASE("ALSA sink: a device that does not exist, or a rate outside the range, is a clear error") {
  CHECK_THROWS_AS(AlsaSink({.device = "no_such_pcm_device"}), AudioError);
  CHECK_THROWS_AS(AlsaSink({.device = "null", .sample_rate = 4000}), std::invalid_argument);
  try {
    AlsaSink sink({.device = "no_such_pcm_device"});
  } catch (const AudioError& e) {
    CHECK(std::string(e.what()).find("no_such_pcm_device") != std::string::npos);
  }
}
#endif
