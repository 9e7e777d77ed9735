#pragma once
/// @file denoise.hpp
/// FrameDenoiser: removes compression noise from gray video frames before
/// the mask sees them, without freezing or smearing what moves.
///
/// - temporal: a motion-adaptive recursive filter (Dubois & Sabri, "Noise
///   reduction in image sequences using motion-compensated temporal
///   filtering", IEEE Trans. Commun. 32(7), 1984; the motion-detecting
///   recursive filters of Brailean et al., "Noise reduction filters for
///   dynamic image sequences: a review", Proc. IEEE 83(9), 1995):
///   a per-pixel running average a += k (g - a) over the frames of one
///   scene, whose gain k rises from `weight` to 1 with the motion measure.
///   The motion measure is the frame difference |g - a| averaged over a
///   `motion_window` square (then the largest over 3 x 3 px), not the
///   pixel's own difference: averaging cuts compression noise (at static
///   edges of vtest.avi a pixel's |g - a| is 3.4 levels at the 90th
///   percentile) while a moving object changes a whole neighbourhood, so
///   motion of a few levels is followed without noise being taken for it,
///   and the gain where nothing moves can be low. k = weight up to
///   `motion_floor`, 1 (the current frame, no lag) from `motion_threshold`,
///   linear between. The floor rises with the frame's noise: to 1.5 times
///   the 25th percentile of the motion measure (most of a frame is static;
///   white noise of sigma s gives about 0.8 s), at most 4 times the
///   configured floor, the threshold moving with it. Reset at cuts.
/// - spatial: OpenCV's bilateral filter (edges are kept, flat areas smoothed).
/// - both: spatial, then temporal.

#include <algorithm>
#include <array>
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
  double weight = 0.1;            ///< temporal: gain of the newest frame where nothing moves, (0, 1]
  double motion_floor = 3.0;      ///< temporal: motion measure up to which the gain is `weight` [gray levels]
  double motion_threshold = 8.0;  ///< temporal: motion measure from which g is followed at once [gray levels]
  int motion_window = 7;     ///< temporal: side of the square the motion measure averages |g - a| over [px], odd 3..31
  int spatial_diameter = 5;  ///< spatial: bilateral neighbourhood [px], odd 3..15
  double spatial_sigma_color = 10.0;  ///< spatial: bilateral range sigma [gray levels]
  double spatial_sigma_space = 2.0;   ///< spatial: bilateral space sigma [px]

  /// @throws std::invalid_argument naming the bad value.
  void validate() const {
    if (!std::isfinite(weight) || weight <= 0.0 || weight > 1.0)
      throw std::invalid_argument("DenoiseConfig: weight must be in (0, 1]");
    if (!std::isfinite(motion_floor) || motion_floor < 0.0)
      throw std::invalid_argument("DenoiseConfig: motion_floor must be finite and >= 0 [gray levels]");
    if (!std::isfinite(motion_threshold) || motion_threshold <= motion_floor)
      throw std::invalid_argument(
          "DenoiseConfig: motion_threshold must be finite and above motion_floor [gray levels]");
    if (motion_window < 3 || motion_window > 31 || motion_window % 2 == 0)
      throw std::invalid_argument("DenoiseConfig: motion_window must be odd, 3..31 [px]");
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
    difference_.create(gray.size(), CV_32FC1);
    for (int y = 0; y < gray.rows; ++y) {
      const float* g = gray.ptr<float>(y);
      const float* a = average_.ptr<float>(y);
      float* d = difference_.ptr<float>(y);
      for (int x = 0; x < gray.cols; ++x)
        d[x] = std::abs(g[x] - a[x]);
    }
    box_mean(difference_, config_.motion_window / 2, motion_);
    const float noise = lower_quartile(motion_);
    const auto configured_floor = static_cast<float>(config_.motion_floor);
    const float floor = std::min(std::max(configured_floor, noise_factor * noise), max_floor_factor * configured_floor);
    const float per_level =
        1.0f / (static_cast<float>(config_.motion_threshold) - configured_floor);  // > 0 (validated)
    // The largest measure over 3 x 3 px, so that a pixel at the rim of a
    // moving region follows it as fully as the region's inside.
    cv::dilate(motion_, motion_, cv::Mat());
    const auto w = static_cast<float>(config_.weight);
    for (int y = 0; y < gray.rows; ++y) {
      float* g = gray.ptr<float>(y);
      float* a = average_.ptr<float>(y);
      const float* m = motion_.ptr<float>(y);
      for (int x = 0; x < gray.cols; ++x) {
        const float u = std::min(std::max((m[x] - floor) * per_level, 0.0f), 1.0f);
        const float k = w + (1.0f - w) * u;
        const float next = a[x] + k * (g[x] - a[x]);
        a[x] = next;
        g[x] = next;
      }
    }
  }

  /// The mean of `in` over the (2 r + 1)^2 px square around each pixel,
  /// edges replicated: running column sums (one row added, one taken
  /// away), then 2 r + 1 shifted rows of them added (vectorised; for the
  /// default r = 3 cheaper than a running sum along the row, a serial
  /// chain). Float rounding drifts by about 1e-4 level over a frame.
  void box_mean(const cv::Mat& in, int r, cv::Mat& out) {
    out.create(in.size(), CV_32FC1);
    columns_.create(1, in.cols + 2 * r, CV_32FC1);
    float* padded = columns_.ptr<float>(0);
    float* column = padded + r;
    const int last_row = in.rows - 1, w = in.cols;
    std::fill(column, column + w, 0.0f);
    for (int j = -r; j <= r; ++j) {
      const float* src = in.ptr<float>(std::clamp(j, 0, last_row));
      for (int x = 0; x < w; ++x)
        column[x] += src[x];
    }
    const float scale = 1.0f / static_cast<float>((2 * r + 1) * (2 * r + 1));
    for (int y = 0; y < in.rows; ++y) {
      if (y > 0) {
        const float* added = in.ptr<float>(std::min(y + r, last_row));
        const float* removed = in.ptr<float>(std::max(y - r - 1, 0));
        for (int x = 0; x < w; ++x)
          column[x] += added[x] - removed[x];
      }
      std::fill(padded, column, column[0]);
      std::fill(column + w, column + w + r, column[w - 1]);
      float* dst = out.ptr<float>(y);
      std::fill(dst, dst + w, 0.0f);
      for (int i = 0; i <= 2 * r; ++i) {
        const float* shifted = padded + i;
        for (int x = 0; x < w; ++x)
          dst[x] += shifted[x];
      }
      for (int x = 0; x < w; ++x)
        dst[x] *= scale;
    }
  }

  /// The 25th percentile of a motion measure [gray levels], to 1/8 level,
  /// from every 4th pixel of every 4th row (a histogram: no allocation).
  [[nodiscard]] static float lower_quartile(const cv::Mat& measure) {
    std::array<long, quartile_bins> count{};
    long total = 0;
    for (int y = 0; y < measure.rows; y += 4) {
      const float* m = measure.ptr<float>(y);
      for (int x = 0; x < measure.cols; x += 4, ++total)
        ++count[static_cast<std::size_t>(
            std::clamp(m[x] * bins_per_level, 0.0f, static_cast<float>(quartile_bins - 1)))];  // drift: >= -1e-4
    }
    const long quarter = total / 4;
    long seen = 0;
    for (int b = 0; b < quartile_bins; ++b) {
      seen += count[static_cast<std::size_t>(b)];
      if (seen > quarter) return (static_cast<float>(b) + 0.5f) / bins_per_level;
    }
    return static_cast<float>(quartile_bins) / bins_per_level;
  }

  static constexpr float noise_factor = 1.5f;      ///< floor >= this x the frame's noise measure
  static constexpr float max_floor_factor = 4.0f;  ///< ... but at most this x the configured floor
  static constexpr float bins_per_level = 8.0f;
  static constexpr int quartile_bins = 512;  ///< up to 64 gray levels

  DenoiseConfig config_;
  cv::Mat average_;     ///< running average [gray levels], CV_32FC1
  cv::Mat difference_;  ///< |g - a| [gray levels]
  cv::Mat motion_;      ///< the motion measure [gray levels]
  cv::Mat columns_;     ///< running column sums of |g - a|, padded by r each side [gray levels]
  cv::Mat scratch_;
};

}  // namespace hapticfield
