#pragma once
/// @file material_image.hpp
/// Property and index maps (material/property_map.hpp) from pictures: one
/// channel of an OpenCV image (needs hapticfield::image / OpenCV), or of a
/// file read through hapticfield::load_image (image/load.hpp). Setup code.
///
/// A property map scales the channel's level t (8-bit: level / 255, 16-bit:
/// level / 65535, float: the value itself) to low + (high - low) t, so a
/// painted mask, black for glass and white for sandpaper, gives mu from 0.2
/// to 0.8. An index map takes the channel's integer level as the id.

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hapticfield/image/load.hpp"
#include "hapticfield/material/property_map.hpp"

namespace hapticfield::material {

namespace detail {

inline void check_picture(const cv::Mat& image, int channel, const char* who) {
  if (image.empty()) throw std::invalid_argument(std::string(who) + ": the picture is empty");
  if (channel < 0 || channel >= image.channels())
    throw std::invalid_argument(std::string(who) + ": channel " + std::to_string(channel) + " of a picture with " +
                                std::to_string(image.channels()) + " channel(s)");
  const int depth = image.depth();
  if (depth != CV_8U && depth != CV_16U && depth != CV_32F && depth != CV_64F)
    throw std::invalid_argument(std::string(who) + ": pixels must be 8-bit, 16-bit, float or double");
}

/// The channel's levels as doubles, row by row (the scale to [0, 1] for integers).
inline std::vector<double> channel_levels(const cv::Mat& image, int channel, bool normalise) {
  cv::Mat one;
  cv::extractChannel(image, one, channel);
  cv::Mat d;
  const double scale = !normalise                ? 1.0
                       : image.depth() == CV_8U  ? 1.0 / 255.0
                       : image.depth() == CV_16U ? 1.0 / 65535.0
                                                 : 1.0;
  one.convertTo(d, CV_64F, scale);
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(d.rows) * static_cast<std::size_t>(d.cols));
  for (int j = 0; j < d.rows; ++j)
    for (int i = 0; i < d.cols; ++i)
      out.push_back(d.at<double>(j, i));
  return out;
}

}  // namespace detail

/// One channel of image as a property low + (high - low) t (see the file comment).
/// @throws std::invalid_argument for an empty picture, a missing channel, an
///         unsupported pixel type or a non-finite value, low or high.
[[nodiscard]] inline PropertyMap property_map_from_image(const cv::Mat& image, int channel, double low, double high,
                                                         UvLayout layout = {}) {
  detail::check_picture(image, channel, "property_map_from_image");
  if (!std::isfinite(low) || !std::isfinite(high))
    throw std::invalid_argument("property_map_from_image: low and high must be finite");
  const std::vector<double> t = detail::channel_levels(image, channel, true);
  std::vector<float> values;
  values.reserve(t.size());
  for (const double x : t)
    values.push_back(static_cast<float>(low + (high - low) * x));
  return PropertyMap(image.cols, image.rows, std::move(values), layout);
}

/// One channel of image as region ids (its integer levels).
/// @throws std::invalid_argument for an empty picture, a missing channel or
///         a level that is negative, not whole or not finite.
[[nodiscard]] inline IndexMap index_map_from_image(const cv::Mat& image, int channel = 0, UvLayout layout = {}) {
  detail::check_picture(image, channel, "index_map_from_image");
  const std::vector<double> levels = detail::channel_levels(image, channel, false);
  std::vector<std::uint32_t> ids;
  ids.reserve(levels.size());
  for (const double x : levels) {
    if (!std::isfinite(x) || x < 0.0 || x != std::floor(x) || x > 4294967295.0)
      throw std::invalid_argument("index_map_from_image: level " + std::to_string(x) + " is not a region id");
    ids.push_back(static_cast<std::uint32_t>(x));
  }
  return IndexMap(image.cols, image.rows, std::move(ids), layout);
}

/// property_map_from_image of a picture file. @throws ImageError for a
/// missing or unreadable file, std::invalid_argument as above.
[[nodiscard]] inline PropertyMap load_property_map(const std::string& path, int channel, double low, double high,
                                                   UvLayout layout = {}) {
  return property_map_from_image(load_image(path), channel, low, high, layout);
}

/// index_map_from_image of a picture file (keep it lossless: PNG).
[[nodiscard]] inline IndexMap load_index_map(const std::string& path, int channel = 0, UvLayout layout = {}) {
  return index_map_from_image(load_image(path), channel, layout);
}

}  // namespace hapticfield::material
