#pragma once
/// @file denoise.hpp
/// FrameDenoiser: removes compression noise from gray video frames before
/// the mask sees them, without freezing or smearing what moves.
///
/// - temporal: a per-pixel running average a += w (g - a) of the frames of
///   one scene. Where a pixel differs from the average by more than
///   `motion_threshold` gray levels (something moved there, or the light
///   changed), the average takes the current frame's value at once, so a
///   moving edge is felt where the current frame shows it. Reset at cuts.
/// - spatial: OpenCV's bilateral filter (edges are kept, flat areas smoothed).
/// - both: spatial, then temporal.

#include <cmath>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace hapticfield {

enum class DenoiseMode { none, temporal, spatial, both };

[[nodiscard]] constexpr const char* to_string(DenoiseMode mode) noexcept {
  switch (mode) {
    case DenoiseMode::none:
      return "none";
    case DenoiseMode::temporal:
      return "temporal";
    case DenoiseMode::spatial:
      return "spatial";
    case DenoiseMode::both:
      return "both";
  }
  return "?";
}

struct DenoiseConfig {
  DenoiseMode mode = DenoiseMode::temporal;
  double weight = 0.25;               ///< temporal: weight w of the newest frame, (0, 1]
  double motion_threshold = 12.0;     ///< temporal: |g - a| above this follows g at once [gray levels]
  int spatial_diameter = 5;           ///< spatial: bilateral neighbourhood [px], odd 3..15
  double spatial_sigma_color = 10.0;  ///< spatial: bilateral range sigma [gray levels]
  double spatial_sigma_space = 2.0;   ///< spatial: bilateral space sigma [px]

  /// @throws std::invalid_argument naming the bad value.
  void validate() const {
    if (!std::isfinite(weight) || weight <= 0.0 || weight > 1.0)
      throw std::invalid_argument("DenoiseConfig: weight must be in (0, 1]");
    if (!std::isfinite(motion_threshold) || motion_threshold < 0.0)
      throw std::invalid_argument("DenoiseConfig: motion_threshold must be finite and >= 0 [gray levels]");
    if (spatial_diameter < 3 || spatial_diameter > 15 || spatial_diameter % 2 == 0)
      throw std::invalid_argument("DenoiseConfig: spatial_diameter must be odd, 3..15 [px]");
    if (!std::isfinite(spatial_sigma_color) || spatial_sigma_color <= 0.0 || !std::isfinite(spatial_sigma_space) ||
        spatial_sigma_space <= 0.0)
      throw std::invalid_argument("DenoiseConfig: bilateral sigmas must be finite and positive");
  }
};

class FrameDenoiser {
 public:
  explicit FrameDenoiser(const DenoiseConfig& config = {}) : config_(config) { config_.validate(); }

  /// Denoises one gray frame (CV_32FC1, levels 0..255) in place. `new_scene`
  /// restarts the temporal average (a cut, a seek, the first frame).
  /// @throws std::invalid_argument for a frame that is not CV_32FC1.
  void apply(cv::Mat& gray, bool new_scene) {
    if (gray.type() != CV_32FC1) throw std::invalid_argument("FrameDenoiser: expected a CV_32FC1 frame");
    const DenoiseMode m = config_.mode;
    if (m == DenoiseMode::spatial || m == DenoiseMode::both) {
      cv::bilateralFilter(gray, scratch_, config_.spatial_diameter, config_.spatial_sigma_color,
                          config_.spatial_sigma_space, cv::BORDER_REFLECT_101);
      std::swap(gray, scratch_);
    }
    if (m == DenoiseMode::temporal || m == DenoiseMode::both) temporal(gray, new_scene);
  }

  void reset() noexcept { average_.release(); }
  [[nodiscard]] const DenoiseConfig& config() const noexcept { return config_; }

 private:
  void temporal(cv::Mat& gray, bool new_scene) {
    if (new_scene || average_.size() != gray.size()) {
      gray.copyTo(average_);
      return;
    }
    const auto w = static_cast<float>(config_.weight);
    const auto threshold = static_cast<float>(config_.motion_threshold);
    for (int y = 0; y < gray.rows; ++y) {
      float* g = gray.ptr<float>(y);
      float* a = average_.ptr<float>(y);
      for (int x = 0; x < gray.cols; ++x) {
        const float d = g[x] - a[x];
        const float next = (d > threshold || d < -threshold) ? g[x] : a[x] + w * d;
        a[x] = next;
        g[x] = next;
      }
    }
  }

  DenoiseConfig config_;
  cv::Mat average_;  ///< running average [gray levels], CV_32FC1
  cv::Mat scratch_;
};

}  // namespace hapticfield
