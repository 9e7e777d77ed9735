#pragma once
/// @file stream.hpp
/// Where the rendered vibration goes, and the thread that drives it.
///
/// A sink is anything with `std::size_t write(std::span<const float>)`
/// (interleaved frames in, frames taken out) and `bool paced() const`:
/// true when write() blocks at the device's rate (ALSA), false when it
/// returns at once (a file, NullSink), in which case VibrationStream paces
/// the blocks itself on the monotonic clock. The sinks: NullSink (here),
/// WavSink (wav_sink.hpp, libsndfile), AlsaSink (alsa_sink.hpp, ALSA).
///
/// VibrationStream runs one block after another: render (never waits for
/// the servo thread), write. pull() does one block by hand, which is how
/// tests drive the audio path with no thread and no clock.

#include <atomic>
#include <chrono>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <thread>
#include <vector>

namespace hapticfield::vibration {

/// Where frames go.
template <class K>
concept AudioSink = requires(K& sink, const K& csink, std::span<const float> frames) {
  { sink.write(frames) }
  noexcept->std::same_as<std::size_t>;
  { csink.paced() }
  noexcept->std::same_as<bool>;
};

/// What renders frames (VibrationRenderer, or a user's own).
template <class R>
concept AudioCallback = requires(R& callback, const R& ccallback, std::span<float> frames) {
  { callback.render(frames) }
  noexcept;
  { ccallback.channels() }
  noexcept->std::convertible_to<int>;
  { ccallback.sample_rate() }
  noexcept->std::convertible_to<double>;
};

/// Discards every frame and counts them.
class NullSink {
 public:
  explicit NullSink(int channels = 1) : channels_(channels) {
    if (channels < 1) throw std::invalid_argument("NullSink: channels must be >= 1");
  }
  std::size_t write(std::span<const float> frames) noexcept {
    const std::size_t n = frames.size() / static_cast<std::size_t>(channels_);
    frames_ += n;
    return n;
  }
  [[nodiscard]] bool paced() const noexcept { return false; }
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }

 private:
  int channels_;
  std::uint64_t frames_{0};
};

/// Blocks of block_frames frames, rendered and written one after another.
template <AudioCallback R, AudioSink K>
class VibrationStream {
 public:
  /// @throws std::invalid_argument for block_frames outside 1..65536.
  VibrationStream(R& callback, K& sink, std::size_t block_frames) : callback_(&callback), sink_(&sink) {
    if (block_frames < 1 || block_frames > 65536)
      throw std::invalid_argument("VibrationStream: block_frames must be within 1..65536");
    buffer_.assign(block_frames * static_cast<std::size_t>(callback.channels()), 0.0f);
  }
  VibrationStream(const VibrationStream&) = delete;
  VibrationStream& operator=(const VibrationStream&) = delete;
  ~VibrationStream() { stop(); }

  /// Renders one block and writes it; returns the frames the sink took.
  /// Not while the thread runs.
  std::size_t pull() noexcept {
    callback_->render(buffer_);
    const std::size_t n = sink_->write(buffer_);
    blocks_.fetch_add(1, std::memory_order_relaxed);
    if (n < block_frames()) short_writes_.fetch_add(1, std::memory_order_relaxed);
    return n;
  }

  /// Starts the audio thread (a paced sink sets the rate; otherwise blocks
  /// are due every block_frames / sample_rate on the monotonic clock).
  void start() {
    if (thread_.joinable()) return;
    stop_.store(false, std::memory_order_relaxed);
    thread_ = std::thread([this] { run(); });
  }
  /// Stops the thread after its current block and joins it.
  void stop() noexcept {
    stop_.store(true, std::memory_order_relaxed);
    if (thread_.joinable()) thread_.join();
  }

  [[nodiscard]] std::size_t block_frames() const noexcept {
    return buffer_.size() / static_cast<std::size_t>(callback_->channels());
  }
  [[nodiscard]] std::uint64_t blocks() const noexcept { return blocks_.load(std::memory_order_relaxed); }
  /// Blocks the sink did not take whole (a device error; see the sink).
  [[nodiscard]] std::uint64_t short_writes() const noexcept { return short_writes_.load(std::memory_order_relaxed); }

 private:
  void run() noexcept {
    using Clock = std::chrono::steady_clock;  // monotonic; absolute sleeps, so no drift
    const auto period = std::chrono::nanoseconds(
        static_cast<std::int64_t>(1e9 * static_cast<double>(block_frames()) / callback_->sample_rate()));
    auto due = Clock::now();
    while (!stop_.load(std::memory_order_relaxed)) {
      pull();
      if (!sink_->paced()) {
        due += period;
        std::this_thread::sleep_until(due);
      }
    }
  }

  R* callback_;
  K* sink_;
  std::vector<float> buffer_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> blocks_{0};
  std::atomic<std::uint64_t> short_writes_{0};
};

}  // namespace hapticfield::vibration
