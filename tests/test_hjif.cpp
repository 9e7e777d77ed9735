// .hjif haptic media: the model's synthesis against closed forms (material/band_synthesis.hpp), the reader and
// writer (io/hjif.hpp) on the shared sample files and on hostile input, the export of a recorded run and its round
// trip, playback on contact and on trigger (material/haptic_playback.hpp), and the hjif_render tool as a user runs it.
#include <catch2/catch.hpp>

#include <sndfile.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "child_process.hpp"
#include "hapticfield/io/hjif.hpp"
#include "hapticfield/material/band_synthesis.hpp"
#include "hapticfield/material/haptic_playback.hpp"
#include "hapticfield/material/haptic_recording.hpp"
#include "io_test_util.hpp"
#include "run_seed.hpp"

using namespace hapticfield;
using namespace hapticfield::material;
namespace fs = std::filesystem;

namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

/// A media of one perception, one channel and one band holding `effects`.
HapticMedia one_band(BandType type, std::vector<Effect> effects, std::int64_t timescale = 1000,
                     CurveType curve = CurveType::linear) {
  Band b;
  b.type = type;
  b.curve_type = curve;
  b.has_curve_type = type == BandType::curve;
  b.lower_frequency_limit = 0;
  b.upper_frequency_limit = 1000;
  b.effects = std::move(effects);
  Channel c;
  c.bands.push_back(std::move(b));
  Perception p;
  p.modality = "Vibrotactile";
  p.channels.push_back(std::move(c));
  HapticMedia m;
  m.timescale = timescale;
  m.perceptions.push_back(std::move(p));
  return m;
}

Effect effect_of(std::int64_t position, std::vector<Keyframe> keyframes, BaseSignal signal = BaseSignal::sine,
                 double phase = 0.0) {
  Effect e;
  e.position = position;
  e.base_signal = signal;
  e.phase = phase;
  e.keyframes = std::move(keyframes);
  return e;
}

std::vector<double> render_one(const HapticMedia& m, double rate, std::size_t count) {
  return render_channel(m, m.perceptions[0], m.perceptions[0].channels[0], rate, count);
}

template <class F>
void expect_file_error(F&& f, const std::string& part) {
  try {
    f();
    FAIL("no FileError; expected one containing: " << part);
  } catch (const FileError& e) {
    const std::string what = e.what();
    INFO(what);
    CHECK(what.find(part) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
  }
}

fs::path haptics_data() {
  const fs::path d = io_test::shared_data();
  return d.empty() ? fs::path() : d / "haptics";
}

}  // namespace

// --- VectorialWave -----------------------------------------------------------------------------------------------
TEST_CASE("VectorialWave: a sine at a constant frequency is sin(2 pi f t + phase), its zero crossings 1/(2f) apart",
          "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 200; ++trial) {
    const double f = std::uniform_int_distribution<int>(20, 400)(rng);
    const double rate = std::uniform_int_distribution<int>(4, 48)(rng) * 1000.0;
    const std::int64_t ts = std::vector<std::int64_t>{1000, 8000, 44100, 1000000}[trial % 4];
    const std::int64_t length = ts / 4;  // 250 ms
    const double phase = std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
    const double a = std::uniform_real_distribution<double>(0.1, 1.0)(rng);
    const auto m =
        one_band(BandType::vectorial_wave, {effect_of(0, {{0, a, f}, {length, a, f}}, BaseSignal::sine, phase)}, ts);
    const auto y = render_one(m, rate, static_cast<std::size_t>(rate * 0.25) + 1);
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double t = static_cast<double>(i) / rate;
      REQUIRE(y[i] == Approx(a * std::sin(two_pi * f * t + phase)).margin(1e-9));
    }
    // zero crossings: count = number of k with t_k = (k pi - phase) / (2 pi f) inside (0, 0.25)
    int crossings = 0;
    for (std::size_t i = 1; i < y.size(); ++i)
      crossings += (y[i - 1] < 0.0) != (y[i] < 0.0) ? 1 : 0;
    const double expected = 2.0 * f * 0.25;
    CHECK(std::abs(crossings - expected) <= 2.0);
  }
}

TEST_CASE("VectorialWave: amplitude keyframes interpolate linearly (a square at 0 Hz shows the envelope)",
          "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> amp(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<Keyframe> k;
    std::int64_t t = 0;
    const int n = std::uniform_int_distribution<int>(2, 12)(rng);
    for (int i = 0; i < n; ++i) {
      k.push_back({t, amp(rng), i == 0 ? std::optional<double>(0.0) : std::nullopt});
      t += std::uniform_int_distribution<int>(1, 200)(rng);
    }
    const auto m = one_band(BandType::vectorial_wave, {effect_of(0, k, BaseSignal::square)});
    const double rate = 2000.0;
    const auto y = render_one(m, rate, static_cast<std::size_t>(t * 2) + 10);
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double tick = static_cast<double>(i) / rate * 1000.0;
      double expect = 0.0;
      if (tick <= static_cast<double>(*k.back().relative_position) + 1e-9) {
        for (std::size_t j = 0; j + 1 < k.size(); ++j) {
          const auto t0 = static_cast<double>(*k[j].relative_position),
                     t1 = static_cast<double>(*k[j + 1].relative_position);
          if (tick >= t0 && tick <= t1)
            expect = *k[j].amplitude + (*k[j + 1].amplitude - *k[j].amplitude) * (tick - t0) / (t1 - t0);
        }
      }
      REQUIRE(y[i] == Approx(std::clamp(expect, -1.0, 1.0)).margin(1e-9));
    }
  }
}

TEST_CASE("VectorialWave: a chirp's phase is the integral of its linear frequency; crossings give f(t)",
          "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 50; ++trial) {
    const double f0 = std::uniform_int_distribution<int>(50, 200)(rng);
    const double f1 = std::uniform_int_distribution<int>(50, 400)(rng);
    const double T = 0.5;  // [s]
    const auto m = one_band(BandType::vectorial_wave, {effect_of(0, {{0, 1.0, f0}, {500, 1.0, f1}})});
    const double rate = 48000.0;
    const auto y = render_one(m, rate, static_cast<std::size_t>(rate * T) + 1);
    const double k = (f1 - f0) / T;
    for (std::size_t i = 0; i < y.size(); i += 7) {
      const double t = static_cast<double>(i) / rate;
      REQUIRE(y[i] == Approx(std::sin(two_pi * (f0 * t + 0.5 * k * t * t))).margin(1e-9));
    }
    // instantaneous frequency from successive upward crossings (interpolated): f0 + k t within 1 %
    std::vector<double> ups;
    for (std::size_t i = 1; i < y.size(); ++i)
      if (y[i - 1] < 0.0 && y[i] >= 0.0) ups.push_back((static_cast<double>(i) - y[i] / (y[i] - y[i - 1])) / rate);
    REQUIRE(ups.size() > 10);
    for (std::size_t j = 1; j < ups.size(); ++j) {
      const double mid = 0.5 * (ups[j] + ups[j - 1]);
      CHECK(1.0 / (ups[j] - ups[j - 1]) == Approx(f0 + k * mid).epsilon(0.01));
    }
  }
}

TEST_CASE("VectorialWave: the base signals against their own closed forms", "[hjif][synthesis]") {
  const double f = 50.0, rate = 10000.0;
  const auto wave_of = [&](BaseSignal s) {
    return render_one(one_band(BandType::vectorial_wave, {effect_of(0, {{0, 1.0, f}, {100, 1.0, f}}, s)}), rate, 1000);
  };
  const auto sq = wave_of(BaseSignal::square), tri = wave_of(BaseSignal::triangle);
  const auto up = wave_of(BaseSignal::saw_tooth_up), down = wave_of(BaseSignal::saw_tooth_down);
  for (std::size_t i = 0; i < sq.size(); ++i) {
    const double t = static_cast<double>(i) / rate, x = two_pi * f * t;
    const double cycle = std::fmod(f * t, 1.0);
    if (std::abs(cycle - 0.5) > 1e-6 && cycle > 1e-6 && cycle < 1 - 1e-6)
      CHECK(sq[i] == (std::sin(x) > 0 ? 1.0 : -1.0));
    CHECK(tri[i] == Approx(2.0 / std::numbers::pi * std::asin(std::sin(x))).margin(1e-9));
    const double saw = cycle < 0.5 ? 2.0 * cycle : 2.0 * cycle - 2.0;  // rises through 0 at phase 0
    if (std::abs(cycle - 0.5) > 1e-6) {
      CHECK(up[i] == Approx(saw).margin(1e-9));
      CHECK(down[i] == Approx(-saw).margin(1e-9));
    }
  }
}

// --- Curve ------------------------------------------------------------------------------------------------------
TEST_CASE("Curve: every curve type passes its ends, stays on a line through collinear keyframes", "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (CurveType type : {CurveType::linear, CurveType::cubic, CurveType::unknown, CurveType::akima, CurveType::bezier,
                         CurveType::bspline}) {
    INFO("curve type " << curve_type_name(type));
    for (int trial = 0; trial < 30; ++trial) {
      const double slope = std::uniform_real_distribution<double>(-0.0006, 0.0006)(rng), c0 = 0.3;  // |value| < 1
      std::vector<Keyframe> k;
      std::int64_t t = std::uniform_int_distribution<int>(0, 50)(rng);
      const int n = std::uniform_int_distribution<int>(3, 9)(rng);
      for (int i = 0; i < n; ++i) {
        k.push_back({t, c0 + slope * static_cast<double>(t), std::nullopt});
        t += std::uniform_int_distribution<int>(5, 100)(rng);
      }
      const auto m = one_band(BandType::curve, {effect_of(10, k)}, 1000, type);
      const double rate = 1000.0;  // one sample per tick
      const auto y = render_one(m, rate, static_cast<std::size_t>(t + 20));
      const auto first = *k.front().relative_position + 10, last = *k.back().relative_position + 10;
      for (std::size_t i = 0; i < y.size(); ++i) {
        const auto tick = static_cast<std::int64_t>(i);
        if (tick < first || tick > last) {
          REQUIRE(y[i] == 0.0);
        } else if (type == CurveType::cubic || type == CurveType::unknown) {
          // zero slope at every keyframe: values stay between the two neighbours
          REQUIRE(y[i] >= std::min(k.front().amplitude.value(), k.back().amplitude.value()) - 1e-12);
          REQUIRE(y[i] <= std::max(k.front().amplitude.value(), k.back().amplitude.value()) + 1e-12);
        } else {
          REQUIRE(y[i] == Approx(c0 + slope * static_cast<double>(tick - 10)).margin(1e-9));
        }
      }
      CHECK(y[static_cast<std::size_t>(first)] == Approx(*k.front().amplitude).margin(1e-9));
      CHECK(y[static_cast<std::size_t>(last)] == Approx(*k.back().amplitude).margin(1e-9));
    }
  }
}

TEST_CASE("Curve: Linear, Cubic and Akima pass through every keyframe; Cubic is the zero-slope Hermite",
          "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> amp(-0.9, 0.9);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Keyframe> k;
    std::int64_t t = 0;
    for (int i = 0; i < 8; ++i) {
      k.push_back({t, amp(rng), std::nullopt});
      t += std::uniform_int_distribution<int>(10, 60)(rng);
    }
    for (CurveType type : {CurveType::linear, CurveType::cubic, CurveType::akima}) {
      const auto y =
          render_one(one_band(BandType::curve, {effect_of(0, k)}, 1000, type), 1000.0, static_cast<std::size_t>(t));
      for (const Keyframe& kf : k)
        REQUIRE(y[static_cast<std::size_t>(*kf.relative_position)] == Approx(*kf.amplitude).margin(1e-12));
      if (type == CurveType::cubic)
        for (std::size_t j = 0; j + 1 < k.size(); ++j) {
          const auto t0 = static_cast<double>(*k[j].relative_position),
                     t1 = static_cast<double>(*k[j + 1].relative_position);
          const double mid = std::floor(0.5 * (t0 + t1)), s = (mid - t0) / (t1 - t0);
          const double smooth = *k[j].amplitude + (*k[j + 1].amplitude - *k[j].amplitude) * s * s * (3 - 2 * s);
          CHECK(y[static_cast<std::size_t>(mid)] == Approx(smooth).margin(1e-12));
        }
    }
  }
}

// --- Transient ----------------------------------------------------------------------------------------------------
TEST_CASE("Transient: two periods of a sine at the keyframe's frequency, scaled by its amplitude",
          "[hjif][synthesis]") {
  const auto m = one_band(BandType::transient, {effect_of(100, {{0, 0.8, 200.0}, {50, -0.5, std::nullopt}})});
  const double rate = 20000.0;
  const auto y = render_one(m, rate, 4000);
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double t = static_cast<double>(i) / rate;
    double expect = 0.0;
    if (t >= 0.1 - 1e-12 && t <= 0.1 + 0.01 + 1e-12) expect += 0.8 * std::sin(two_pi * 200.0 * (t - 0.1));
    if (t >= 0.15 - 1e-12 && t <= 0.15 + 0.022 + 1e-12)
      expect += -0.5 * std::sin(two_pi * default_transient_frequency * (t - 0.15));
    REQUIRE(y[i] == Approx(expect).margin(1e-9));
  }
}

// --- rate and timescale ------------------------------------------------------------------------------------------
TEST_CASE("Synthesis: any rate samples the same signal; any timescale gives the same signal", "[hjif][synthesis]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> amp(-0.5, 0.5);
  for (int trial = 0; trial < 20; ++trial) {
    // a media in milliseconds with every band type that renders
    std::vector<Keyframe> vk{{0, amp(rng), 120.0}, {40, amp(rng), std::nullopt}, {90, amp(rng), 260.0}};
    std::vector<Keyframe> ck{{0, amp(rng), std::nullopt},
                             {30, amp(rng), std::nullopt},
                             {70, amp(rng), std::nullopt},
                             {100, amp(rng), std::nullopt}};
    std::vector<Keyframe> tk{{5, amp(rng), 150.0}, {60, amp(rng), std::nullopt}};
    const auto build = [&](std::int64_t scale) {  // timescale 1000 x scale, every position x scale
      const auto scaled = [&](std::vector<Keyframe> k) {
        for (Keyframe& x : k)
          x.relative_position = *x.relative_position * scale;
        return k;
      };
      HapticMedia m = one_band(BandType::vectorial_wave, {effect_of(20 * scale, scaled(vk), BaseSignal::triangle, 0.3)},
                               1000 * scale);
      Band curve;
      curve.type = BandType::curve;
      curve.curve_type = CurveType::akima;
      curve.effects.push_back(effect_of(10 * scale, scaled(ck)));
      Band transient;
      transient.type = BandType::transient;
      transient.effects.push_back(effect_of(0, scaled(tk)));
      m.perceptions[0].channels[0].bands.push_back(curve);
      m.perceptions[0].channels[0].bands.push_back(transient);
      return m;
    };
    const auto a = render_media(build(1), 8000.0), b = render_media(build(441), 8000.0);
    const auto fine = render_media(build(1), 24000.0);
    REQUIRE(a.channels[0].size() == b.channels[0].size());
    for (std::size_t i = 0; i < a.channels[0].size(); ++i) {
      REQUIRE(a.channels[0][i] == Approx(b.channels[0][i]).margin(1e-9));
      if (3 * i < fine.channels[0].size()) REQUIRE(a.channels[0][i] == Approx(fine.channels[0][3 * i]).margin(1e-9));
    }
  }
}

TEST_CASE("Synthesis: Reference effects play their library entry at their own position; gain and exponent scale",
          "[hjif][synthesis]") {
  HapticMedia direct = one_band(BandType::vectorial_wave, {effect_of(30, {{0, 0.5, 100.0}, {40, 0.5, 100.0}})});
  HapticMedia referred = direct;
  Effect lib = direct.perceptions[0].channels[0].bands[0].effects[0];
  lib.id = 7;
  lib.position = 0;
  Effect ref;
  ref.type = EffectType::reference;
  ref.id = 7;
  ref.position = 30;
  referred.perceptions[0].effect_library = {lib};
  referred.perceptions[0].channels[0].bands[0].effects = {ref};
  const auto a = render_media(direct, 8000.0), b = render_media(referred, 8000.0);
  CHECK(a.channels == b.channels);
  referred.perceptions[0].channels[0].gain = 0.5;
  referred.perceptions[0].perception_unit_exponent = 1;
  const auto c = render_media(referred, 8000.0);
  for (std::size_t i = 0; i < a.channels[0].size(); ++i)
    REQUIRE(c.channels[0][i] == Approx(5.0 * a.channels[0][i]));
}

// --- real files -----------------------------------------------------------------------------------------------------
TEST_CASE("hjif: every shared sample file loads, renders finite and bounded, and survives a write and re-read",
          "[hjif][real]") {
  const fs::path dir = haptics_data();
  if (dir.empty() || !fs::is_directory(dir)) {
    WARN("skipped: no shared data folder (set HAPTICFIELD_SHARED_DATA)");
    return;
  }
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".hjif") continue;
    ++files;
    INFO(entry.path().filename().string());
    const io::HjifFile f = io::load_hjif(entry.path().string());
    REQUIRE_FALSE(f.media.perceptions.empty());
    for (double rate : {8000.0, 44100.0}) {
      const RenderedMedia r = render_media(f.media, rate);
      for (std::size_t c = 0; c < r.channels.size(); ++c) {
        const double gain = std::abs(f.media.perceptions[0].channels[c].gain);
        for (double y : r.channels[c])
          REQUIRE((std::isfinite(y) && std::abs(y) <= gain + 1e-12));
      }
    }
    const io::HjifFile again = io::parse_hjif(io::write_hjif_string(f.media), "rewritten");
    CHECK(render_media(again.media, 8000.0).channels == render_media(f.media, 8000.0).channels);
    CHECK(io::write_hjif_string(again.media) == io::write_hjif_string(f.media));
    if (entry.path().filename() != "wmtlab-legacy-0.hjif") {  // the Encoder's files come back as the same JSON
      std::ifstream in(entry.path(), std::ios::binary);
      const std::string original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      CHECK(nlohmann::json::parse(original) == nlohmann::json::parse(io::write_hjif_string(f.media)));
    }
  }
  CHECK(files >= 12);
  // the refactored file (effect_library + Reference effects) renders as the plain one
  const auto plain = render_media(io::load_hjif((dir / "IMMR-vib-Content1.hjif").string()).media, 8000.0);
  const auto refactored =
      render_media(io::load_hjif((dir / "IMMR-vib-Content1-refactored.hjif").string()).media, 8000.0);
  CHECK(plain.channels == refactored.channels);
  // Boing: a 159 -> 218 Hz chirp from 15 ms to 265 ms: count zero crossings against the integral of f (ignoring the
  // transient in its first 22 ms)
  const auto boing = io::load_hjif((dir / "APPL-vib-boing.hjif").string());
  const auto y = render_media(boing.media, 48000.0).channels[0];
  int crossings = 0;
  for (std::size_t i = static_cast<std::size_t>(0.03 * 48000); i + 1 < static_cast<std::size_t>(0.2 * 48000); ++i)
    crossings += (y[i] < 0.0) != (y[i + 1] < 0.0) ? 1 : 0;
  const auto cycles = [](double t) { return 159.0 * t + 0.5 * (59.0 / 0.25) * t * t; };  // t from 15 ms
  CHECK(std::abs(crossings - 2.0 * (cycles(0.185) - cycles(0.015))) <= 2.0);
  // the legacy draft file is reported, not refused: its unknown field is a note
  const auto legacy = io::load_hjif((dir / "wmtlab-legacy-0.hjif").string());
  CHECK(std::find(legacy.notes.begin(), legacy.notes.end(), "kept, not rendered: channel.mixing_weight") !=
        legacy.notes.end());
  WARN("no reference synthesizer output (.wav) comes with the samples: nothing to compare sample by sample");
}

TEST_CASE("WaveletWave: the Actronika file renders its PCM input back (Curve + wavelet blocks)", "[hjif][real]") {
  const fs::path dir = haptics_data();
  if (dir.empty() || !fs::is_directory(dir)) {
    WARN("skipped: no shared data folder (set HAPTICFIELD_SHARED_DATA)");
    return;
  }
  SF_INFO info{};
  SNDFILE* f = sf_open((dir / "inputs" / "ACTK-vib-pantheongrandstarfall-8kHz-16-nopad.wav").c_str(), SFM_READ, &info);
  REQUIRE(f != nullptr);
  std::vector<double> pcm(static_cast<std::size_t>(info.frames));
  CHECK(sf_readf_double(f, pcm.data(), info.frames) == info.frames);
  sf_close(f);
  const auto snr_db = [&](const std::string& name) {
    const auto y = render_media(io::load_hjif((dir / name).string()).media, info.samplerate).channels[0];
    REQUIRE(y.size() >= pcm.size());
    double signal = 0.0, error = 0.0;
    for (std::size_t i = 0; i < pcm.size(); ++i)
      signal += pcm[i] * pcm[i], error += (pcm[i] - y[i]) * (pcm[i] - y[i]);
    return 10.0 * std::log10(signal / error);
  };
  const double full = snr_db("ACTK-vib-pantheongrandstarfall.hjif");
  const double curve_only = snr_db("ACTK-vib-pantheongrandstarfall-curveonly.hjif");
  INFO("SNR against the encoder's input: " << full << " dB with the wavelet band, " << curve_only << " dB without");
  CHECK(full >= 15.0);  // measured 15.97 dB
  CHECK(curve_only <= 4.0);
}

TEST_CASE("WaveletWave: garbage streams decode to finite samples; other block lengths to nothing", "[hjif][hostile]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/=?";
  for (int trial = 0; trial < 200; ++trial) {
    std::string s(std::uniform_int_distribution<std::size_t>(0, 300)(rng), 'A');
    for (char& c : s)
      c = alphabet[std::uniform_int_distribution<std::size_t>(0, alphabet.size() - 1)(rng)];
    const std::size_t n = std::size_t{16} << std::uniform_int_distribution<int>(0, 8)(rng);
    const auto x = decode_wavelet_block(s, n);
    REQUIRE(x.size() == n);
    for (double v : x)
      REQUIRE(std::isfinite(v));
  }
  CHECK(decode_wavelet_block("AAAA", 1000).empty());
  CHECK(decode_wavelet_block("AAAA", 8).empty());  // the tree roots would have no room for their children
  CHECK(decode_wavelet_block("AAAA", max_wavelet_block * 2).empty());
  CHECK(decode_wavelet_block("", 1024) == std::vector<double>(1024, 0.0));
}

// --- export of a recorded run, round trip -------------------------------------------------------------------------
TEST_CASE("hjif: a recorded run exported and read back renders the recorded force, contact and vibration",
          "[hjif][export]") {
  const auto seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  RecordedRun run;
  run.servo_rate = 1000.0;
  run.vibration_rate = 8000.0;
  for (int i = 0; i < 500; ++i) {
    run.force.push_back({noise(rng), 2.0 * noise(rng), 3.0 + noise(rng)});
    run.contact.push_back(std::abs(3.0 + noise(rng)));
  }
  for (int i = 0; i < 4000; ++i)
    run.vibration.push_back(0.3 * std::sin(i * 0.2) + 0.1 * noise(rng));
  const HapticMedia m = media_from_run(run);
  const fs::path dir = fs::path(HAPTICFIELD_TEST_TMP) / "hjif";
  fs::create_directories(dir);
  const std::string path = (dir / "run.hjif").string();
  io::save_hjif(m, path);
  const io::HjifFile back = io::load_hjif(path);
  REQUIRE(back.media.perceptions.size() == 3);
  CHECK(back.media.perceptions[0].modality == "Force");
  CHECK(back.media.perceptions[2].modality == "Vibrotactile");
  const auto& force = back.media.perceptions[0];
  for (int axis = 0; axis < 3; ++axis) {
    const auto y = render_channel(back.media, force, force.channels[static_cast<std::size_t>(axis)], 1000.0, 500);
    for (std::size_t i = 0; i < 500; ++i)
      REQUIRE(y[i] == Approx(run.force[i][axis]).margin(1e-12));
  }
  const auto& contact = back.media.perceptions[1];
  const auto yc = render_channel(back.media, contact, contact.channels[0], 1000.0, 500);
  for (std::size_t i = 0; i < 500; ++i)
    REQUIRE(yc[i] == Approx(run.contact[i]).margin(1e-12));
  const auto& vib = back.media.perceptions[2];
  const auto yv = render_channel(back.media, vib, vib.channels[0], 8000.0, 4000);
  for (std::size_t i = 0; i < 4000; ++i)
    REQUIRE(yv[i] == Approx(std::clamp(run.vibration[i], -1.0, 1.0)).margin(1e-12));
  // the layout the reference loader requires: every top-level member, Curve bands with a curve_type
  const std::string text = io::write_hjif_string(m);
  for (const char* key : {"\"version\"", "\"profile\"", "\"level\"", "\"date\"", "\"description\"", "\"timescale\"",
                          "\"avatars\"", "\"perceptions\"", "\"syncs\"", "\"mixing_coefficient\"", "\"body_part_mask\"",
                          "\"curve_type\":\"Linear\"", "\"effect_library\"", "\"reference_devices\""})
    CHECK(text.find(key) != std::string::npos);
}

TEST_CASE("hjif: unknown fields are kept and written back, unknown band types skipped, each with a note", "[hjif]") {
  const std::string text = R"({"version":"2023","profile":"Main","level":1,"date":"","description":"","timescale":1000,
    "avatars":[{"id":0,"lod":0,"type":"Vibration"}],"vendor_thing":{"a":[1,2]},
    "perceptions":[{"id":0,"avatar_id":0,"description":"","perception_modality":"Smell","effect_library":[],
      "channels":[{"id":0,"description":"","gain":1,"mixing_coefficient":1,"body_part_mask":0,"direction":[0,0,1],
        "bands":[{"band_type":"Hologram","effects":[]},
                 {"band_type":"VectorialWave","lower_frequency_limit":0,"upper_frequency_limit":1000,"effects":[
                   {"effect_type":"Basis","position":0,"keyframes":[{"relative_position":0,"amplitude_modulation":1,
                     "frequency_modulation":100,"colour":"red"},{"relative_position":10}]},
                   {"effect_type":"Composite","position":0,"timeline":[]}]}]}]}],"syncs":[]})";
  const io::HjifFile f = io::parse_hjif(text, "t.hjif");
  const auto has = [&](const std::string& n) { return std::find(f.notes.begin(), f.notes.end(), n) != f.notes.end(); };
  CHECK(has("kept, not rendered: (top level).vendor_thing"));
  CHECK(has("kept, not rendered: channel.direction"));
  CHECK(has("skipped: band of unknown band_type \"Hologram\""));
  CHECK(has("skipped: keyframe field \"colour\""));
  CHECK(has("skipped: Composite effects (their timeline is not rendered)"));
  CHECK(has("modality \"Smell\": rendered as a signal, played on the vibration path"));
  REQUIRE(f.media.perceptions[0].channels[0].bands.size() == 1);
  const std::string out = io::write_hjif_string(f.media);
  CHECK(out.find("\"vendor_thing\":{\"a\":[1,2]}") != std::string::npos);
  CHECK(out.find("\"direction\":[0,0,1]") != std::string::npos);
  CHECK(out.find("\"avatars\":[{\"id\":0,\"lod\":0,\"type\":\"Vibration\"}]") != std::string::npos);
}

// --- hostile input -------------------------------------------------------------------------------------------------
TEST_CASE("hjif: hostile files give one FileError naming the limit or the field, in bounded time", "[hjif][hostile]") {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string head =
      R"({"timescale":1000,"perceptions":[{"channels":[{"bands":[{"band_type":"Curve","effects":[)";
  const std::string tail = "]}]}]}]}";
  SECTION("deep nesting") {
    expect_file_error([] { (void)io::parse_hjif(std::string(100000, '['), "deep.hjif"); },
                      "deep.hjif: nested deeper than the limit of 32 levels");
    expect_file_error([] { (void)io::parse_hjif(std::string(50000, '{'), "deep.hjif"); }, "deep.hjif: ");
  }
  SECTION("huge arrays") {
    io::HjifLimits arrays;  // the default's 4,000,000 the same way, at a size a test builds quickly
    arrays.max_array = 100'000;
    std::string big = "{\"perceptions\":[";
    for (int i = 0; i < 100'001; ++i)
      big += "0,";
    big += "0]}";
    expect_file_error([&] { (void)io::parse_hjif(big, "huge.hjif", arrays); },
                      "huge.hjif: an array of 100002 elements, more than the limit of 100000");
    io::HjifLimits small;
    small.max_values = 1000;
    std::string many = head + R"({"keyframes":[)";
    for (int i = 0; i < 2000; ++i)
      many += "{\"relative_position\":" + std::to_string(i) + "},";
    many += "{}]}" + tail;
    expect_file_error([&] { (void)io::parse_hjif(many, "many.hjif", small); },
                      "more than the limit of 1000 JSON values");
  }
  SECTION("a 10 MB string") {
    const std::string s = head + R"({"wavelet_stream":")" + std::string(10 << 20, 'A') + "\"}" + tail;
    expect_file_error([&] { (void)io::parse_hjif(s, "string.hjif"); },
                      "string.hjif: a string of 10485760 bytes, longer than the limit of 1048576 bytes");
  }
  SECTION("wrong types") {
    expect_file_error([] { (void)io::parse_hjif("[1,2]", "a.hjif"); },
                      "a.hjif: (top level): expected an object, got array");
    expect_file_error([] { (void)io::parse_hjif(R"({"perceptions":{}})", "a.hjif"); },
                      "perceptions: expected an array, got object");
    expect_file_error(
        [&] { (void)io::parse_hjif(head + R"({"keyframes":[{"amplitude_modulation":"loud"}]})" + tail, "a.hjif"); },
        "perceptions[0].channels[0].bands[0].effects[0].keyframes[0].amplitude_modulation: expected a "
        "number, got string");
    expect_file_error([&] { (void)io::parse_hjif(head + R"({"position":-5,"keyframes":[]})" + tail, "a.hjif"); },
                      "effects[0].position: out of range");
    expect_file_error([] { (void)io::parse_hjif(R"({"timescale":0,"perceptions":[]})", "a.hjif"); },
                      "timescale: out of range");
    expect_file_error([] { (void)io::parse_hjif(R"({"perceptions":[{"channels":[{"bands":[{}]}]}]})", "a.hjif"); },
                      "bands[0]: missing \"band_type\"");
  }
  SECTION("NaN and infinite keyframes") {
    expect_file_error(
        [&] { (void)io::parse_hjif(head + R"({"keyframes":[{"amplitude_modulation":NaN}]})" + tail, "n.hjif"); },
        "n.hjif: not JSON");
    expect_file_error(
        [&] { (void)io::parse_hjif(head + R"({"keyframes":[{"amplitude_modulation":1e999}]})" + tail, "n.hjif"); },
        "n.hjif: not JSON: number overflow");
    expect_file_error(
        [&] { (void)io::parse_hjif(head + R"({"keyframes":[{"frequency_modulation":-3}]})" + tail, "n.hjif"); },
        "frequency_modulation: negative frequency");
  }
  SECTION("not JSON, truncated, empty, a missing file") {
    expect_file_error([] { (void)io::parse_hjif("", "e.hjif"); }, "e.hjif: not JSON");
    expect_file_error([&] { (void)io::parse_hjif(head, "t.hjif"); }, "t.hjif: not JSON");
    expect_file_error([] { (void)io::load_hjif("/nonexistent/x.hjif"); }, "no such file");
  }
  SECTION("an effect at the end of time renders nothing rather than an hour-long buffer") {
    const std::string far =
        head + R"({"position":4503599627370496,"keyframes":[{"relative_position":0,"amplitude_modulation":1}]})" + tail;
    const io::HjifFile f = io::parse_hjif(far, "far.hjif");
    CHECK_THROWS_AS(render_media(f.media, 8000.0), std::invalid_argument);
  }
  // bounded time: generous, a hang is what this catches (not a speed test)
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60));
}

// --- playback ----------------------------------------------------------------------------------------------------
TEST_CASE("ClipSource: plays the rendered clip once per touch or per trigger, allocation-free", "[hjif][playback]") {
  std::vector<double> clip(80);
  for (std::size_t i = 0; i < clip.size(); ++i)
    clip[i] = std::sin(0.3 * static_cast<double>(i));
  ClipSource touch(clip, {8000.0, 2.0, ClipStart::on_contact, 0.0});
  touch.prepare(8000.0);
  vibration::ContactState off{}, on{};
  on.touching = true;
  on.normal_force = 1.0;
  CHECK(touch.next(off) == 0.0);
  std::vector<double> played;
  played.reserve(200);
  const long allocations = test::count_allocations([&] {
    for (int i = 0; i < 100; ++i)
      played.push_back(touch.next(on));
    (void)touch.next(off);
    for (int i = 0; i < 10; ++i)
      played.push_back(touch.next(on));  // a new touch starts over
  });
  if (test::allocations_counted) CHECK(allocations == 0);
  for (std::size_t i = 0; i < 80; ++i)
    REQUIRE(played[i] == Approx(2.0 * clip[i]));
  for (std::size_t i = 80; i < 100; ++i)
    REQUIRE(played[i] == 0.0);
  for (std::size_t i = 0; i < 10; ++i)
    REQUIRE(played[100 + i] == Approx(2.0 * clip[i]));

  ClipSource trig(clip, {8000.0, 1.0, ClipStart::on_trigger, 0.0});
  trig.prepare(16000.0);  // resampled: twice as many samples, the same signal
  CHECK(trig.next(on) == 0.0);
  trig.trigger();
  for (std::size_t i = 0; i < 158; ++i) {
    const double expect = (i % 2 == 0) ? clip[i / 2] : 0.5 * (clip[i / 2] + clip[i / 2 + 1]);
    REQUIRE(trig.next(off) == Approx(expect).margin(1e-12));
  }
}

TEST_CASE("NormalClipField: without a vibration path the clip plays along the surface normal", "[hjif][playback]") {
  struct Zero {
    glm::dvec3 force(const Probe&) noexcept { return glm::dvec3{0.0}; }
  };
  NormalClipField<Zero> field(Zero{}, {0.0, 1.0, 0.0, -1.0}, {1000.0, 0.5, ClipStart::on_contact, 0.0});
  Probe p;
  p.surface_normal = {0.0, 0.0, 1.0};
  p.time = 1.0;
  CHECK(field.force(p).z == 0.0);  // not touching
  p.normal_force = 2.0;
  const double expect[] = {0.0, 0.5, 0.0, -0.5, 0.0, 0.0};
  for (double e : expect) {
    CHECK(field.force(p).z == Approx(e).margin(1e-12));
    p.time += 0.001;
  }
}

// --- the tool, as a user runs it -------------------------------------------------------------------------------------
#ifdef HAPTICFIELD_TOOL_HJIF_RENDER
TEST_CASE("hjif_render: --help, --info, a bad file, and a WAV read back with libsndfile", "[hjif][tool]") {
  const std::string tool = HAPTICFIELD_TOOL_HJIF_RENDER;
  const fs::path dir = fs::path(HAPTICFIELD_TEST_TMP) / "hjif_tool";
  fs::create_directories(dir);
  {
    testing::Child c(tool, {"--help"}, dir, "help");
    REQUIRE(c.wait());
    CHECK(c.status() == 0);
    CHECK(c.out().find("usage: hjif_render") != std::string::npos);
  }
  // a two-channel media: a 100 Hz sine and a Curve ramp
  HapticMedia m = one_band(BandType::vectorial_wave, {effect_of(0, {{0, 0.5, 100.0}, {100, 0.5, 100.0}})});
  Channel ramp;
  ramp.id = 1;
  Band curve;
  curve.type = BandType::curve;
  curve.curve_type = CurveType::linear;
  curve.effects.push_back(effect_of(0, {{0, 0.0, std::nullopt}, {50, 0.25, std::nullopt}, {100, 1.0, std::nullopt}}));
  ramp.bands.push_back(curve);
  Perception force;
  force.id = 1;
  force.modality = "Force";
  force.channels.push_back(ramp);
  m.perceptions.push_back(force);
  const std::string in = (dir / "two.hjif").string();
  io::save_hjif(m, in);
  {
    testing::Child c(tool, {in, "--info"}, dir, "info");
    REQUIRE(c.wait());
    CHECK(c.status() == 0);
    CHECK(c.out().find("channel 0: perception 0 modality Vibrotactile channel 0 bands VectorialWave") !=
          std::string::npos);
    CHECK(c.out().find("channel 1: perception 1 modality Force channel 1 bands Curve") != std::string::npos);
  }
  {
    const std::string bad = io_test::write(dir / "bad.hjif", R"({"perceptions":[{"channels":7}]})");
    testing::Child c(tool, {bad, "--info"}, dir, "bad");
    REQUIRE(c.wait());
    CHECK(c.status() == 1);
    CHECK(c.err() == "hjif_render: " + bad + ": perceptions[0].channels: expected an array, got number\n");
  }
  {
    testing::Child c(tool, {in, "--wav", (dir / "x.wav").string(), "--rate", "12.5"}, dir, "rate");
    REQUIRE(c.wait());
    CHECK(c.status() == 2);
  }
  const std::string wav = (dir / "two.wav").string();
  testing::Child c(tool, {in, "--wav", wav, "--rate", "16000"}, dir, "wav");
  REQUIRE(c.wait());
  REQUIRE(c.status() == 0);
  CHECK(c.err().find("[0] perception 0 (Vibrotactile) channel 0; [1] perception 1 (Force) channel 1;") !=
        std::string::npos);
  SF_INFO info{};
  SNDFILE* f = sf_open(wav.c_str(), SFM_READ, &info);
  REQUIRE(f != nullptr);
  CHECK(info.channels == 2);
  CHECK(info.samplerate == 16000);
  std::vector<float> frames(static_cast<std::size_t>(info.frames) * 2);
  CHECK(sf_readf_float(f, frames.data(), info.frames) == info.frames);
  sf_close(f);
  const auto expect = render_media(m, 16000.0);
  REQUIRE(static_cast<std::size_t>(info.frames) == expect.channels[0].size());
  for (std::size_t i = 0; i < expect.channels[0].size(); ++i) {
    REQUIRE(frames[2 * i] == Approx(expect.channels[0][i]).margin(1e-6));
    REQUIRE(frames[2 * i + 1] == Approx(expect.channels[1][i]).margin(1e-6));
  }
  CHECK(frames[2 * 800 + 1] == Approx(0.25).margin(1e-6));  // the ramp's middle keyframe at 50 ms
}
#endif
