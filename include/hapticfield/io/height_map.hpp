#pragma once
/// @file height_map.hpp
/// Height maps into a HeightGrid through OpenCV (CMake target
/// hapticfield::image): a picture whose gray level is height, or a depth
/// map (16-bit PNG/TIFF, 32-bit float TIFF) whose value is height in a
/// stated unit. The picture's size is read from its header and checked
/// against a pixel limit before anything is decoded (load_image()).
/// OpenEXR is refused: convert to a 32-bit float TIFF. Never used in a tick.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/image/load.hpp"
#include "hapticfield/io/height_grid.hpp"

namespace hapticfield::io {

/// A picture read as heights: gray level x mm_per_level.
struct PictureHeightConfig {
  double pixel_size = 1e-4;    ///< distance between pixel centres on the surface [m]
  double mm_per_level = 0.01;  ///< height of one gray level [mm] (255 levels: 2.55 mm)
  bool dark_is_high = false;   ///< true: black is the top (255 - level), as a tangible image feels it
  double blur_sigma = 0.0;     ///< Gaussian blur before use [px]; 0: none
  GrayWeights weights = GrayWeights::paper;
  std::uint64_t max_pixels = default_max_pixels;  ///< largest width x height accepted [px]
};

/// A depth map read as heights: value x metres_per_unit.
struct DepthMapConfig {
  double pixel_size = 1e-4;       ///< distance between pixel centres on the surface [m]
  double metres_per_unit = 1e-6;  ///< height of one unit of the file [m] (16-bit in um: 1e-6; float in m: 1.0)
  double blur_sigma = 0.0;        ///< Gaussian blur before use [px]; 0: none
  std::uint64_t max_pixels = default_max_pixels;  ///< largest width x height accepted [px]
};

namespace detail {

inline void check_positive(double v, const char* what) {
  if (!std::isfinite(v) || v <= 0.0)
    throw std::invalid_argument(std::string(what) + " must be finite and positive, got " + std::to_string(v));
}

inline void check_blur(double sigma) {
  if (!std::isfinite(sigma) || sigma < 0.0 || sigma > 1000.0)
    throw std::invalid_argument("blur_sigma must be in [0, 1000] px, got " + std::to_string(sigma));
}

/// Gaussian blur of a one-channel double plane, edges replicated.
inline void blur_plane(cv::Mat& plane, double sigma) {
  if (sigma > 0.0) cv::GaussianBlur(plane, plane, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
}

/// "W x H px" for messages.
[[nodiscard]] inline std::string size_text(int width, int height) {
  return std::to_string(width) + " x " + std::to_string(height) + " px";
}

/// A one-channel double plane (picture rows, top first) into a grid with
/// its bottom row first, each value times scale.
[[nodiscard]] inline HeightGrid grid_from_plane(const cv::Mat& plane, double scale, double pixel_size) {
  HeightGrid grid;
  grid.width = plane.cols;
  grid.height = plane.rows;
  grid.spacing_x = pixel_size;
  grid.spacing_y = pixel_size;
  grid.heights.resize(static_cast<std::size_t>(plane.cols) * static_cast<std::size_t>(plane.rows));
  for (int j = 0; j < plane.rows; ++j) {
    const double* src = plane.ptr<double>(plane.rows - 1 - j);
    double* dst = grid.heights.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(plane.cols);
    for (int i = 0; i < plane.cols; ++i)
      dst[i] = src[i] * scale;
  }
  return grid;
}

/// Refuses what the header check cannot see: OpenEXR (OpenCV reads it only
/// with OPENCV_IO_ENABLE_OPENEXR set, and no pixel limit is read from its
/// header here).
inline void refuse_exr(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext)
    c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (ext == ".exr")
    throw ImageError("cannot load '" + path +
                     "': OpenEXR depth maps are not supported (convert to a 32-bit float TIFF)");
}

}  // namespace detail

/// Heights from gray levels already in memory: level (0..255) x
/// mm_per_level / 1000 [m], after the optional blur.
/// @throws std::invalid_argument for a picture smaller than 2 x 2 px or bad
///         settings.
[[nodiscard]] inline HeightGrid height_grid_from_gray(const GrayImage& gray, const PictureHeightConfig& config = {}) {
  detail::check_positive(config.pixel_size, "PictureHeightConfig::pixel_size");
  detail::check_positive(config.mm_per_level, "PictureHeightConfig::mm_per_level");
  detail::check_blur(config.blur_sigma);
  if (gray.empty()) throw std::invalid_argument("height_grid_from_gray: the picture is empty (0 x 0 px)");
  if (gray.width() < 2 || gray.height() < 2)
    throw std::invalid_argument("height_grid_from_gray: the picture is " +
                                detail::size_text(gray.width(), gray.height()) +
                                "; a height map needs at least 2 x 2 px");
  cv::Mat plane(gray.height(), gray.width(), CV_64F);
  for (int y = 0; y < gray.height(); ++y) {
    const double* src = gray.row(y);
    double* dst = plane.ptr<double>(y);
    for (int x = 0; x < gray.width(); ++x)
      dst[x] = config.dark_is_high ? gray_full_scale - src[x] : src[x];
  }
  detail::blur_plane(plane, config.blur_sigma);
  HeightGrid grid = detail::grid_from_plane(plane, config.mm_per_level * 1e-3, config.pixel_size);
  grid.validate();
  return grid;
}

/// Heights from a picture file (PNG, JPEG, BMP, TIFF, Netpbm; 8 or 16 bit,
/// gray or colour): its gray level (to_gray()) x mm_per_level.
/// @throws ImageError (a FileError) naming the file when it is missing,
///         declares 0 x 0 or more than max_pixels (checked from the header
///         before decoding), is smaller than 2 x 2 px (a surface needs
///         four heights), is OpenEXR or cannot be decoded.
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline HeightGrid load_height_picture(const std::string& path, const PictureHeightConfig& config = {}) {
  detail::check_positive(config.pixel_size, "PictureHeightConfig::pixel_size");
  detail::check_positive(config.mm_per_level, "PictureHeightConfig::mm_per_level");
  detail::check_blur(config.blur_sigma);
  detail::refuse_exr(path);
  const GrayImage gray = load_gray(path, config.weights, config.max_pixels);
  if (gray.width() < 2 || gray.height() < 2)
    throw ImageError("cannot use '" + path + "' as a height map: " + detail::size_text(gray.width(), gray.height()) +
                     "; a height map needs at least 2 x 2 px");
  return height_grid_from_gray(gray, config);
}

/// Heights from a one-channel depth image already in memory (16-bit
/// unsigned, 32- or 64-bit float): value x metres_per_unit, after the
/// optional blur.
/// @param name  the file's name for messages
/// @throws FileError naming the file for another pixel type, more than one
///         channel, an image smaller than 2 x 2 px or a non-finite value
///         (with its pixel).
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline HeightGrid height_grid_from_depth(const cv::Mat& depth, const std::string& name,
                                                       const DepthMapConfig& config = {}) {
  detail::check_positive(config.pixel_size, "DepthMapConfig::pixel_size");
  detail::check_positive(config.metres_per_unit, "DepthMapConfig::metres_per_unit");
  detail::check_blur(config.blur_sigma);
  const auto fail = [&name](const std::string& what) {
    return ImageError("cannot use '" + name + "' as a depth map: " + what);
  };
  if (depth.empty() || depth.rows <= 0 || depth.cols <= 0) throw fail("0 x 0 px");
  if (depth.rows < 2 || depth.cols < 2)
    throw fail(detail::size_text(depth.cols, depth.rows) + "; a height map needs at least 2 x 2 px");
  if (depth.channels() != 1)
    throw fail(std::to_string(depth.channels()) +
               " channels; a depth map has one (use load_height_picture for a picture)");
  const int type = depth.depth();
  if (type == CV_8U) throw fail("8-bit levels; a depth map is 16-bit or float (use load_height_picture for a picture)");
  if (type != CV_16U && type != CV_32F && type != CV_64F)
    throw fail("OpenCV pixel depth " + std::to_string(type) + "; a depth map is 16-bit unsigned or float");
  cv::Mat plane;
  depth.convertTo(plane, CV_64F);
  for (int y = 0; y < plane.rows; ++y) {
    const double* row = plane.ptr<double>(y);
    for (int x = 0; x < plane.cols; ++x)
      if (!std::isfinite(row[x]))
        throw fail("the value at column " + std::to_string(x) + ", row " + std::to_string(y) + " is not finite");
  }
  detail::blur_plane(plane, config.blur_sigma);
  HeightGrid grid = detail::grid_from_plane(plane, config.metres_per_unit, config.pixel_size);
  for (const double h : grid.heights)
    if (!std::isfinite(h))
      throw fail("a height overflows at metres_per_unit " + std::to_string(config.metres_per_unit));
  grid.validate();
  return grid;
}

/// Heights from a depth-map file: a 16-bit PNG or TIFF, or a 32-bit float
/// TIFF, one channel: value x metres_per_unit.
/// @throws ImageError (a FileError) naming the file when it is missing,
///         declares 0 x 0 or more than max_pixels (checked from the header
///         before decoding), is smaller than 2 x 2 px, is OpenEXR, cannot
///         be decoded, is not a one-channel 16-bit or float image, or holds
///         a NaN or infinite value.
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline HeightGrid load_depth_map(const std::string& path, const DepthMapConfig& config = {}) {
  detail::check_positive(config.pixel_size, "DepthMapConfig::pixel_size");
  detail::check_positive(config.metres_per_unit, "DepthMapConfig::metres_per_unit");
  detail::check_blur(config.blur_sigma);
  detail::refuse_exr(path);
  return height_grid_from_depth(load_image(path, config.max_pixels), path, config);
}

}  // namespace hapticfield::io
