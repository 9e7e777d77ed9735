#pragma once
/// @file plane_mapping.hpp
/// Mapping between the device's workspace [m] and an image plane [px].
///
/// Device frame (Phantom convention): x to the user's right, y up, z toward
/// the user. Image frame: x right, y down, integer coordinates are pixel
/// centres. By default the image lies in the device's x-y plane, centred on
/// the device origin, image x along device +x and image y along device -y.

#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Kim & Kwon (World Haptics 2013): the device's 100 x 100 mm plane is shown
/// on screen at 6.4 px/mm.
inline constexpr double kim_kwon_px_per_mm = 6.4;  // [px/mm]

class PlaneMapping {
 public:
  /// @param px_per_mm  image pixels per device millimetre [px/mm]
  /// @param origin_px  image point [px] that sits at plane_origin
  /// @param plane_origin  device point [m] where origin_px lies
  /// @param image_x_axis  unit device direction of image +x
  /// @param image_y_axis  unit device direction of image +y (down the picture)
  /// @throws std::invalid_argument for a non-finite or non-positive scale,
  ///         non-finite origins, or axes that are not orthonormal.
  explicit PlaneMapping(double px_per_mm, glm::dvec2 origin_px = glm::dvec2{0.0},
                        glm::dvec3 plane_origin = glm::dvec3{0.0}, glm::dvec3 image_x_axis = glm::dvec3{1.0, 0.0, 0.0},
                        glm::dvec3 image_y_axis = glm::dvec3{0.0, -1.0, 0.0})
      : px_per_m_(px_per_mm * 1000.0),
        origin_px_(origin_px),
        plane_origin_(plane_origin),
        u_(image_x_axis),
        v_(image_y_axis),
        n_(glm::cross(image_y_axis, image_x_axis)) {
    if (!std::isfinite(px_per_mm) || px_per_mm <= 0.0)
      throw std::invalid_argument("PlaneMapping: px_per_mm must be finite and positive");
    const auto finite2 = [](glm::dvec2 a) { return std::isfinite(a.x) && std::isfinite(a.y); };
    const auto finite3 = [](glm::dvec3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); };
    if (!finite2(origin_px) || !finite3(plane_origin))
      throw std::invalid_argument("PlaneMapping: origins must be finite");
    constexpr double tolerance = 1e-9;
    if (!finite3(u_) || !finite3(v_) || std::abs(glm::length(u_) - 1.0) > tolerance ||
        std::abs(glm::length(v_) - 1.0) > tolerance || std::abs(glm::dot(u_, v_)) > tolerance)
      throw std::invalid_argument("PlaneMapping: image axes must be orthonormal device directions");
  }

  /// The normals paper's preset: 6.4 px/mm, image centre at the device origin.
  [[nodiscard]] static PlaneMapping kim_kwon(int image_width, int image_height) {
    return PlaneMapping(kim_kwon_px_per_mm, centre_of(image_width, image_height));
  }

  /// A mapping that fits a width x height image into a square workspace of
  /// side workspace_mm [mm], centred on the device origin.
  [[nodiscard]] static PlaneMapping fit(int image_width, int image_height, double workspace_mm) {
    if (image_width <= 0 || image_height <= 0 || !std::isfinite(workspace_mm) || workspace_mm <= 0.0)
      throw std::invalid_argument("PlaneMapping::fit: image size and workspace must be positive");
    const int longest = image_width > image_height ? image_width : image_height;
    return PlaneMapping(longest / workspace_mm, centre_of(image_width, image_height));
  }

  /// Device position [m] -> image position [px] (projected onto the plane).
  [[nodiscard]] glm::dvec2 to_image(const glm::dvec3& position) const noexcept {
    const glm::dvec3 d = position - plane_origin_;
    return origin_px_ + px_per_m_ * glm::dvec2{glm::dot(d, u_), glm::dot(d, v_)};
  }

  /// Image position [px] -> device position [m] on the plane.
  [[nodiscard]] glm::dvec3 to_device(const glm::dvec2& pixel) const noexcept {
    const glm::dvec2 d = (pixel - origin_px_) / px_per_m_;
    return plane_origin_ + d.x * u_ + d.y * v_;
  }

  /// Device velocity [m/s] -> image-plane velocity [px/s].
  [[nodiscard]] glm::dvec2 velocity_to_image(const glm::dvec3& velocity) const noexcept {
    return px_per_m_ * glm::dvec2{glm::dot(velocity, u_), glm::dot(velocity, v_)};
  }

  /// A vector given in image axes (x right, y down) -> device frame. Units are
  /// kept (a force in N stays in N).
  [[nodiscard]] glm::dvec3 vector_to_device(const glm::dvec2& in_image_axes) const noexcept {
    return in_image_axes.x * u_ + in_image_axes.y * v_;
  }

  /// Signed distance of a device point from the plane [m], positive on the
  /// side the picture is seen from (image y cross image x: toward the user
  /// for the default axes).
  [[nodiscard]] double height_above_plane(const glm::dvec3& position) const noexcept {
    return glm::dot(position - plane_origin_, n_);
  }

  [[nodiscard]] double px_per_mm() const noexcept { return px_per_m_ / 1000.0; }
  [[nodiscard]] glm::dvec2 origin_px() const noexcept { return origin_px_; }
  [[nodiscard]] glm::dvec3 normal() const noexcept { return n_; }

 private:
  static glm::dvec2 centre_of(int width, int height) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("PlaneMapping: image size must be positive");
    return glm::dvec2{(width - 1) / 2.0, (height - 1) / 2.0};
  }

  double px_per_m_;
  glm::dvec2 origin_px_;
  glm::dvec3 plane_origin_;
  glm::dvec3 u_;
  glm::dvec3 v_;
  glm::dvec3 n_;
};

}  // namespace hapticfield
