#pragma once
/// @file image_maps.hpp
/// Data and label maps from OpenCV images, for data visualisation and false
/// texturing (needs hapticfield::image / OpenCV; not part of texture.hpp).

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/texture/data_texture.hpp"

namespace hapticfield::texture {

namespace detail {
inline cv::Mat to_gray8(const cv::Mat& image, const char* who) {
  if (image.empty()) throw std::invalid_argument(std::string(who) + ": empty image");
  cv::Mat gray;
  if (image.channels() == 3)
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);  // Y = .299R + .587G + .114B
  else if (image.channels() == 4)
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  else if (image.channels() == 1)
    gray = image;
  else
    throw std::invalid_argument(std::string(who) + ": image must have 1, 3 or 4 channels");
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  return gray;
}
}  // namespace detail

/// Gray levels 0..255 -> data values 0..1 on the plane.
/// @throws std::invalid_argument for an empty or unsupported image.
[[nodiscard]] inline ScalarMap scalar_map_from_image(const cv::Mat& image, const PlaneMapping& mapping) {
  const cv::Mat gray = detail::to_gray8(image, "scalar_map_from_image");
  std::vector<float> values(static_cast<std::size_t>(gray.rows) * static_cast<std::size_t>(gray.cols));
  for (int y = 0; y < gray.rows; ++y)
    for (int x = 0; x < gray.cols; ++x)
      values[static_cast<std::size_t>(y) * static_cast<std::size_t>(gray.cols) + static_cast<std::size_t>(x)] =
          gray.at<std::uint8_t>(y, x) / 255.0f;
  return ScalarMap(gray.cols, gray.rows, std::move(values), mapping);
}

/// Quantises gray levels into `levels` equal bands (label = gray * levels / 256).
/// @throws std::invalid_argument for an empty image or levels outside 1..256.
[[nodiscard]] inline LabelMap label_map_from_gray_levels(const cv::Mat& image, int levels,
                                                         const PlaneMapping& mapping) {
  if (levels < 1 || levels > 256) throw std::invalid_argument("label_map_from_gray_levels: levels must be in 1..256");
  const cv::Mat gray = detail::to_gray8(image, "label_map_from_gray_levels");
  std::vector<std::uint16_t> labels(static_cast<std::size_t>(gray.rows) * static_cast<std::size_t>(gray.cols));
  for (int y = 0; y < gray.rows; ++y)
    for (int x = 0; x < gray.cols; ++x)
      labels[static_cast<std::size_t>(y) * static_cast<std::size_t>(gray.cols) + static_cast<std::size_t>(x)] =
          static_cast<std::uint16_t>(gray.at<std::uint8_t>(y, x) * levels / 256);
  return LabelMap(gray.cols, gray.rows, std::move(labels), mapping);
}

/// Loads an image file (any format OpenCV reads) as 8-bit BGR.
/// @throws std::invalid_argument when the file cannot be read.
[[nodiscard]] inline cv::Mat load_image(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw std::invalid_argument("load_image: no such file '" + path + "'");
  cv::Mat m = cv::imread(path, cv::IMREAD_COLOR);
  if (m.empty()) throw std::invalid_argument("load_image: cannot read image '" + path + "'");
  return m;
}

}  // namespace hapticfield::texture
