#pragma once
/// @file playback_clock.hpp
/// PlaybackClock: video time from the servo loop's clock, with pause, seek,
/// a playback rate and looping. The controls may be called from any thread
/// (atomics); at() runs on the servo thread: noexcept, no allocation, no lock.
///
/// A run starts at the configured start: at the first tick, at the first
/// tick after restart(), and at a tick whose loop time goes back (the loop's
/// clock restarted, a second run from 0): each starts a new epoch, so a
/// worker that follows epoch() seeks there.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace hapticfield {

inline constexpr double max_playback_rate = 16.0;  ///< [video s per loop s]

static_assert(std::atomic<double>::is_always_lock_free, "the servo thread reads playback controls without a lock");

struct PlaybackConfig {
  double rate = 1.0;                                          ///< video seconds per loop second, in (0, 16]
  double start = 0.0;                                         ///< video time at the first tick [s], at most duration
  bool loop = false;                                          ///< start again at 0 after the end
  double duration = std::numeric_limits<double>::infinity();  ///< length of the video [s]

  /// @throws std::invalid_argument naming the bad value.
  void validate() const {
    if (!std::isfinite(rate) || rate <= 0.0 || rate > max_playback_rate)
      throw std::invalid_argument("PlaybackConfig: rate must be in (0, 16]");
    if (!std::isfinite(start) || start < 0.0) throw std::invalid_argument("PlaybackConfig: start must be >= 0 [s]");
    if (!(duration > 0.0)) throw std::invalid_argument("PlaybackConfig: duration must be positive [s]");
    if (start > duration)
      throw std::invalid_argument("PlaybackConfig: start " + std::to_string(start) +
                                  " s is past the end of the video (" + std::to_string(duration) + " s)");
  }
};

class PlaybackClock {
 public:
  explicit PlaybackClock(const PlaybackConfig& config = {}) : config_(config) {
    config_.validate();
    rate_.store(config.rate);
  }

  // ---- controls: any thread ----
  void pause() noexcept { paused_.store(true); }
  void resume() noexcept { paused_.store(false); }
  /// Jumps to video time t [s] at the next tick (clamped to [0, duration]).
  void seek(double t) noexcept {
    if (!std::isfinite(t)) return;
    seek_to_.store(std::clamp(t, 0.0, config_.duration));
    seek_serial_.fetch_add(1);
  }
  /// Starts again at the configured start at the next tick (a new epoch).
  void restart() noexcept { restart_serial_.fetch_add(1, std::memory_order_release); }
  /// @throws std::invalid_argument for a rate outside (0, 16].
  void set_rate(double rate) {
    if (!std::isfinite(rate) || rate <= 0.0 || rate > max_playback_rate)
      throw std::invalid_argument("PlaybackClock: rate must be in (0, 16]");
    rate_.store(rate);
  }

  // ---- servo thread ----
  /// Video time [s] at loop time `now` [s].
  [[nodiscard]] double at(double now) noexcept {
    if (!std::isfinite(now)) return video_;
    const bool paused = paused_.load(std::memory_order_relaxed);
    const double rate = rate_.load(std::memory_order_relaxed);
    const std::uint32_t serial = seek_serial_.load(std::memory_order_acquire);
    const std::uint32_t restart = restart_serial_.load(std::memory_order_acquire);
    if (anchored_ && (restart != applied_restart_ || now < last_now_)) {  // a new run: from the start
      anchored_ = false;
      epoch_.fetch_add(1, std::memory_order_release);
    }
    applied_restart_ = restart;
    last_now_ = now;
    if (!anchored_) {
      anchored_ = true;
      anchor_loop_ = now;
      anchor_video_ = config_.start;
      applied_paused_ = paused;
      applied_rate_ = rate;
    }
    if (paused != applied_paused_ || rate != applied_rate_) {  // re-anchor where we are
      anchor_video_ = video_;
      anchor_loop_ = now;
      applied_paused_ = paused;
      applied_rate_ = rate;
    }
    if (serial != applied_serial_) {
      applied_serial_ = serial;
      anchor_video_ = seek_to_.load(std::memory_order_relaxed);
      anchor_loop_ = now;
      epoch_.fetch_add(1, std::memory_order_release);
    }
    double t = anchor_video_ + (applied_paused_ ? 0.0 : applied_rate_ * (now - anchor_loop_));
    if (t >= config_.duration) {
      if (config_.loop) {
        t = std::fmod(t, config_.duration);
        anchor_video_ = t;
        anchor_loop_ = now;
        epoch_.fetch_add(1, std::memory_order_release);
      } else {
        t = config_.duration;
      }
    }
    video_ = t;
    return t;
  }

  /// Counts seeks and loops (a jump in video time); any thread.
  [[nodiscard]] std::uint32_t epoch() const noexcept { return epoch_.load(std::memory_order_acquire); }
  [[nodiscard]] bool paused() const noexcept { return paused_.load(); }
  [[nodiscard]] const PlaybackConfig& config() const noexcept { return config_; }

 private:
  PlaybackConfig config_;
  std::atomic<bool> paused_{false};
  std::atomic<double> rate_{1.0};
  std::atomic<double> seek_to_{0.0};
  std::atomic<std::uint32_t> seek_serial_{0};
  std::atomic<std::uint32_t> restart_serial_{0};
  std::atomic<std::uint32_t> epoch_{0};
  // servo-thread state
  bool anchored_ = false;
  std::uint32_t applied_restart_ = 0;
  double last_now_ = 0.0;  ///< the last tick's loop time [s]
  bool applied_paused_ = false;
  double applied_rate_ = 1.0;
  std::uint32_t applied_serial_ = 0;
  double anchor_loop_ = 0.0;
  double anchor_video_ = 0.0;
  double video_ = 0.0;
};

}  // namespace hapticfield
