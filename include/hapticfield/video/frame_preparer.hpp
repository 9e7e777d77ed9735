#pragma once
/// @file frame_preparer.hpp
/// FramePreparer: one decoded video frame to a VideoFrame, ready for the
/// servo thread: gray levels (the paper's Y = 0.3 R + 0.59 G + 0.11 B),
/// scene-cut detection, denoising, rounding to 1/100 level, then the
/// tangible-image tables (the O(1) kernel's integral images for Prewitt and
/// emboss). Runs on the worker
/// thread (or offline); allocates.

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/tangible_image.hpp"
#include "hapticfield/video/denoise.hpp"
#include "hapticfield/video/frame_window.hpp"
#include "hapticfield/video/scene_cut.hpp"

namespace hapticfield {

struct PrepareConfig {
  TangibleConfig tangible{};  ///< mask, size, border: as for a still picture
  DenoiseConfig denoise{};
  SceneCutConfig cuts{};
};

class FramePreparer {
 public:
  /// @throws std::invalid_argument for a bad mask size or denoise / cut setting.
  explicit FramePreparer(const PrepareConfig& config) : config_(config), denoiser_(config.denoise), cuts_(config.cuts) {
    validate_mask_size(config.tangible.mask, config.tangible.size);
  }

  /// Prepares frame `index` at video time `time` [s] from a BGR (3 or 4
  /// channel) or gray 8-bit image.
  /// @throws std::invalid_argument for an empty frame, another depth or
  ///         channel count, a size that differs from the first frame's, or a
  ///         frame smaller than the mask.
  std::shared_ptr<const VideoFrame> prepare(const cv::Mat& image, long index, double time) {
    if (image.empty()) throw std::invalid_argument("FramePreparer: empty frame");
    if (image.depth() != CV_8U) throw std::invalid_argument("FramePreparer: expected 8-bit frames");
    if (size_.width > 0 && image.size() != size_)
      throw std::invalid_argument("FramePreparer: frame size changed from " + std::to_string(size_.width) + " x " +
                                  std::to_string(size_.height) + " px");
    to_gray32(image, gray_);
    const bool cut = cuts_.push(gray_);
    denoiser_.apply(gray_, cut || !started_);
    started_ = true;

    // The inverted levels 255 - Y, as TangibleImage would invert them.
    GrayImage inverted(gray_.cols, gray_.rows);
    for (int y = 0; y < gray_.rows; ++y) {
      const float* src = gray_.ptr<float>(y);
      double* dst = inverted.row(y);
      for (int x = 0; x < gray_.cols; ++x)
        dst[x] = gray_full_scale - quantised_level(src[x]);
    }
    auto frame = std::make_shared<VideoFrame>(VideoFrame{index, time, cut && index_ >= 0, cuts_.last_difference(),
                                                         TangibleImage::from_inverted(inverted, config_.tangible)});
    size_ = image.size();
    index_ = index;
    return frame;
  }

  /// Checks that frames of w x h px can carry the mask, before any is prepared.
  /// @throws std::invalid_argument naming both sizes when a side is smaller than the mask.
  void check_frame_size(int w, int h) const {
    const int m = config_.tangible.size;
    if (w < m || h < m)
      throw std::invalid_argument("the video's frames (" + std::to_string(w) + " x " + std::to_string(h) +
                                  " px) are smaller than the " + std::to_string(m) + " x " + std::to_string(m) +
                                  " mask");
  }

  /// The next frame starts a new scene without being a cut (a seek): the
  /// temporal average and the cut detector restart.
  void restart() noexcept {
    cuts_.reset();
    denoiser_.reset();
    started_ = false;
    index_ = -1;
  }

  /// The gray frame after denoising, as the mask saw it last [levels, CV_32F].
  [[nodiscard]] const cv::Mat& last_gray() const noexcept { return gray_; }
  [[nodiscard]] const PrepareConfig& config() const noexcept { return config_; }

  /// A gray level rounded to 1/100 level: the paper's colour weights give
  /// exact hundredths, which float arithmetic and denoising blur by ~1e-5
  /// level. On hundredths the tables hold 32-bit integers (12 bytes a cell
  /// up to m = 65, see integral_kernel.hpp) instead of 2^24 fixed point in
  /// 64 bits; the force moves by at most 2e-5 of full scale.
  /// @pre level in [0, 255]: the weights sum to 1 and both denoisers average,
  ///      so every prepared level is (no clamp, so the loop vectorises).
  [[nodiscard]] static double quantised_level(float level) noexcept {
    const float hundredths = level * 100.0f + 0.5f;
    return static_cast<double>(static_cast<int>(hundredths)) / 100.0;
  }

  /// One pass: B, G, R bytes to Y = 0.11 B + 0.59 G + 0.3 R; the channel
  /// count fixed at compile time so the loop vectorises.
  template <int Channels>
  static void paper_gray(const cv::Mat& image, cv::Mat& out) {
    out.create(image.size(), CV_32FC1);
    for (int y = 0; y < image.rows; ++y) {
      const unsigned char* src = image.ptr<unsigned char>(y);
      float* dst = out.ptr<float>(y);
      for (int x = 0; x < image.cols; ++x) {
        const unsigned char* p = src + Channels * x;
        dst[x] = 0.11f * static_cast<float>(p[0]) + 0.59f * static_cast<float>(p[1]) + 0.3f * static_cast<float>(p[2]);
      }
    }
  }

  /// Gray levels with the paper's weights, as float [0, 255].
  static void to_gray32(const cv::Mat& image, cv::Mat& out) {
    switch (image.channels()) {
      case 1:
        image.convertTo(out, CV_32F);
        return;
      case 3:
        paper_gray<3>(image, out);
        return;
      case 4:
        paper_gray<4>(image, out);
        return;
      default:
        throw std::invalid_argument("FramePreparer: expected 1, 3 or 4 channels");
    }
  }

 private:
  PrepareConfig config_;
  FrameDenoiser denoiser_;
  SceneCutDetector cuts_;
  cv::Mat gray_;
  cv::Size size_{0, 0};
  long index_ = -1;
  bool started_ = false;
};

}  // namespace hapticfield
