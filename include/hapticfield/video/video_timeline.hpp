#pragma once
/// @file video_timeline.hpp
/// VideoTimeline: the same forces as VideoField, offline and synchronous:
/// for video times that never decrease, prepares every frame in order on
/// the calling thread and evaluates the window that brackets each time.
/// Used by `tangible_video --probes` and by tests as the reference.

#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include <glm/vec2.hpp>

#include "hapticfield/video/frame_preparer.hpp"
#include "hapticfield/video/frame_window.hpp"
#include "hapticfield/video/video_field.hpp"
#include "hapticfield/video/video_source.hpp"

namespace hapticfield {

class VideoTimeline {
 public:
  /// @throws std::invalid_argument for a bad mask, denoise or fade setting,
  ///         or frames smaller than the mask.
  VideoTimeline(VideoSource& source, const PrepareConfig& prepare, double fade = default_cut_fade)
      : source_(source), preparer_(prepare), builder_(fade) {
    preparer_.check_frame_size(source.width(), source.height());
  }

  /// Normalised force at image position (x, y) [px] at video time t [s]
  /// (a black/white edge = 1, y down). Times must not decrease.
  /// @throws std::invalid_argument for a time that goes back;
  ///         std::invalid_argument from preparation (a frame of another size).
  [[nodiscard]] glm::dvec2 at(double t, double x, double y) {
    advance(t);
    return window_ ? window_->at(t, x, y) : glm::dvec2{0.0};
  }

  /// Prepares frames until the window brackets video time t [s].
  void advance(double t) {
    if (t < last_t_) throw std::invalid_argument("VideoTimeline: video times must not decrease");
    last_t_ = t;
    while (!ended_ && (!window_ || window_->t1 <= t))
      step();
  }

  [[nodiscard]] const std::vector<SceneCut>& cuts() const noexcept { return cuts_; }
  [[nodiscard]] long prepared() const noexcept { return prepared_; }
  [[nodiscard]] bool ended() const noexcept { return ended_; }
  /// The window in use (none before the first time).
  [[nodiscard]] const std::optional<FrameWindow>& window() const noexcept { return window_; }
  /// The last prepared frame's gray levels after denoising (CV_32F).
  [[nodiscard]] const cv::Mat& last_gray() const noexcept { return preparer_.last_gray(); }

  /// Prepares the rest of the stream (to find every cut).
  void run_to_end() {
    while (!ended_)
      step();
  }

 private:
  void step() {
    cv::Mat image;
    long index = 0;
    if (!source_.read(image, index)) {
      ended_ = true;
      if (auto w = builder_.last()) window_ = std::move(w);
      return;
    }
    auto frame = preparer_.prepare(image, index, source_.time_of(index));
    ++prepared_;
    if (frame->cut) cuts_.push_back({frame->index, frame->time});
    if (auto w = builder_.push(std::move(frame))) {
      window_ = std::move(w);
    }
  }

  VideoSource& source_;
  FramePreparer preparer_;
  WindowBuilder builder_;
  std::optional<FrameWindow> window_;
  std::vector<SceneCut> cuts_;
  double last_t_ = -1e300;
  long prepared_ = 0;
  bool ended_ = false;
};

}  // namespace hapticfield
