#pragma once
/// @file scene_cut.hpp
/// SceneCutDetector: finds the frames where the camera changes, with a
/// measure that compression noise does not trip.
///
/// Each gray frame is shrunk to a 64 x 36 thumbnail by area averaging (a
/// 1280 x 720 frame: each thumbnail pixel is the mean of 20 x 20 pixels, so
/// codec noise of a few levels averages to a fraction of a level) and the
/// mean absolute difference (MAD, [gray levels]) to the previous thumbnail is
/// taken. Motion within a scene moves a few thumbnail pixels and changes
/// slowly from frame to frame; a cut changes almost all of them at once. A
/// frame is a cut when its MAD is at least `min_difference` and at least
/// `ratio` times the mean MAD of the previous `history` frames of the scene,
/// and the scene has lasted `min_scene_frames`.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace hapticfield {

struct SceneCutConfig {
  double min_difference = 18.0;  ///< least thumbnail MAD of a cut [gray levels, 0..255]
  double ratio = 3.0;            ///< a cut's MAD over the recent mean MAD of the scene
  int min_scene_frames = 3;      ///< frames a scene lasts at least (no cut right after a cut)
  bool enabled = true;           ///< false: never report a cut

  /// @throws std::invalid_argument for a non-finite or negative threshold,
  ///         a ratio below 1 or a scene length below 1.
  void validate() const {
    if (!std::isfinite(min_difference) || min_difference < 0.0)
      throw std::invalid_argument("SceneCutConfig: min_difference must be finite and >= 0 [gray levels]");
    if (!std::isfinite(ratio) || ratio < 1.0) throw std::invalid_argument("SceneCutConfig: ratio must be >= 1");
    if (min_scene_frames < 1) throw std::invalid_argument("SceneCutConfig: min_scene_frames must be >= 1");
  }
};

class SceneCutDetector {
 public:
  static constexpr int thumb_width = 64;   ///< [px]
  static constexpr int thumb_height = 36;  ///< [px]
  static constexpr std::size_t history = 8;

  explicit SceneCutDetector(const SceneCutConfig& config = {}) : config_(config) { config_.validate(); }

  /// Feeds the next frame (gray, CV_8U or CV_32F, levels 0..255). True when
  /// it starts a new scene. The first frame after reset() is not a cut.
  /// @throws cv::Exception for an empty or multi-channel frame.
  bool push(const cv::Mat& gray) {
    cv::Mat thumb;
    cv::resize(gray, thumb, cv::Size(thumb_width, thumb_height), 0.0, 0.0, cv::INTER_AREA);
    thumb.convertTo(thumb, CV_32F);
    if (previous_.empty()) {
      previous_ = thumb;
      last_difference_ = 0.0;
      scene_frames_ = 1;
      return false;
    }
    last_difference_ = cv::norm(thumb, previous_, cv::NORM_L1) / static_cast<double>(thumb.total());
    previous_ = thumb;
    const double recent = count_ == 0 ? 0.0 : sum_ / static_cast<double>(count_);
    const bool cut = config_.enabled && scene_frames_ >= config_.min_scene_frames &&
                     last_difference_ >= config_.min_difference && last_difference_ >= config_.ratio * recent;
    if (cut) {
      scene_frames_ = 1;
      count_ = 0;
      sum_ = 0.0;
      next_ = 0;
    } else {
      ++scene_frames_;
      if (count_ == history)
        sum_ -= recent_[next_];
      else
        ++count_;
      recent_[next_] = last_difference_;
      sum_ += last_difference_;
      next_ = (next_ + 1) % history;
    }
    return cut;
  }

  /// The MAD of the last frame pushed to the one before [gray levels].
  [[nodiscard]] double last_difference() const noexcept { return last_difference_; }
  [[nodiscard]] const SceneCutConfig& config() const noexcept { return config_; }

  void reset() noexcept {
    previous_.release();
    count_ = 0;
    sum_ = 0.0;
    next_ = 0;
    scene_frames_ = 0;
    last_difference_ = 0.0;
  }

 private:
  SceneCutConfig config_;
  cv::Mat previous_;
  std::array<double, history> recent_{};
  std::size_t count_ = 0;
  std::size_t next_ = 0;
  double sum_ = 0.0;
  int scene_frames_ = 0;
  double last_difference_ = 0.0;
};

}  // namespace hapticfield
