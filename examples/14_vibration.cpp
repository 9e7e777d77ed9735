// vibration --hatt FILE (--wav OUT.wav | --alsa DEVICE | --spectrum OUT.csv) [options]
//
// The vibration path end to end, on a scripted stroke: a probe slides over
// a plane textured with a HaTT material (Culbertson, Lopez Delgado &
// Kuchenbecker 2014) at the speed and force of one of its models. The servo
// side runs tap(contact(plane), ring) at 1 kHz; the audio side runs the
// model at its own rate (10 kHz) through VibrationRenderer into a sink: a
// WAV file, an ALSA device (`null` needs no sound card), or nothing but a
// spectrum. Time is simulated and tied to the audio frames (1 ms of ticks
// per 1 ms of frames), so a WAV file is written as fast as the machine goes
// and is the same on every run; an ALSA device sets the pace itself.
//
// The stroke: 0.1 s above the surface, then sliding along x at the model's
// speed, pressed to the model's force, then 0.1 s lifted. --spectrum writes
// the Welch PSD of what the audio path played while sliding beside the
// model's own closed-form PSD, in dB (docs/images/vibration_spectrum.png).
//
// Exit status: 0 done, 1 bad input (model file, output file, device), 2
// bad usage.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/cli.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/texture/psd.hpp"
#include "hapticfield/vibration.hpp"
#ifdef HAPTICFIELD_EXAMPLE_ALSA
#include "hapticfield/vibration/alsa_sink.hpp"
#endif
#include "hapticfield/vibration/wav_sink.hpp"

using namespace hapticfield;
namespace vib = hapticfield::vibration;

namespace {

const char* const usage_text =
    "usage: vibration --hatt FILE (--wav OUT.wav | --alsa DEVICE | --spectrum OUT.csv) [options]\n"
    "  a scripted stroke over a HaTT texture: tap -> ring -> renderer -> sink, on simulated time\n"
    "  --hatt FILE        a HaTT modelSet (.xml), e.g. Models_Book.xml of the toolkit's 10 kHz models;\n"
    "                     at most 16 MB, <SampleRate> in 100..100000 Hz\n"
    "  --model K          stroke at the speed and force of model K (default: the first with motion and force)\n"
    "  --wav OUT.wav      record what would have been played (32-bit float WAV)\n"
    "  --alsa DEVICE      play on an ALSA PCM (e.g. default, hw:0, plughw:0; null plays nowhere)\n"
    "  --spectrum OUT.csv the played PSD while sliding against the model's own (frequency_Hz, audio_dB, model_dB)\n"
    "  --seconds S        stroke length [s], in [0.5, 600] (default 3)\n"
    "  --rate HZ          audio rate [Hz], a whole number in [8000, 192000] (default 48000)\n"
    "  --block N          frames per audio block (the ALSA period), in 16..8192 (default 256)\n"
    "  --periods N        ALSA periods in the device buffer, in 2..16 (default 2)\n"
    "  --gain G           output per m/s^2 [s^2/m], in (0, 10] (default 0.02: 50 m/s^2 full scale)\n"
    "--wav and --alsa exclude each other; --spectrum goes with either or alone.\n"
    "Exit status: 0 done, 1 bad input (file, device), 2 bad usage.\n";

struct Args {
  std::string hatt, wav, alsa, spectrum;
  long long model{-1};  // -1: the first with motion and force
  double seconds{3.0};
  double rate{48000.0};
  long long block{256};
  long long periods{2};
  double gain{0.02};
};

constexpr std::uint32_t material = 1;  // the textured plane's material id
constexpr double stiffness = 1000.0;   // [N/m]
constexpr double approach_time = 0.1;  // [s] above the surface before the stroke
constexpr double lift_time = 0.1;      // [s] lifted at the end
constexpr double settle_time = 0.05;   // [s] of sliding left out of the spectrum (onset)
constexpr std::size_t psd_segment = 4096;

/// The scripted probe at time t [s]: above, sliding at `speed` pressed to
/// depth force / stiffness, above again.
Probe scripted_probe(double t, double seconds, double speed, double force) {
  Probe p;
  p.time = t;
  const bool sliding = t >= approach_time && t < seconds - lift_time;
  const double x = speed * std::clamp(t - approach_time, 0.0, seconds - approach_time - lift_time);
  p.position = {x, 0.0, sliding ? -force / stiffness : 0.005};
  p.velocity = {sliding ? speed : 0.0, 0.0, 0.0};
  return p;
}

/// The model the stroke holds, by index or the first with motion and force.
std::size_t choose_model(const texture::HattModelSet& set, long long wanted) {
  if (wanted >= 0) {
    if (static_cast<std::size_t>(wanted) >= set.models.size())
      throw cli::UsageError("--model must be in 0.." + std::to_string(set.models.size() - 1) + " for this file, got " +
                            std::to_string(wanted));
    const auto k = static_cast<std::size_t>(wanted);
    if (!(set.speeds[k] > 0.0 && set.forces[k] > 0.0))
      throw cli::UsageError("--model " + std::to_string(wanted) + " has no motion or no force (speed " +
                            std::to_string(set.speeds[k]) + ", force " + std::to_string(set.forces[k]) + ")");
    return k;
  }
  for (std::size_t k = 0; k < set.models.size(); ++k)
    if (set.speeds[k] > 0.0 && set.forces[k] > 0.0) return k;
  throw FileError("'" + set.name + "' has no model with motion and force");
}

/// Writes the played PSD beside the model's closed-form PSD; returns the
/// median |dB error| up to 4 kHz.
double write_spectrum(const std::string& path, const std::vector<double>& played, double rate,
                      const texture::HattModelSet& set, std::size_t m) {
  const texture::HattModel& model = set.models[m];
  std::vector<double> a = model.ar_coeff;  // the file's own coefficients when it has them
  if (a.empty()) a = texture::lsf_to_ar(model.ar_lsf);
  if (a.size() == set.ar_order) a.insert(a.begin(), 1.0);
  std::vector<double> b = model.ma_coeff;
  if (b.empty() && !model.ma_lsf.empty()) b = texture::lsf_to_ar(model.ma_lsf);
  const double ma_gain = set.ma_order > 0 ? model.gain : 1.0;

  const offline::Spectrum psd = offline::welch_psd(played, rate, psd_segment);
  std::ofstream out(path);
  if (!out) throw FileError("--spectrum: cannot write '" + path + "'");
  out << "frequency_Hz,audio_dB,model_dB\n";
  std::vector<double> errors;
  const double top = std::min(rate, set.sample_rate) / 2.0;
  for (std::size_t k = 1; k < psd.frequency.size() && psd.frequency[k] < top; ++k) {
    const double f = psd.frequency[k];
    const double model_psd = offline::arma_psd(a, b, model.variance, ma_gain, f, set.sample_rate);
    const double audio_db = 10.0 * std::log10(std::max(psd.density[k], 1e-300));
    const double model_db = 10.0 * std::log10(model_psd);
    out << f << ',' << audio_db << ',' << model_db << '\n';
    if (f <= 4000.0) errors.push_back(std::fabs(audio_db - model_db));
  }
  if (!out) throw FileError("--spectrum: cannot write '" + path + "'");
  std::sort(errors.begin(), errors.end());
  return errors.empty() ? 0.0 : errors[errors.size() / 2];
}

/// Passes each block on to a sink and keeps a copy for the figures printed.
template <class Sink>
struct Observed {
  Sink* sink;
  std::vector<float> last;
  std::size_t write(std::span<const float> frames) noexcept {
    std::copy(frames.begin(), frames.end(), last.begin());
    return sink->write(frames);
  }
  [[nodiscard]] bool paced() const noexcept { return sink->paced(); }
};

template <class Sink>
int run(const Args& a, const texture::HattModelSet& set, std::size_t m, Sink& sink, const char* sink_name,
        double device_buffer_s) {
  const double speed = set.speeds[m] / set.speed_to_file;  // [m/s]
  const double force = set.forces[m];                      // [N]
  static vib::ContactRing<> ring;                          // shared by the two sides
  auto field = vib::tap(contact(PlaneConstraint({.stiffness = stiffness})), ring, {.material = material});

  const auto block = static_cast<std::size_t>(a.block);
  vib::RendererConfig config;
  config.playout.sample_rate = a.rate;
  config.playout.delay = static_cast<double>(block) / a.rate + 0.002;  // one block + two ticks (as in main)
  auto renderer =
      vib::renderer(ring, config, vib::route(vib::HattSource<64>(set, {.gain = a.gain, .seed = 7}), material));
  Observed<Sink> observed{&sink, std::vector<float>(block)};
  vib::VibrationStream stream(renderer, observed, block);

  // The two sides on one simulated timeline: before each block, the ticks
  // up to the block's first frame.
  const auto blocks = static_cast<long>(std::ceil(a.seconds * a.rate / static_cast<double>(block)));
  const double slide_from = approach_time + settle_time + config.playout.delay;
  const double slide_to = a.seconds - lift_time;
  const std::vector<float>& last = observed.last;
  std::vector<double> played;  // the sliding part, for the spectrum, in m/s^2
  double sum_sq = 0.0;
  std::size_t sliding_frames = 0, clipped = 0;
  long tick = 0;
  for (long b = 0; b < blocks; ++b) {
    const double now = static_cast<double>(b) * static_cast<double>(block) / a.rate;
    for (; static_cast<double>(tick) * 1e-3 <= now + 1e-12; ++tick)
      (void)field.force(scripted_probe(static_cast<double>(tick) * 1e-3, a.seconds, speed, force));
    if (stream.pull() < block) throw FileError(std::string(sink_name) + ": the sink did not take a whole block");
    for (std::size_t i = 0; i < block; ++i) {
      const double t = now + static_cast<double>(i) / a.rate;
      if (std::fabs(last[i]) >= 1.0f) ++clipped;
      if (t >= slide_from && t < slide_to) {
        sum_sq += static_cast<double>(last[i]) * static_cast<double>(last[i]);
        ++sliding_frames;
        if (!a.spectrum.empty()) played.push_back(static_cast<double>(last[i]) / (a.gain * set.acceleration_to_si));
      }
    }
  }
  const double frames = static_cast<double>(blocks) * static_cast<double>(block);
  std::printf("vibration: %s, model %zu of '%s' (%.0f Hz): %.3f m/s at %.2f N\n", sink_name, m, set.name.c_str(),
              set.sample_rate, speed, force);
  std::printf("  %.0f frames at %.0f Hz (%.3f s), blocks of %zu, %llu ticks, %llu dropped\n", frames, a.rate,
              frames / a.rate, block, static_cast<unsigned long long>(tick),
              static_cast<unsigned long long>(field.dropped()));
  std::printf("  output RMS while sliding %.4f (full scale 1), %zu samples clipped\n",
              sliding_frames ? std::sqrt(sum_sq / static_cast<double>(sliding_frames)) : 0.0, clipped);
  std::printf("  latency, tick to output: %.2f ms (delay) + %.2f ms (device buffer)\n", config.playout.delay * 1e3,
              device_buffer_s * 1e3);
  if (!a.spectrum.empty()) {
    const double e = write_spectrum(a.spectrum, played, a.rate, set, m);
    std::printf("  spectrum: %s, median |dB error| up to 4 kHz against the model: %.2f dB\n", a.spectrum.c_str(), e);
  }
  return cli::exit_ok;
}

int run_with_sink(const Args& a) {
  const texture::HattModelSet set = texture::load_hatt_model_set(a.hatt);
  const std::size_t m = choose_model(set, a.model);
  if (!a.wav.empty()) {
    vib::WavSink sink(a.wav, {.sample_rate = a.rate});
    const int status = run(a, set, m, sink, ("WAV '" + a.wav + "'").c_str(), 0.0);
    sink.close();
    return status;
  }
  if (!a.alsa.empty()) {
#ifdef HAPTICFIELD_EXAMPLE_ALSA
    // ALSA's library prints its own complaint before failing: muted, the tool reports it once
    auto opened = cli::quiet_stderr([&] {
      return std::make_unique<vib::AlsaSink>(vib::AlsaConfig{.device = a.alsa,
                                                             .sample_rate = static_cast<unsigned>(a.rate),
                                                             .format = vib::AlsaFormat::s16,
                                                             .period_frames = static_cast<unsigned>(a.block),
                                                             .periods = static_cast<unsigned>(a.periods)});
    });
    vib::AlsaSink& sink = *opened;
    const double buffer = static_cast<double>(a.block * a.periods) / a.rate;
    const int status = run(a, set, m, sink, ("ALSA '" + a.alsa + "'").c_str(), buffer);
    if (sink.errors() > 0) std::printf("  ALSA: %llu write errors\n", static_cast<unsigned long long>(sink.errors()));
    return status;
#else
    throw FileError("--alsa: this build has no ALSA (libasound2-dev)");
#endif
  }
  vib::NullSink sink;
  return run(a, set, m, sink, "no sink", 0.0);
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("vibration", usage_text, argc, argv, [](cli::Parser& p) {
    Args a;
    while (p.next()) {
      if (p.is("--hatt"))
        a.hatt = p.value();
      else if (p.is("--model"))
        a.model = p.integer(0, 100000);
      else if (p.is("--wav"))
        a.wav = p.output_file();
      else if (p.is("--alsa"))
        a.alsa = p.value();
      else if (p.is("--spectrum"))
        a.spectrum = p.output_file();
      else if (p.is("--seconds"))
        a.seconds = p.real(cli::closed(0.5, 600.0));
      else if (p.is("--rate"))
        a.rate = p.whole(cli::closed(8000.0, 192000.0), "Hz");
      else if (p.is("--block"))
        a.block = p.integer(16, 8192);
      else if (p.is("--periods"))
        a.periods = p.integer(2, 16);
      else if (p.is("--gain"))
        a.gain = p.real(cli::open_closed(0.0, 10.0));
      else
        p.unknown();
    }
    if (a.hatt.empty()) throw cli::UsageError("--hatt FILE is required");
    if (!a.wav.empty() && !a.alsa.empty()) throw cli::UsageError("--wav and --alsa exclude each other");
    if (a.wav.empty() && a.alsa.empty() && a.spectrum.empty())
      throw cli::UsageError("choose an output: --wav OUT.wav, --alsa DEVICE or --spectrum OUT.csv");
    const double delay = static_cast<double>(a.block) / a.rate + 0.002;
    const double sliding = a.seconds - approach_time - settle_time - lift_time - delay;  // [s] in the spectrum
    if (!a.spectrum.empty() && sliding * a.rate < 2.0 * static_cast<double>(psd_segment))
      throw cli::UsageError("--spectrum needs a longer stroke (--seconds) to average a PSD of " +
                            std::to_string(psd_segment) + "-frame segments");
    p.finish();
    check_file(a.hatt, texture::max_hatt_file_bytes);
    return run_with_sink(a);
  });
}
