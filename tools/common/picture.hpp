#pragma once
/// @file picture.hpp
/// Pictures for the tools to draw on: loaded with the library's one loader
/// (hapticfield::load_image: checked file, size guard from the header,
/// ImageError naming the file), then made 8-bit BGR.

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cli.hpp"
#include "hapticfield/image/load.hpp"

namespace hapticfield::cli {

/// Any picture as 8-bit BGR (16-bit and float scaled, gray and alpha converted).
inline cv::Mat to_bgr8(const cv::Mat& in) {
  cv::Mat eight;
  if (in.depth() == CV_8U)
    eight = in;
  else if (in.depth() == CV_16U)
    in.convertTo(eight, CV_8U, 1.0 / 257.0);
  else
    in.convertTo(eight, CV_8U, 255.0);  // float pictures in [0, 1]
  cv::Mat out;
  if (eight.channels() == 1)
    cv::cvtColor(eight, out, cv::COLOR_GRAY2BGR);
  else if (eight.channels() == 4)
    cv::cvtColor(eight, out, cv::COLOR_BGRA2BGR);
  else if (eight.channels() == 3)
    out = eight;
  else
    throw FileError("'" + std::string("picture") + "' has " + std::to_string(in.channels()) +
                    " channels (1, 3 or 4 expected)");
  return out;
}

/// Loads a picture as 8-bit BGR, decoders' own complaints muted (one error line).
/// @throws ImageError as hapticfield::load_image.
[[nodiscard]] inline cv::Mat load_bgr8(const std::string& path) {
  return to_bgr8(quiet_stderr([&] { return load_image(path); }));
}

}  // namespace hapticfield::cli
