#pragma once
/// @file wav_sink.hpp
/// WAV files through libsndfile (link hapticfield::vibration_wav): WavSink
/// records what would have been played (a sink that never blocks on a
/// device: VibrationStream paces it, or tests pull it by hand), and
/// read_wav() loads a recorded vibration for a SignalSource or a check.
/// write() is file I/O: it belongs on the audio thread or in a tool, never
/// in a servo tick.

#include <sndfile.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticfield/core/error.hpp"

namespace hapticfield::vibration {

/// Sample format of a written file.
enum class WavFormat : std::uint8_t {
  float32,  ///< IEEE float, exact
  pcm16,    ///< 16-bit integer, what every player reads
};

struct WavConfig {
  double sample_rate{48000.0};  ///< [Hz], 1000..192000 (stored as an integer)
  int channels{1};              ///< 1..8
  WavFormat format{WavFormat::float32};
};

class WavSink {
 public:
  /// @throws std::invalid_argument for a bad configuration; FileError
  ///         naming the file when it cannot be created.
  WavSink(const std::filesystem::path& path, const WavConfig& config) : path_(path.string()), config_(config) {
    if (!(config.sample_rate >= 1000.0 && config.sample_rate <= 192000.0))
      throw std::invalid_argument("WavSink: sample_rate must be within [1000, 192000] [Hz]");
    if (config.channels < 1 || config.channels > 8) throw std::invalid_argument("WavSink: channels must be 1..8");
    SF_INFO info{};
    info.samplerate = static_cast<int>(config.sample_rate + 0.5);
    info.channels = config.channels;
    info.format = SF_FORMAT_WAV | (config.format == WavFormat::float32 ? SF_FORMAT_FLOAT : SF_FORMAT_PCM_16);
    file_ = sf_open(path_.c_str(), SFM_WRITE, &info);
    if (!file_) throw FileError("cannot create '" + path_ + "': " + sf_strerror(nullptr));
  }
  WavSink(const WavSink&) = delete;
  WavSink& operator=(const WavSink&) = delete;
  ~WavSink() { close(); }

  /// Appends interleaved frames; returns the frames written.
  std::size_t write(std::span<const float> frames) noexcept {
    if (!file_) return 0;
    const auto n = static_cast<sf_count_t>(frames.size() / static_cast<std::size_t>(config_.channels));
    const sf_count_t w = sf_writef_float(file_, frames.data(), n);
    frames_ += static_cast<std::uint64_t>(w > 0 ? w : 0);
    return static_cast<std::size_t>(w > 0 ? w : 0);
  }
  [[nodiscard]] bool paced() const noexcept { return false; }
  /// Finishes the header and closes the file (the destructor does it too).
  void close() noexcept {
    if (file_) sf_close(file_);
    file_ = nullptr;
  }
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }

 private:
  std::string path_;
  WavConfig config_;
  SNDFILE* file_{nullptr};
  std::uint64_t frames_{0};
};

/// A sound file's samples, interleaved, as floats in [-1, 1].
struct WavData {
  std::vector<float> samples;
  double sample_rate{0.0};  ///< [Hz]
  int channels{0};
  [[nodiscard]] std::size_t frames() const noexcept {
    return channels > 0 ? samples.size() / static_cast<std::size_t>(channels) : 0;
  }
};

/// Reads a sound file libsndfile knows (WAV, FLAC, ...) of at most max_frames frames.
/// @throws FileError naming the file when it is missing, unreadable, not a
///         sound file or longer than max_frames.
[[nodiscard]] inline WavData read_wav(const std::filesystem::path& path,
                                      std::size_t max_frames = std::size_t{1} << 26) {
  const std::string name = path.string();
  check_file(name, std::uintmax_t{1} << 32);
  SF_INFO info{};
  SNDFILE* f = sf_open(name.c_str(), SFM_READ, &info);
  if (!f) throw FileError("cannot read '" + name + "': " + sf_strerror(nullptr));
  if (info.channels < 1 || info.frames < 0 || static_cast<std::uint64_t>(info.frames) > max_frames) {
    sf_close(f);
    throw FileError("cannot read '" + name + "': no channels or more than " + std::to_string(max_frames) + " frames");
  }
  WavData d;
  d.sample_rate = info.samplerate;
  d.channels = info.channels;
  d.samples.resize(static_cast<std::size_t>(info.frames) * static_cast<std::size_t>(info.channels));
  const sf_count_t got = sf_readf_float(f, d.samples.data(), info.frames);
  sf_close(f);
  d.samples.resize(static_cast<std::size_t>(got > 0 ? got : 0) * static_cast<std::size_t>(info.channels));
  return d;
}

}  // namespace hapticfield::vibration
