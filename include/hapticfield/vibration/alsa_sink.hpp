#pragma once
/// @file alsa_sink.hpp
/// AlsaSink: vibration out through an ALSA PCM (libasound; link
/// hapticfield::vibration_alsa). Any PCM name works: "default", "hw:1,0",
/// "plughw:1", or the plugins the tests use: "null" (discards) and
/// "file:'/tmp/out.raw',raw" (writes the raw samples, then discards).
///
/// Latency knob: period_frames x periods is the device buffer; write()
/// blocks while it is full, so a paced stream runs as many frames ahead of
/// the actuator as the buffer holds. Xruns (the buffer ran dry) are
/// recovered with snd_pcm_recover and counted.
///
/// Never run on a real sound card in this project's CI (no card there):
/// only the null and file plugins have been exercised.

#include <alsa/asoundlib.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticfield/core/error.hpp"

namespace hapticfield::vibration {

/// An audio device that cannot be opened or set up as asked.
class AudioError : public Error {
 public:
  using Error::Error;
};

/// Sample format on the wire.
enum class AlsaFormat : std::uint8_t {
  float32,  ///< FLOAT_LE
  s16,      ///< S16_LE, what every card takes
};

struct AlsaConfig {
  std::string device{"default"};  ///< PCM name
  unsigned sample_rate{48000};    ///< [Hz], 8000..192000; the device must take it exactly
  int channels{1};                ///< 1..8
  AlsaFormat format{AlsaFormat::s16};
  unsigned period_frames{256};  ///< frames per device period (the stream's block)
  unsigned periods{2};          ///< periods in the device buffer, >= 2

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    if (sample_rate < 8000 || sample_rate > 192000)
      throw std::invalid_argument("AlsaConfig: sample_rate must be within [8000, 192000] [Hz]");
    if (channels < 1 || channels > 8) throw std::invalid_argument("AlsaConfig: channels must be within 1..8");
    if (period_frames < 16 || period_frames > 65536)
      throw std::invalid_argument("AlsaConfig: period_frames must be within 16..65536");
    if (periods < 2 || periods > 64) throw std::invalid_argument("AlsaConfig: periods must be within 2..64");
  }
};

class AlsaSink {
 public:
  /// Opens and sets up the PCM for blocking interleaved playback.
  /// @throws std::invalid_argument for a bad configuration; AudioError
  ///         naming the device and ALSA's reason when it cannot be opened
  ///         or does not take the rate, format or channels.
  explicit AlsaSink(const AlsaConfig& config) : config_((config.validate(), config)) {
    check(snd_pcm_open(&pcm_, config_.device.c_str(), SND_PCM_STREAM_PLAYBACK, 0), "open");
    try {
      snd_pcm_hw_params_t* hw = nullptr;
      snd_pcm_hw_params_alloca(&hw);
      check(snd_pcm_hw_params_any(pcm_, hw), "read the hardware parameters");
      check(snd_pcm_hw_params_set_access(pcm_, hw, SND_PCM_ACCESS_RW_INTERLEAVED), "set interleaved access");
      check(snd_pcm_hw_params_set_format(
                pcm_, hw, config_.format == AlsaFormat::s16 ? SND_PCM_FORMAT_S16_LE : SND_PCM_FORMAT_FLOAT_LE),
            "set the sample format");
      check(snd_pcm_hw_params_set_channels(pcm_, hw, static_cast<unsigned>(config_.channels)), "set the channels");
      check(snd_pcm_hw_params_set_rate_resample(pcm_, hw, 0), "turn resampling off");
      check(snd_pcm_hw_params_set_rate(pcm_, hw, config_.sample_rate, 0), "set the rate (exactly)");
      snd_pcm_uframes_t period = config_.period_frames;
      check(snd_pcm_hw_params_set_period_size_near(pcm_, hw, &period, nullptr), "set the period size");
      snd_pcm_uframes_t buffer = period * config_.periods;
      check(snd_pcm_hw_params_set_buffer_size_near(pcm_, hw, &buffer), "set the buffer size");
      check(snd_pcm_hw_params(pcm_, hw), "apply the hardware parameters");
      period_ = period;
      buffer_ = buffer;
      snd_pcm_sw_params_t* sw = nullptr;
      snd_pcm_sw_params_alloca(&sw);
      check(snd_pcm_sw_params_current(pcm_, sw), "read the software parameters");
      check(snd_pcm_sw_params_set_start_threshold(pcm_, sw, period_), "set the start threshold");
      check(snd_pcm_sw_params_set_avail_min(pcm_, sw, period_), "set avail_min");
      check(snd_pcm_sw_params(pcm_, sw), "apply the software parameters");
      check(snd_pcm_prepare(pcm_), "prepare");
      s16_.resize(static_cast<std::size_t>(period_ * config_.periods) * static_cast<std::size_t>(config_.channels));
    } catch (...) {
      snd_pcm_close(pcm_);
      throw;
    }
  }
  AlsaSink(const AlsaSink&) = delete;
  AlsaSink& operator=(const AlsaSink&) = delete;
  /// Plays out what is buffered (snd_pcm_drain), then closes.
  ~AlsaSink() {
    snd_pcm_drain(pcm_);
    snd_pcm_close(pcm_);
  }

  /// Writes interleaved frames, blocking while the device buffer is full;
  /// returns the frames written (fewer only on an unrecoverable error).
  std::size_t write(std::span<const float> frames) noexcept {
    const auto ch = static_cast<std::size_t>(config_.channels);
    std::size_t done = 0;
    const std::size_t total = frames.size() / ch;
    while (done < total) {
      std::size_t n = total - done;
      const void* data = frames.data() + done * ch;
      if (config_.format == AlsaFormat::s16) {
        if (n * ch > s16_.size()) n = s16_.size() / ch;
        for (std::size_t i = 0; i < n * ch; ++i) {
          const float v = frames[done * ch + i];
          const float c = v > 1.0f ? 1.0f : (v < -1.0f ? -1.0f : v);
          s16_[i] = static_cast<std::int16_t>(std::lrint(c * 32767.0f));
        }
        data = s16_.data();
      }
      const snd_pcm_sframes_t w = snd_pcm_writei(pcm_, data, n);
      if (w >= 0) {
        done += static_cast<std::size_t>(w);
        continue;
      }
      if (w == -EPIPE) ++xruns_;
      if (snd_pcm_recover(pcm_, static_cast<int>(w), 1) < 0) {
        ++errors_;
        break;
      }
    }
    frames_ += done;
    return done;
  }
  [[nodiscard]] bool paced() const noexcept { return true; }

  /// Frames queued ahead of the output now (snd_pcm_delay), 0 if unknown.
  [[nodiscard]] std::size_t delay_frames() const noexcept {
    snd_pcm_sframes_t d = 0;
    return snd_pcm_delay(pcm_, &d) == 0 && d > 0 ? static_cast<std::size_t>(d) : 0;
  }
  [[nodiscard]] std::size_t period_frames() const noexcept { return period_; }
  [[nodiscard]] std::size_t buffer_frames() const noexcept { return buffer_; }
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }
  [[nodiscard]] std::uint64_t xruns() const noexcept { return xruns_; }
  [[nodiscard]] std::uint64_t errors() const noexcept { return errors_; }
  [[nodiscard]] const AlsaConfig& config() const noexcept { return config_; }

 private:
  void check(int rc, const char* what) const {
    if (rc < 0) throw AudioError("ALSA device '" + config_.device + "': cannot " + what + ": " + snd_strerror(rc));
  }

  AlsaConfig config_;
  snd_pcm_t* pcm_{nullptr};
  std::size_t period_{0};
  std::size_t buffer_{0};
  std::vector<std::int16_t> s16_;
  std::uint64_t frames_{0};
  std::uint64_t xruns_{0};
  std::uint64_t errors_{0};
};

}  // namespace hapticfield::vibration
