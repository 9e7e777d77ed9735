#pragma once
/// @file video_player.hpp
/// The viewer's video: builds the VideoField the servo loop feels (through
/// the viewer's LiveField, like every other field), shows the frame being
/// felt, and serves the playback keys (pause, seek) and the parameter keys
/// (a new VideoField with another PrepareConfig, starting where the old one
/// was).
///
/// Viewer thread only: it allocates, opens files and may throw. The servo
/// thread only ever calls the published field's force(). Lifetime: the
/// VideoField lives in the AnyField that start() returns, which the viewer
/// publishes into its LiveField; a LiveField destroys replaced fields on the
/// publishing (viewer) thread, never in a tick, and never the newest one. So
/// the player's pointer to the newest VideoField stays valid until the next
/// publish, and the player forgets it (stop(), or start() of the next one)
/// before the viewer publishes anything else. A retired field's worker is
/// stopped at once; the field itself (its last window) may serve a tick or
/// two more until the loop picks up the new one.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "hapticfield/core/any_field.hpp"
#include "hapticfield/core/error.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/video/video_field.hpp"
#include "hapticfield/video/video_source.hpp"
#include "view/scene.hpp"

namespace hapticfield::view {

struct VideoPlayerConfig {
  double speed{1.0};                             ///< video seconds per loop second, in (0, 16]
  double from{0.0};                              ///< video time at the start [s], at most the video's length
  bool loop{false};                              ///< start again at 0 after the end
  double fade{default_cut_fade};                 ///< fade out and in across a scene cut [s]
  double seek_step{5.0};                         ///< what one seek key moves [s]
  int display_frames{8};                         ///< decoded frames the worker keeps for display
  std::uint64_t max_pixels{default_max_pixels};  ///< largest frame decoded [px] (VideoSourceConfig)
};

/// What the status panel shows about the video.
struct VideoStatus {
  double time{0.0};      ///< video time [s] (the servo loop's, while the video field is felt)
  double duration{0.0};  ///< [s], infinity when unknown
  long frame{-1};        ///< index of the frame shown
  bool paused{false};
  long dropped{0};    ///< frames the worker skipped (it lagged behind the video time)
  long cuts{0};       ///< scene cuts detected
  std::string error;  ///< the worker's error, if it stopped on one
};

class VideoPlayer {
 public:
  /// Opens `path` (anything VideoSource opens) to learn its size, rate and
  /// length, and decodes the frame at config.from for the first view.
  /// @throws FileError / VideoError for a missing or undecodable video;
  ///         std::invalid_argument for a bad speed, start or fade.
  VideoPlayer(std::string path, const VideoPlayerConfig& config) : path_(std::move(path)), config_(config) {
    PlaybackConfig{.rate = config.speed, .start = config.from}.validate();
    if (!std::isfinite(config.fade) || config.fade < 0.0 || config.fade > 10.0)
      throw std::invalid_argument("VideoPlayer: fade must be in [0, 10] s");
    VideoSource source(path_, source_config());
    fps_ = source.fps();
    duration_ = source.duration();
    frame_count_ = source.frame_count();
    if (config.from > duration_)
      throw Error("--from " + std::to_string(config.from) + " s is past the end of '" + path_ + "' (" +
                  std::to_string(duration_) + " s)");
    long index = 0;
    if (config.from > 0.0) source.seek(static_cast<long>(std::floor(config.from * fps_ + 1e-9)));
    if (!source.read(shown_, index))
      throw VideoError("cannot decode '" + path_ + "' at " + std::to_string(config.from) + " s");
    shown_index_ = index;
    time_ = config.from;
    last_.time = time_;
    last_.duration = duration_;
  }
  VideoPlayer(const VideoPlayer&) = delete;
  VideoPlayer& operator=(const VideoPlayer&) = delete;
  ~VideoPlayer() = default;  // the LiveField owns (and joins) the fields

  /// A new VideoField for `scene` (mask, size, border, video denoise mode,
  /// gain) in `mapping`, starting at the current video time, paused when
  /// playback is paused. The previous one's worker is stopped: publish the
  /// returned field at once. When it throws, the previous one plays on.
  /// @throws as VideoField and VideoSource.
  [[nodiscard]] AnyField start(const SceneConfig& scene, const PlaneMapping& mapping) {
    VideoFieldConfig c;
    c.prepare.tangible.mask = scene.mask;
    c.prepare.tangible.size = scene.size;
    c.prepare.tangible.border = scene.border;
    c.prepare.denoise.mode = scene.video_denoise;
    c.playback.rate = config_.speed;
    c.playback.start = std::clamp(time(), 0.0, duration_);
    c.playback.loop = config_.loop;
    c.fade = config_.fade;
    c.gain = scene.gain;
    c.display_frames = config_.display_frames;
    VideoField field(std::make_unique<VideoSource>(path_, source_config()), mapping, std::move(c));
    if (paused_) field.playback().pause();
    AnyField any(std::move(field));
    VideoField* fresh = any.target<VideoField>();
    stop();
    current_ = fresh;
    return any;
  }

  /// The viewer feels something else now: the worker stops, the video time
  /// and counters are kept for the next start().
  void stop() {
    if (!current_) return;
    (void)status();
    time_ = last_.time;
    dropped_before_ = last_.dropped;
    cuts_before_ = last_.cuts;
    current_->stop();
    current_ = nullptr;
  }

  /// True while a VideoField from start() is the one published.
  [[nodiscard]] bool playing() const noexcept { return current_ != nullptr; }

  /// Video time [s]: the servo loop's latest while playing, else where it stopped.
  [[nodiscard]] double time() const { return current_ ? current_->statistics().video_time : time_; }

  /// Pauses or resumes playback (also for the next start()); returns paused.
  bool toggle_pause() {
    paused_ = !paused_;
    if (current_) {
      if (paused_)
        current_->playback().pause();
      else
        current_->playback().resume();
    }
    return paused_;
  }
  [[nodiscard]] bool paused() const noexcept { return paused_; }

  /// Seeks by `steps` seek steps (negative: back), clamped to [0, duration];
  /// returns the target [s]. Applied at the loop's next tick.
  double seek_by(int steps) {
    const double t = std::clamp(time() + steps * config_.seek_step, 0.0, duration_);
    if (current_)
      current_->playback().seek(t);
    else
      time_ = t;
    return t;
  }

  /// The frame being felt: the newest decoded frame whose time is at most
  /// the loop's video time (the last one shown when none is new, or when the
  /// video field is not the one felt).
  [[nodiscard]] const cv::Mat& frame() {
    if (current_) {
      if (std::optional<DisplayFrame> f = current_->display_frame(current_->statistics().video_time)) {
        shown_ = f->image;
        shown_index_ = f->index;
      }
    }
    return shown_;
  }

  /// Waits up to `timeout` for the frame of the current video time to be
  /// decoded, then returns frame() (for a one-off picture, --screenshot).
  const cv::Mat& settle(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (current_ && shown_index_ != expected_index() && std::chrono::steady_clock::now() < until) {
      (void)frame();
      if (shown_index_ != expected_index()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return frame();
  }

  /// Index of the frame whose time span holds the current video time.
  [[nodiscard]] long expected_index() const {
    const long k = static_cast<long>(std::floor(time() * fps_ + 1e-9));
    return frame_count_ > 0 ? std::min(k, frame_count_ - 1) : k;
  }

  [[nodiscard]] VideoStatus status() {
    if (current_) {
      const VideoStatistics s = current_->statistics();
      last_.time = s.video_time;
      last_.dropped = dropped_before_ + s.dropped;
      last_.cuts = cuts_before_ + s.cuts;
      last_.error = current_->error();
    } else {
      last_.time = time_;
    }
    last_.duration = duration_;
    last_.frame = shown_index_;
    last_.paused = paused_;
    return last_;
  }

  [[nodiscard]] VideoSourceConfig source_config() const { return VideoSourceConfig{.max_pixels = config_.max_pixels}; }

  [[nodiscard]] double fps() const noexcept { return fps_; }
  [[nodiscard]] double duration() const noexcept { return duration_; }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] const VideoPlayerConfig& config() const noexcept { return config_; }

 private:
  std::string path_;
  VideoPlayerConfig config_;
  double fps_{25.0};
  double duration_{HUGE_VAL};
  long frame_count_{0};
  VideoField* current_{nullptr};  ///< the newest published video field (owned by the LiveField)
  double time_{0.0};              ///< video time while no video field is felt [s]
  bool paused_{false};
  long dropped_before_{0}, cuts_before_{0};  ///< counted by retired fields
  cv::Mat shown_;
  long shown_index_{-1};
  VideoStatus last_;
};

}  // namespace hapticfield::view
