#pragma once
/// @file camera.hpp
/// Pinhole camera intrinsics K and lens distortion for the normals-from-a-
/// picture estimation (Kim & Kwon, World Haptics 2013): from an OpenCV
/// calibration file, from a focal length and principal point, or guessed
/// from a field of view. Setup code: may allocate and throw.

#include <cmath>
#include <filesystem>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <glm/vec2.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace hapticfield {

/// Camera intrinsics: K = [fx s cx; 0 fy cy; 0 0 1] [px] and OpenCV
/// distortion coefficients (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]]).
/// Pixel convention as OpenCV: x right, y down, integer coordinates are
/// pixel centres.
class Camera {
 public:
  /// From focal lengths and principal point [px].
  /// @throws std::invalid_argument for a non-positive or non-finite focal
  ///         length or a non-finite principal point.
  Camera(double fx, double fy, glm::dvec2 centre, std::vector<double> distortion = {})
      : Camera(cv::Matx33d(fx, 0.0, centre.x, 0.0, fy, centre.y, 0.0, 0.0, 1.0),
               std::move(distortion)) {}

  /// From a full 3x3 camera matrix and optional distortion coefficients.
  /// @throws std::invalid_argument when K is not finite, not upper
  ///         triangular with K(2,2) = 1, or a focal length is not positive,
  ///         or the number of distortion coefficients is not 4, 5, 8, 12 or 14.
  explicit Camera(const cv::Matx33d& K, std::vector<double> distortion = {})
      : K_(K), distortion_(std::move(distortion)) {
    for (int i = 0; i < 9; ++i)
      if (!std::isfinite(K.val[i]))
        throw std::invalid_argument("Camera: camera matrix entries must be finite");
    if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0))
      throw std::invalid_argument("Camera: focal length must be positive [px]");
    if (K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
      throw std::invalid_argument("Camera: camera matrix must be [fx s cx; 0 fy cy; 0 0 1]");
    const std::size_t n = distortion_.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
      throw std::invalid_argument(
          "Camera: distortion_coefficients must have 4, 5, 8, 12 or 14 entries");
    for (double d : distortion_)
      if (!std::isfinite(d))
        throw std::invalid_argument("Camera: distortion coefficients must be finite");
    bool any = false;
    for (double d : distortion_) any = any || d != 0.0;
    if (!any) distortion_.clear();
  }

  /// Square pixels: fx = fy = focal [px], principal point centre [px].
  [[nodiscard]] static Camera from_focal(double focal, glm::dvec2 centre) {
    if (!std::isfinite(focal) || focal <= 0.0)
      throw std::invalid_argument(
          "Camera::from_focal: focal length must be finite and positive [px]");
    if (!std::isfinite(centre.x) || !std::isfinite(centre.y))
      throw std::invalid_argument("Camera::from_focal: principal point must be finite [px]");
    return Camera(focal, focal, centre);
  }

  /// A guess for an uncalibrated picture: square pixels, principal point at
  /// the image centre ((w-1)/2, (h-1)/2), focal length from the horizontal
  /// field of view: f = (w/2) / tan(hfov/2) [px].
  [[nodiscard]] static Camera from_field_of_view(double horizontal_fov_deg, int width, int height) {
    if (width <= 0 || height <= 0)
      throw std::invalid_argument("Camera::from_field_of_view: image size must be positive [px]");
    if (!std::isfinite(horizontal_fov_deg) || horizontal_fov_deg <= 0.0 ||
        horizontal_fov_deg >= 180.0)
      throw std::invalid_argument(
          "Camera::from_field_of_view: horizontal field of view must be in (0, 180) [deg]");
    const double half = horizontal_fov_deg * std::numbers::pi / 360.0;
    return from_focal(0.5 * width / std::tan(half), image_centre(width, height));
  }

  /// Reads an OpenCV calibration file (YAML, XML or JSON written with
  /// cv::FileStorage, as after cv::calibrateCamera): the 3x3 node
  /// `camera_matrix` and optionally `distortion_coefficients` (also accepted:
  /// `dist_coeffs`, `distortion`), `image_width`, `image_height`.
  /// @throws std::invalid_argument when the file cannot be read, the camera
  ///         matrix is missing or not 3x3, or its values are invalid.
  [[nodiscard]] static Camera from_file(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw std::invalid_argument("Camera::from_file: cannot open calibration file '" + path + "'");
    cv::FileStorage fs;
    try {
      if (!fs.open(path, cv::FileStorage::READ))
        throw std::invalid_argument("Camera::from_file: cannot open calibration file '" + path +
                                    "'");
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("Camera::from_file: cannot parse calibration file '" + path +
                                  "': " + e.what());
    }
    cv::Mat k;
    cv::Mat d;
    int width = 0;
    int height = 0;
    try {
      fs["camera_matrix"] >> k;
      for (const char* name : {"distortion_coefficients", "dist_coeffs", "distortion"}) {
        if (!fs[name].empty()) {
          fs[name] >> d;
          break;
        }
      }
      if (!fs["image_width"].empty()) fs["image_width"] >> width;
      if (!fs["image_height"].empty()) fs["image_height"] >> height;
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("Camera::from_file: bad content in '" + path + "': " + e.what());
    }
    if (k.empty())
      throw std::invalid_argument("Camera::from_file: no 'camera_matrix' node in '" + path + "'");
    if (k.rows != 3 || k.cols != 3 || k.channels() != 1)
      throw std::invalid_argument("Camera::from_file: 'camera_matrix' in '" + path +
                                  "' must be 3x3");
    cv::Mat k64;
    k.convertTo(k64, CV_64F);
    std::vector<double> dist;
    if (!d.empty()) {
      if (d.channels() != 1 || (d.rows != 1 && d.cols != 1))
        throw std::invalid_argument("Camera::from_file: 'distortion_coefficients' in '" + path +
                                    "' must be a vector");
      cv::Mat d64;
      d.convertTo(d64, CV_64F);
      dist.assign(d64.begin<double>(), d64.end<double>());
    }
    Camera camera(cv::Matx33d(k64.ptr<double>()), std::move(dist));
    camera.width_ = width;
    camera.height_ = height;
    return camera;
  }

  /// Writes K and the distortion in the layout from_file() reads.
  void save(const std::string& path) const {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw std::invalid_argument("Camera::save: cannot write '" + path + "'");
    if (width_ > 0) fs << "image_width" << width_;
    if (height_ > 0) fs << "image_height" << height_;
    fs << "camera_matrix" << cv::Mat(K_);
    fs << "distortion_coefficients"
       << cv::Mat(distortion_.empty() ? std::vector<double>(5, 0.0) : distortion_);
  }

  /// The same camera for the picture resized by (sx, sy): focal lengths and
  /// skew scale, the principal point maps pixel centres
  /// (c' = (c + 0.5) s - 0.5); distortion is unchanged (it acts on
  /// normalised coordinates). The recorded image size scales too.
  /// @throws std::invalid_argument for a non-finite or non-positive factor.
  [[nodiscard]] Camera scaled(double sx, double sy) const {
    if (!std::isfinite(sx) || !std::isfinite(sy) || sx <= 0.0 || sy <= 0.0)
      throw std::invalid_argument("Camera::scaled: scale factors must be finite and positive");
    cv::Matx33d k = K_;
    k(0, 0) *= sx;
    k(0, 1) *= sx;
    k(0, 2) = (k(0, 2) + 0.5) * sx - 0.5;
    k(1, 1) *= sy;
    k(1, 2) = (k(1, 2) + 0.5) * sy - 0.5;
    Camera c(k, distortion_);
    c.width_ = static_cast<int>(std::lround(width_ * sx));
    c.height_ = static_cast<int>(std::lround(height_ * sy));
    return c;
  }

  /// The camera matrix K [px].
  [[nodiscard]] const cv::Matx33d& matrix() const noexcept { return K_; }
  /// Distortion coefficients (empty when the lens is ideal).
  [[nodiscard]] const std::vector<double>& distortion() const noexcept { return distortion_; }
  [[nodiscard]] bool has_distortion() const noexcept { return !distortion_.empty(); }
  /// Image size recorded in the calibration file [px] (0 when unknown).
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }

  /// Distorted pixel positions -> ideal (undistorted) pixel positions seen
  /// through the same K. Returns the points unchanged without distortion.
  [[nodiscard]] std::vector<glm::dvec2> undistort(std::span<const glm::dvec2> pixels) const {
    std::vector<glm::dvec2> out(pixels.begin(), pixels.end());
    if (distortion_.empty() || out.empty()) return out;
    std::vector<cv::Point2d> src;
    src.reserve(out.size());
    for (auto p : out) src.emplace_back(p.x, p.y);
    std::vector<cv::Point2d> dst;
    cv::undistortPoints(src, dst, cv::Mat(K_), cv::Mat(distortion_), cv::noArray(), cv::Mat(K_));
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = glm::dvec2{dst[i].x, dst[i].y};
    return out;
  }

  /// The centre of a width x height image in the pixel-centre convention [px].
  [[nodiscard]] static glm::dvec2 image_centre(int width, int height) noexcept {
    return glm::dvec2{(width - 1) / 2.0, (height - 1) / 2.0};
  }

 private:
  cv::Matx33d K_;
  std::vector<double> distortion_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace hapticfield
