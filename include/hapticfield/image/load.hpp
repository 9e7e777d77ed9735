#pragma once
/// @file load.hpp
/// Loading pictures through OpenCV with errors that say what went wrong.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/image/picture_size.hpp"

namespace hapticfield {

/// A picture file cannot be used (missing, unreadable, not decodable).
class ImageError : public FileError {
 public:
  using FileError::FileError;
};

/// Largest picture load_image() and load_gray() accept by default [px]:
/// 100 Mpx. Memory per pixel: 8 bytes for the gray plane, and a tangible
/// image built on it takes 12 bytes of integer tables (24 for BT.601 gray
/// above m = 17, paper-weighted colour above m = 65, or non-integer levels)
/// plus an 8-byte inverted copy while it is built: measured +17 bytes per
/// pixel at the peak for m = 17 on 12 Mpx (it was +38 with double tables),
/// so 100 Mpx needs about 2.5 GB. Raise the limit with max_pixels.
inline constexpr std::uint64_t default_max_pixels = 100'000'000;

namespace detail {
[[nodiscard]] inline std::string too_large(const std::string& path, std::uint64_t w, std::uint64_t h,
                                           std::uint64_t max_pixels) {
  return "cannot load '" + path + "': " + std::to_string(w) + " x " + std::to_string(h) + " px (" +
         std::to_string(w * h) + " px) is larger than the limit of " + std::to_string(max_pixels) +
         " px (raise max_pixels to allow it)";
}
}  // namespace detail

/// Loads a picture unchanged (keeps 16-bit depth and alpha).
///
/// The size is read from the file header (PNG, JPEG, BMP, TIFF, Netpbm; see
/// read_picture_size()) and checked against max_pixels before anything is
/// decoded, so a small file that declares a huge picture fails at once
/// instead of meeting the OOM killer. Other formats are checked after
/// decoding; their decoders are bounded by OpenCV's own limit, the
/// environment variable OPENCV_IO_MAX_IMAGE_PIXELS (default 2^30 px).
/// @param max_pixels  largest width x height accepted [px]
/// @throws ImageError when the file is missing, is not a regular file,
///         declares a zero size or more than max_pixels, cannot be decoded,
///         or decodes to an empty image.
[[nodiscard]] inline cv::Mat load_image(const std::string& path, std::uint64_t max_pixels = default_max_pixels) {
  std::optional<PictureSize> declared;
  try {
    check_file(path, std::uintmax_t{1} << 34);
    declared = read_picture_size(path);
  } catch (const FileError& e) {
    throw ImageError(e.what());
  }
  if (declared) {
    if (declared->width == 0 || declared->height == 0)
      throw ImageError("cannot decode '" + path + "': the " + declared->format + " header declares " +
                       std::to_string(declared->width) + " x " + std::to_string(declared->height) + " px");
    // width, height < 2^32 each: the product fits in 64 bits.
    if (declared->pixels() > max_pixels)
      throw ImageError(detail::too_large(path, declared->width, declared->height, max_pixels));
  }
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw ImageError("cannot decode '" + path + "': " + e.what());
  }
  if (image.empty()) throw ImageError("cannot decode '" + path + "': not a picture OpenCV can read, or corrupt");
  if (std::uint64_t(image.cols) * std::uint64_t(image.rows) > max_pixels)
    throw ImageError(detail::too_large(path, std::uint64_t(image.cols), std::uint64_t(image.rows), max_pixels));
  return image;
}

/// Loads a picture as gray levels in [0, 255] (see to_gray()).
/// @throws ImageError as load_image(), or for an unsupported pixel format.
[[nodiscard]] inline GrayImage load_gray(const std::string& path, GrayWeights weights = GrayWeights::paper,
                                         std::uint64_t max_pixels = default_max_pixels) {
  const cv::Mat image = load_image(path, max_pixels);
  try {
    return to_gray(image, weights);
  } catch (const std::invalid_argument& e) {
    throw ImageError("cannot use '" + path + "': " + e.what());
  }
}

}  // namespace hapticfield
