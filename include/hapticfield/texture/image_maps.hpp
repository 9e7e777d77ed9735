#pragma once
/// @file image_maps.hpp
/// Data and label maps from OpenCV images, for data visualisation and false
/// texturing (needs hapticfield::image / OpenCV; not part of texture.hpp).
/// Pictures are loaded with hapticfield::load_image (image/load.hpp).

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/texture/data_texture.hpp"

namespace hapticfield::texture {

namespace detail {
/// Gray levels in [0, 255] with the library's own conversion (image/grayscale.hpp,
/// the paper's weights by default), so a data map reads the picture exactly as
/// a tangible image does.
inline GrayImage gray_of(const cv::Mat& image, GrayWeights weights, const char* who) {
  if (image.empty()) throw std::invalid_argument(std::string(who) + ": empty image");
  return to_gray(image, weights);
}
}  // namespace detail

/// Gray levels 0..255 -> data values 0..1 on the plane.
/// @throws std::invalid_argument for an empty or unsupported image.
[[nodiscard]] inline ScalarMap scalar_map_from_image(const cv::Mat& image, const PlaneMapping& mapping,
                                                     GrayWeights weights = GrayWeights::paper) {
  const GrayImage gray = detail::gray_of(image, weights, "scalar_map_from_image");
  std::vector<float> values(static_cast<std::size_t>(gray.height()) * static_cast<std::size_t>(gray.width()));
  for (int y = 0; y < gray.height(); ++y)
    for (int x = 0; x < gray.width(); ++x)
      values[static_cast<std::size_t>(y) * static_cast<std::size_t>(gray.width()) + static_cast<std::size_t>(x)] =
          static_cast<float>(gray.at(x, y) / 255.0);
  return ScalarMap(gray.width(), gray.height(), std::move(values), mapping);
}

/// Quantises gray levels into `levels` equal bands (label = gray * levels / 256).
/// @throws std::invalid_argument for an empty image or levels outside 1..256.
[[nodiscard]] inline LabelMap label_map_from_gray_levels(const cv::Mat& image, int levels, const PlaneMapping& mapping,
                                                         GrayWeights weights = GrayWeights::paper) {
  if (levels < 1 || levels > 256) throw std::invalid_argument("label_map_from_gray_levels: levels must be in 1..256");
  const GrayImage gray = detail::gray_of(image, weights, "label_map_from_gray_levels");
  std::vector<std::uint16_t> labels(static_cast<std::size_t>(gray.height()) * static_cast<std::size_t>(gray.width()));
  for (int y = 0; y < gray.height(); ++y)
    for (int x = 0; x < gray.width(); ++x) {
      const int level = static_cast<int>(std::lround(gray.at(x, y)));  // 0..255
      labels[static_cast<std::size_t>(y) * static_cast<std::size_t>(gray.width()) + static_cast<std::size_t>(x)] =
          static_cast<std::uint16_t>(level * levels / 256);
    }
  return LabelMap(gray.width(), gray.height(), std::move(labels), mapping);
}

}  // namespace hapticfield::texture
