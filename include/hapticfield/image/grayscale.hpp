#pragma once
/// @file grayscale.hpp
/// Colour to gray in floating point, from OpenCV matrices (8- or 16-bit,
/// 1, 3 or 4 channels in OpenCV's BGR(A) order).

#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "hapticfield/image/gray_image.hpp"

namespace hapticfield {

/// Luma weights for the gray conversion.
enum class GrayWeights {
  paper,  ///< Y = 0.3 R + 0.59 G + 0.11 B (Vasudevan & Manivannan 2008)
  bt601,  ///< Y = 0.299 R + 0.587 G + 0.114 B (ITU-R BT.601, OpenCV's cvtColor)
};

struct LumaWeights {
  double r, g, b;
};

[[nodiscard]] constexpr LumaWeights luma_weights(GrayWeights weights) noexcept {
  return weights == GrayWeights::paper ? LumaWeights{0.3, 0.59, 0.11} : LumaWeights{0.299, 0.587, 0.114};
}

namespace detail {
template <class Channel>
GrayImage to_gray_typed(const cv::Mat& image, LumaWeights w, double to_8bit) {
  GrayImage out(image.cols, image.rows);
  const int channels = image.channels();
  for (int y = 0; y < image.rows; ++y) {
    const Channel* src = image.ptr<Channel>(y);
    double* dst = out.row(y);
    for (int x = 0; x < image.cols; ++x, src += channels) {
      // OpenCV stores colour as B, G, R (, A); alpha is ignored.
      dst[x] = channels == 1 ? to_8bit * src[0] : to_8bit * (w.b * src[0] + w.g * src[1] + w.r * src[2]);
    }
  }
  return out;
}
}  // namespace detail

/// Gray levels in [0, 255] as doubles, not rounded. 16-bit input is scaled by
/// 255 / 65535 so the same picture gives the same gray levels at either depth.
/// Alpha (4th channel) is ignored.
/// @throws std::invalid_argument for an empty image, a depth other than 8- or
///         16-bit unsigned, or a channel count other than 1, 3 or 4.
[[nodiscard]] inline GrayImage to_gray(const cv::Mat& image, GrayWeights weights = GrayWeights::paper) {
  if (image.empty()) throw std::invalid_argument("to_gray: the image is empty (0 x 0 px)");
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4)
    throw std::invalid_argument("to_gray: expected 1, 3 or 4 channels, got " + std::to_string(channels));
  const LumaWeights w = luma_weights(weights);
  switch (image.depth()) {
    case CV_8U:
      return detail::to_gray_typed<unsigned char>(image, w, 1.0);
    case CV_16U:
      return detail::to_gray_typed<unsigned short>(image, w, gray_full_scale / 65535.0);
    default:
      throw std::invalid_argument("to_gray: expected 8- or 16-bit unsigned pixels, got OpenCV depth " +
                                  std::to_string(image.depth()));
  }
}

/// A GrayImage as a CV_64FC1 matrix that shares nothing with it (a copy).
[[nodiscard]] inline cv::Mat to_mat(const GrayImage& gray) {
  cv::Mat out(gray.height(), gray.width(), CV_64FC1);
  for (int y = 0; y < gray.height(); ++y) {
    const double* src = gray.row(y);
    std::copy(src, src + gray.width(), out.ptr<double>(y));
  }
  return out;
}

}  // namespace hapticfield
