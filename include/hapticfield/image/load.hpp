#pragma once
/// @file load.hpp
/// Loading pictures through OpenCV with errors that say what went wrong.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/image/grayscale.hpp"

namespace hapticfield {

/// A picture file cannot be used (missing, unreadable, not decodable).
class ImageError : public FileError {
 public:
  using FileError::FileError;
};

/// Loads a picture unchanged (keeps 16-bit depth and alpha).
/// @throws ImageError when the file is missing, is not a regular file, cannot
///         be decoded, or decodes to an empty image.
[[nodiscard]] inline cv::Mat load_image(const std::string& path) {
  try {
    check_file(path, std::uintmax_t{1} << 34);
  } catch (const FileError& e) {
    throw ImageError(e.what());
  }
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw ImageError("cannot decode '" + path + "': " + e.what());
  }
  if (image.empty())
    throw ImageError("cannot decode '" + path + "': not a picture OpenCV can read, or corrupt");
  return image;
}

/// Loads a picture as gray levels in [0, 255] (see to_gray()).
/// @throws ImageError as load_image(), or for an unsupported pixel format.
[[nodiscard]] inline GrayImage load_gray(const std::string& path, GrayWeights weights = GrayWeights::paper) {
  const cv::Mat image = load_image(path);
  try {
    return to_gray(image, weights);
  } catch (const std::invalid_argument& e) {
    throw ImageError("cannot use '" + path + "': " + e.what());
  }
}

}  // namespace hapticfield
