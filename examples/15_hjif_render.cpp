// hjif_render FILE.hjif (--wav OUT.wav | --info) [--rate HZ]
//
// Renders an MPEG-I Haptics interchange file (.hjif, ISO/IEC 23090-31) to a
// WAV file: one WAV channel per haptic channel in file order (perception by
// perception), 32-bit float, each sample the channel's signal at i / rate.
// Prints one header line on stderr naming each channel's perception and
// modality, then one "note:" line per field kept without rendering or
// skipped (io/hjif.hpp), so two renderers can be compared sample by sample.
// --info prints the same description on stdout and writes nothing.
//
// Exit status: 0 done, 1 bad input (file, limits), 2 bad usage.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <sndfile.h>

#include "common/cli.hpp"
#include "hapticfield/io/hjif.hpp"
#include "hapticfield/material/band_synthesis.hpp"

using namespace hapticfield;

namespace {

const char* const usage_text =
    "usage: hjif_render FILE.hjif (--wav OUT.wav | --info) [--rate HZ]\n"
    "  renders an MPEG-I Haptics .hjif file: one WAV channel per haptic channel, in file order\n"
    "  --wav OUT.wav   32-bit float WAV; a header line on stderr names each channel's perception and modality\n"
    "  --info          print the channels, their bands and the notes on stdout; write nothing\n"
    "  --rate HZ       output rate [Hz], a whole number in [100, 384000] (default 8000, the reference's)\n"
    "  -h, --help      this text\n"
    "Rendered: Curve (all curve types), VectorialWave (all base signals, AM/FM keyframes, chirps),\n"
    "Transient, WaveletWave (SPIHT blocks); docs/hjif.md lists every field.\n"
    "Limits: 64 MiB per file, nesting 32 levels, 8,000,000 JSON values, 4,000,000 elements per array,\n"
    "1 MiB per string, 3600 s of signal; a file past one is refused with one line naming it.\n"
    "Exit status: 0 done, 1 bad input, 2 bad usage.\n";

struct Args {
  std::string input, wav;
  bool info{false};
  double rate{8000.0};
};

std::string describe(const material::HapticMedia& m) {
  std::string s;
  std::size_t index = 0;
  for (const material::Perception& p : m.perceptions)
    for (const material::Channel& c : p.channels) {
      s += "channel " + std::to_string(index++) + ": perception " + std::to_string(p.id) + " modality " + p.modality +
           " channel " + std::to_string(c.id) + " bands";
      for (const material::Band& b : c.bands)
        s += std::string(" ") + material::band_type_name(b.type);
      if (c.bands.empty()) s += " none";
      s += "\n";
    }
  return s;
}

int run(const Args& a) {
  const io::HjifFile file = io::load_hjif(a.input);
  const material::HapticMedia& m = file.media;
  std::size_t channels = 0;
  for (const auto& p : m.perceptions)
    channels += p.channels.size();
  const double duration = material::media_duration(m);
  char head[256];
  std::snprintf(head, sizeof head, "%s: %zu channel(s), %.6g s, timescale %lld\n", a.input.c_str(), channels, duration,
                static_cast<long long>(m.timescale));
  if (a.info) {
    std::fputs(head, stdout);
    std::fputs(describe(m).c_str(), stdout);
    for (const std::string& n : file.notes)
      std::printf("note: %s\n", n.c_str());
    return cli::exit_ok;
  }
  if (channels == 0) throw FileError(a.input + ": no channel to render");
  const material::RenderedMedia r = material::render_media(m, a.rate);
  // the header line: every channel's perception and modality, in WAV channel order
  std::string header = "hjif_render: " + std::to_string(channels) + " WAV channel(s) at " +
                       std::to_string(static_cast<long long>(a.rate)) + " Hz:";
  for (std::size_t i = 0; i < r.names.size(); ++i)
    header += " [" + std::to_string(i) + "] " + r.names[i] + ";";
  std::fprintf(stderr, "%s\n", header.c_str());
  for (const std::string& n : file.notes)
    std::fprintf(stderr, "note: %s\n", n.c_str());

  SF_INFO info{};
  info.samplerate = static_cast<int>(a.rate);
  info.channels = static_cast<int>(channels);
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  if (channels > 1024) throw FileError(a.input + ": " + std::to_string(channels) + " channels, more than a WAV's 1024");
  SNDFILE* out = sf_open(a.wav.c_str(), SFM_WRITE, &info);
  if (out == nullptr) throw FileError("--wav: cannot write '" + a.wav + "': " + sf_strerror(nullptr));
  const std::size_t frames = r.channels.front().size();
  std::vector<float> block;
  constexpr std::size_t chunk = 4096;
  for (std::size_t f0 = 0; f0 < frames; f0 += chunk) {
    const std::size_t n = std::min(chunk, frames - f0);
    block.assign(n * channels, 0.0f);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < channels; ++c)
        block[i * channels + c] = static_cast<float>(r.channels[c][f0 + i]);
    if (sf_writef_float(out, block.data(), static_cast<sf_count_t>(n)) != static_cast<sf_count_t>(n)) {
      sf_close(out);
      throw FileError("--wav: cannot write '" + a.wav + "': write failed");
    }
  }
  if (sf_close(out) != 0) throw FileError("--wav: cannot write '" + a.wav + "': close failed");
  std::printf("%s: %zu frames of %zu channel(s) at %lld Hz to %s\n", a.input.c_str(), frames, channels,
              static_cast<long long>(a.rate), a.wav.c_str());
  return cli::exit_ok;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("hjif_render", usage_text, argc, argv, [](cli::Parser& p) {
    Args a;
    cli::Input input("FILE.hjif");
    while (p.next()) {
      if (p.is("--wav"))
        a.wav = p.output_file();
      else if (p.is("--info"))
        a.info = true;
      else if (p.is("--rate"))
        a.rate = p.whole(cli::closed(100.0, 384000.0), "Hz");
      else
        p.input_or_unknown(input);
    }
    a.input = input.required();
    if (a.wav.empty() && !a.info) throw cli::UsageError("--wav OUT.wav or --info is required");
    p.finish();
    return run(a);
  });
}
