#pragma once
/// @file frame_window.hpp
/// The force of a video between two frames: VideoFrame (one prepared frame),
/// FrameWindow (the two frames that bracket the video time, and the fade
/// across a scene cut) and WindowBuilder (windows from frames in order).
///
/// Between cuts the force at video time t is the linear blend
///   F(t) = (1 - a) F_k + a F_(k+1),  a = (t - t_k) / (t_(k+1) - t_k)
/// (for a constant frame rate, a = t fps - k). Across a cut at t_c the force
/// never blends two unrelated pictures: it holds F_k up to t_c, fades it
/// out linearly over [t_c, t_c + T/2] and fades the new scene in over
/// [t_c + T/2, t_c + T] (T = the fade time). The first frame after the start
/// or a seek fades in the same way from zero.
///
/// Which clock a fade runs on is the caller's: at(t, x, y) runs it on video
/// time (the offline VideoTimeline, where video time is the only clock);
/// at(t, since_fade, x, y) takes the time since the fade began on another
/// clock. VideoField passes its loop time, so that a fade always completes
/// in T of loop time: while playback is paused, at a file's end, at any rate.
/// Each fade carries a serial number (FrameWindow::fade_serial) so a caller
/// can tell when a new one begins.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>

#include <glm/vec2.hpp>

#include "hapticfield/kernels/tangible_image.hpp"

namespace hapticfield {

/// Default fade across a scene cut [s]: out over the first half, in over the second.
inline constexpr double default_cut_fade = 0.1;

/// One prepared frame: its tables and where it sits in the video.
struct VideoFrame {
  long index = 0;           ///< frame number in the source, from 0
  double time = 0.0;        ///< timestamp [s of video time]
  bool cut = false;         ///< first frame of a new scene
  double difference = 0.0;  ///< scene-cut measure against the frame before [gray levels]
  TangibleImage image;      ///< the frame's force source (normalised, a black/white edge = 1)
};

/// The frames that bracket video time t, and the fade state. Its at() is on
/// the servo path: noexcept, no allocation.
struct FrameWindow {
  std::shared_ptr<const VideoFrame> current;                   ///< frame k (never null in a published window)
  std::shared_ptr<const VideoFrame> next;                      ///< frame k + 1, or null at the end of the stream
  std::shared_ptr<const VideoFrame> before_cut;                ///< last frame of the old scene (felt while fading out)
  double t0 = 0.0;                                             ///< when current is fully felt [s of video time]
  double t1 = std::numeric_limits<double>::infinity();         ///< when next is fully felt [s]
  double cut_time = -std::numeric_limits<double>::infinity();  ///< start of the last fade [s]
  double fade = default_cut_fade;                              ///< fade time T [s]
  double max_hold = 0.5;          ///< past t1 + max_hold (a stalled source) the force is zero [s]
  std::uint32_t fade_serial = 0;  ///< the fade that began at cut_time: a new number for each start, seek or cut

  /// Normalised force at image position (x, y) [px] at video time t [s],
  /// the fade on video time (since_fade = t - cut_time).
  [[nodiscard]] glm::dvec2 at(double t, double x, double y) const noexcept { return at(t, t - cut_time, x, y); }

  /// Normalised force at image position (x, y) [px] at video time t [s],
  /// `since_fade` [s] after the last fade began on the caller's clock
  /// (negative counts as 0; infinite: no fade; NaN: zero force).
  [[nodiscard]] glm::dvec2 at(double t, double since_fade, double x, double y) const noexcept {
    if (!current || !std::isfinite(t) || std::isnan(since_fade)) return glm::dvec2{0.0};
    if (t < t0 - 1e-9 || t > held_until()) return glm::dvec2{0.0};  // a seek away, or a stalled source
    const double half = 0.5 * fade;
    const double s = std::max(since_fade, 0.0);
    if (half > 0.0 && s < fade) {
      if (s < half) {
        if (!before_cut) return glm::dvec2{0.0};
        const double w = std::clamp(1.0 - s / half, 0.0, 1.0);
        return w * before_cut->image.at(x, y);
      }
      return std::clamp((s - half) / half, 0.0, 1.0) * blended(t, x, y);
    }
    return blended(t, x, y);
  }

  /// The last video time this window is felt at: past it the source has
  /// stalled [s].
  [[nodiscard]] double held_until() const noexcept { return t1 + max_hold; }

  /// The blend weight a of `next` at video time t, in [0, 1].
  [[nodiscard]] double weight(double t) const noexcept {
    if (!next || next->cut || !(t1 > t0)) return 0.0;
    return std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
  }

 private:
  [[nodiscard]] glm::dvec2 blended(double t, double x, double y) const noexcept {
    const double a = weight(t);
    if (a <= 0.0) return current->image.at(x, y);
    return (1.0 - a) * current->image.at(x, y) + a * next->image.at(x, y);
  }
};

/// Turns prepared frames, in order, into windows: after frame k + 1 is
/// pushed, the window (k, k + 1) comes out.
class WindowBuilder {
 public:
  /// @param fade  fade time across a cut [s], in [0, 10]
  /// @throws std::invalid_argument for a fade outside [0, 10] s.
  explicit WindowBuilder(double fade = default_cut_fade) : fade_(fade) {
    if (!std::isfinite(fade) || fade < 0.0 || fade > 10.0)
      throw std::invalid_argument("WindowBuilder: the fade time must be in [0, 10] s");
  }

  /// Frame `frame` follows the last one. Returns the window that starts at
  /// the previous frame (none for the first frame after a reset).
  std::optional<FrameWindow> push(std::shared_ptr<const VideoFrame> frame) {
    std::optional<FrameWindow> out;
    if (current_) out = window(current_, frame, current_->time, frame->time);
    previous_ = std::exchange(current_, std::move(frame));
    return out;
  }

  /// The window of the last frame, held to the end (end of the stream).
  [[nodiscard]] std::optional<FrameWindow> last() {
    if (!current_) return std::nullopt;
    return window(current_, nullptr, current_->time, std::numeric_limits<double>::infinity());
  }

  /// A live source: `frame` is blended in from the last one over
  /// [now, now + period] (one frame late); a cut frame fades in after the
  /// old scene fades out, from now on. Returns that window.
  FrameWindow push_live(std::shared_ptr<const VideoFrame> frame, double now, double period) {
    const double forever = std::numeric_limits<double>::infinity();
    if (!current_ || frame->cut) {
      if (current_) {  // a cut: the old scene fades out from now
        before_cut_ = current_;
        cut_time_ = now;
        started_ = true;
        ++fade_serial_;
      }
      previous_ = std::exchange(current_, std::move(frame));
      return window(current_, nullptr, now, forever, true);
    }
    FrameWindow w = window(current_, frame, now, now + period, true);
    previous_ = std::exchange(current_, std::move(frame));
    return w;
  }

  /// Forgets every frame (a seek, a restart): the next frame fades in.
  void reset() noexcept {
    previous_ = nullptr;
    current_ = nullptr;
    before_cut_ = nullptr;
    cut_time_ = -std::numeric_limits<double>::infinity();
    started_ = false;
  }

  [[nodiscard]] double fade() const noexcept { return fade_; }

 private:
  FrameWindow window(const std::shared_ptr<const VideoFrame>& current, std::shared_ptr<const VideoFrame> next,
                     double t0, double t1, bool live = false) {
    if (!started_) {  // the very first frame: fade in from zero
      started_ = true;
      before_cut_ = nullptr;
      cut_time_ = t0;
      ++fade_serial_;
    } else if (!live && current->cut && previous_) {
      before_cut_ = previous_;
      cut_time_ = t0;
      ++fade_serial_;
    }
    // (the old scene is kept until the next cut or reset: a fade runs on
    // the caller's clock and may begin any video time after the cut, when
    // the worker lagged)
    FrameWindow w;
    w.current = current;
    w.next = std::move(next);
    w.before_cut = before_cut_;
    w.t0 = t0;
    w.t1 = t1;
    w.cut_time = cut_time_;
    w.fade = fade_;
    w.fade_serial = fade_serial_;
    return w;
  }

  double fade_;
  std::shared_ptr<const VideoFrame> previous_;
  std::shared_ptr<const VideoFrame> current_;
  std::shared_ptr<const VideoFrame> before_cut_;
  double cut_time_ = -std::numeric_limits<double>::infinity();
  std::uint32_t fade_serial_ = 0;
  bool started_ = false;
};

}  // namespace hapticfield
