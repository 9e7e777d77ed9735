#pragma once
/// @file force_map_render.hpp
/// Pictures of force maps like the tangible-images paper's figures 7 and 8:
/// one picture per component (red positive, blue negative, brightness =
/// magnitude), a magnitude picture and arrows over the photograph.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/kernels/force_map.hpp"

namespace hapticfield {

enum class ForceComponent { x, y };

namespace detail {
inline double full_scale_or_max(const ForceMap& map, double full_scale) {
  if (full_scale > 0.0 && std::isfinite(full_scale)) return full_scale;
  const double m = map.max_magnitude();
  return m > 0.0 ? m : 1.0;
}
inline unsigned char to_byte(double v) {
  return static_cast<unsigned char>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}
}  // namespace detail

/// One component as a BGR picture: red where it is positive (right / down),
/// blue where negative, brightness = |component| / full_scale (<= 0: the
/// map's largest magnitude).
[[nodiscard]] inline cv::Mat component_picture(const ForceMap& map, ForceComponent component, double full_scale = 0.0) {
  const double s = detail::full_scale_or_max(map, full_scale);
  const std::vector<float>& plane = component == ForceComponent::x ? map.fx : map.fy;
  cv::Mat out(map.height, map.width, CV_8UC3, cv::Scalar::all(0));
  for (int y = 0; y < map.height; ++y) {
    auto* row = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < map.width; ++x) {
      const double v = plane[map.index(x, y)] / s;
      row[x] = v >= 0.0 ? cv::Vec3b(0, 0, detail::to_byte(v)) : cv::Vec3b(detail::to_byte(-v), 0, 0);
    }
  }
  return out;
}

/// Force magnitude as a gray picture, white = full_scale (<= 0: the map's largest).
[[nodiscard]] inline cv::Mat magnitude_picture(const ForceMap& map, double full_scale = 0.0) {
  const double s = detail::full_scale_or_max(map, full_scale);
  cv::Mat out(map.height, map.width, CV_8UC1);
  for (int y = 0; y < map.height; ++y) {
    auto* row = out.ptr<unsigned char>(y);
    for (int x = 0; x < map.width; ++x)
      row[x] = detail::to_byte(std::hypot(double(map.fx[map.index(x, y)]), double(map.fy[map.index(x, y)])) / s);
  }
  return out;
}

/// Arrows of the force over the photograph, one per spacing x spacing cell,
/// length proportional to magnitude (spacing px at full scale).
/// @throws std::invalid_argument when the photo and map sizes differ or spacing < 2.
[[nodiscard]] inline cv::Mat arrow_overlay(const cv::Mat& photo, const ForceMap& map, int spacing = 16,
                                           double full_scale = 0.0) {
  if (photo.cols != map.width || photo.rows != map.height)
    throw std::invalid_argument("arrow_overlay: the photo and the force map differ in size");
  if (spacing < 2) throw std::invalid_argument("arrow_overlay: spacing must be at least 2 px");
  const double s = detail::full_scale_or_max(map, full_scale);
  cv::Mat out;
  cv::Mat eight_bit;
  if (photo.depth() == CV_16U)
    photo.convertTo(eight_bit, CV_8U, 255.0 / 65535.0);
  else
    eight_bit = photo;
  if (eight_bit.channels() == 1)
    cv::cvtColor(eight_bit, out, cv::COLOR_GRAY2BGR);
  else if (eight_bit.channels() == 4)
    cv::cvtColor(eight_bit, out, cv::COLOR_BGRA2BGR);
  else
    out = eight_bit.clone();
  out *= 0.6;  // dim the photo so the arrows stand out
  for (int y = spacing / 2; y < map.height; y += spacing) {
    for (int x = spacing / 2; x < map.width; x += spacing) {
      const double fx = map.fx[map.index(x, y)] / s;
      const double fy = map.fy[map.index(x, y)] / s;
      if (std::hypot(fx, fy) < 0.05) continue;
      const cv::Point from(x, y);
      const cv::Point to(static_cast<int>(std::lround(x + fx * spacing)),
                         static_cast<int>(std::lround(y + fy * spacing)));
      cv::arrowedLine(out, from, to, cv::Scalar(0, 255, 255), 1, cv::LINE_AA, 0, 0.3);
    }
  }
  return out;
}

/// The colour scale the pictures use: full_scale when it is positive and
/// finite, else the map's largest magnitude (1 for a map without force).
/// Two maps drawn with the same full_scale compare by eye; each drawn with
/// its own largest magnitude does not.
[[nodiscard]] inline double force_picture_scale(const ForceMap& map, double full_scale = 0.0) {
  return detail::full_scale_or_max(map, full_scale);
}

/// Writes fx.png, fy.png, magnitude.png, arrows.png and the float planes
/// fx.tiff, fy.tiff (32-bit) into dir; returns the paths. Full colour (and
/// a full-length arrow) is full_scale (<= 0: the map's largest magnitude,
/// see force_picture_scale()).
/// @throws std::runtime_error when the folder or a file cannot be written.
inline std::vector<std::string> write_force_pictures(const std::string& dir, const cv::Mat& photo, const ForceMap& map,
                                                     double full_scale = 0.0) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create '" + dir + "': " + ec.message());
  std::vector<std::string> written;
  const auto save = [&](const std::string& name, const cv::Mat& picture) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    bool ok = false;
    try {
      ok = cv::imwrite(path, picture);
    } catch (const cv::Exception& e) {
      throw std::runtime_error("cannot write '" + path + "': " + e.what());
    }
    if (!ok) throw std::runtime_error("cannot write '" + path + "'");
    written.push_back(path);
  };
  save("fx.png", component_picture(map, ForceComponent::x, full_scale));
  save("fy.png", component_picture(map, ForceComponent::y, full_scale));
  save("magnitude.png", magnitude_picture(map, full_scale));
  save("arrows.png", arrow_overlay(photo, map, 16, full_scale));
  save("fx.tiff", cv::Mat(map.height, map.width, CV_32FC1, const_cast<float*>(map.fx.data())).clone());
  save("fy.tiff", cv::Mat(map.height, map.width, CV_32FC1, const_cast<float*>(map.fy.data())).clone());
  return written;
}

}  // namespace hapticfield
