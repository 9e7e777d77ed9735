#pragma once
/// @file box_stimulus.hpp
/// Synthetic version of Kim & Kwon's (World Haptics 2013) accuracy stimulus:
/// a textured box with 20 cm edges rotated about its vertical axis (15 to 75
/// degrees in 5-degree steps in the paper), seen by a known pinhole camera
/// from slightly above. Gives the picture and the exact corners and outward
/// normals of the two visible side faces. Setup / offline code.

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/normals/camera.hpp"

namespace hapticfield {

/// The camera and box of the synthetic stimulus.
struct BoxScene {
  int width = 1024;             ///< picture width [px]
  int height = 768;             ///< picture height [px]
  double focal_px = 1000.0;     ///< focal length [px] (square pixels, centred principal point)
  double edge_mm = 200.0;       ///< box edge [mm] (the paper's 20 cm box)
  double distance_mm = 800.0;   ///< camera centre to box centre [mm]
  double elevation_deg = 20.0;  ///< camera looks down on the box by this angle [deg]

  [[nodiscard]] Camera camera() const { return Camera::from_focal(focal_px, Camera::image_centre(width, height)); }
};

/// One rendered view: the picture and the two visible side faces.
struct BoxView {
  double rotation_deg = 0.0;                           ///< rotation about the box's vertical axis [deg]
  cv::Mat picture;                                     ///< BGR picture (empty when not drawn)
  std::array<std::array<glm::dvec2, 4>, 2> corners{};  ///< exact pixel corners: [0] front, [1] side
  std::array<glm::dvec3, 2> normals{};                 ///< true outward unit normals, camera frame
};

/// The paper's rotations: 15, 20, ..., 75 degrees.
[[nodiscard]] inline std::vector<double> box_rotations() {
  std::vector<double> r;
  for (int a = 15; a <= 75; a += 5)
    r.push_back(a);
  return r;
}

namespace detail {

/// Box (local) -> camera rotation: yaw theta about the box's vertical axis
/// (local y, down), then the camera's downward pitch.
inline cv::Matx33d box_rotation(double rotation_deg, double elevation_deg) noexcept {
  const double t = rotation_deg * std::numbers::pi / 180.0;
  const double e = elevation_deg * std::numbers::pi / 180.0;
  const cv::Matx33d yaw(std::cos(t), 0.0, std::sin(t), 0.0, 1.0, 0.0, -std::sin(t), 0.0, std::cos(t));
  const cv::Matx33d pitch(1.0, 0.0, 0.0, 0.0, std::cos(e), -std::sin(e), 0.0, std::sin(e), std::cos(e));
  return pitch * yaw;
}

/// A procedural face texture: checks of two tones with a coloured border
/// and diagonal stripes, so the warp is visible [BGR].
inline cv::Mat face_texture(int size, cv::Scalar a, cv::Scalar b) {
  cv::Mat tex(size, size, CV_8UC3);
  const int check = size / 8;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool dark = ((x / check) + (y / check)) % 2 == 0;
      const bool stripe = ((x + y) / (check / 2)) % 5 == 0;
      const cv::Scalar c = stripe ? 0.5 * (a + b) : (dark ? a : b);
      tex.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]), cv::saturate_cast<uchar>(c[2]));
    }
  cv::rectangle(tex, cv::Rect(0, 0, size, size), cv::Scalar(40, 40, 40), size / 32);
  return tex;
}

}  // namespace detail

/// Renders the box rotated by rotation_deg about its vertical axis.
/// Faces (box frame, y down): front z = -a, side x = +a, top y = -a. The
/// corners of each side face are listed top-left, top-right, bottom-right,
/// bottom-left as seen from outside, so they map to (0,0), (W,0), (W,H),
/// (0,H) with W = H = edge_mm.
/// @throws std::invalid_argument when a side face is not visible.
[[nodiscard]] inline BoxView render_box(const BoxScene& scene, double rotation_deg, bool draw = true) {
  const cv::Matx33d R = detail::box_rotation(rotation_deg, scene.elevation_deg);
  const cv::Vec3d centre(0.0, 0.0, scene.distance_mm);
  const cv::Matx33d K = scene.camera().matrix();
  const double a = scene.edge_mm / 2.0;
  const auto project = [&](cv::Vec3d local) {
    const cv::Vec3d c = R * local + centre;
    const cv::Vec3d p = K * c;
    return glm::dvec2{p[0] / p[2], p[1] / p[2]};
  };
  struct FaceDef {
    std::array<cv::Vec3d, 4> corners;
    cv::Vec3d outward;
  };
  const std::array<FaceDef, 3> faces{{
      {{cv::Vec3d(-a, -a, -a), cv::Vec3d(a, -a, -a), cv::Vec3d(a, a, -a), cv::Vec3d(-a, a, -a)},
       cv::Vec3d(0, 0, -1)},  // front
      {{cv::Vec3d(a, -a, -a), cv::Vec3d(a, -a, a), cv::Vec3d(a, a, a), cv::Vec3d(a, a, -a)},
       cv::Vec3d(1, 0, 0)},  // side
      {{cv::Vec3d(-a, -a, a), cv::Vec3d(a, -a, a), cv::Vec3d(a, -a, -a), cv::Vec3d(-a, -a, -a)},
       cv::Vec3d(0, -1, 0)},  // top
  }};
  BoxView view;
  view.rotation_deg = rotation_deg;
  std::array<bool, 3> visible{};
  for (std::size_t f = 0; f < 3; ++f) {
    const cv::Vec3d n = R * faces[f].outward;
    const cv::Vec3d c = R * (a * faces[f].outward) + centre;
    visible[f] = n.dot(c) < 0.0;
    if (f < 2) {
      view.normals[f] = glm::dvec3{n[0], n[1], n[2]};
      for (std::size_t k = 0; k < 4; ++k)
        view.corners[f][k] = project(faces[f].corners[k]);
    }
  }
  if (!visible[0] || !visible[1])
    throw std::invalid_argument("render_box: rotation_deg must leave both side faces visible (0..90 exclusive)");
  if (!draw) return view;

  view.picture = cv::Mat(scene.height, scene.width, CV_8UC3, cv::Scalar(200, 200, 200));
  // a floor line and a soft gradient so the background is not flat
  for (int y = 0; y < scene.height; ++y)
    view.picture.row(y).setTo(cv::Scalar(215 - 40.0 * y / scene.height, 205 - 30.0 * y / scene.height, 190));
  const std::array<std::array<cv::Scalar, 2>, 3> tones{{{cv::Scalar(60, 90, 200), cv::Scalar(150, 180, 240)},
                                                        {cv::Scalar(200, 120, 50), cv::Scalar(240, 200, 150)},
                                                        {cv::Scalar(70, 160, 70), cv::Scalar(170, 230, 170)}}};
  const cv::Vec3d light = cv::normalize(cv::Vec3d(-0.3, -1.0, -0.6));
  constexpr int tex_size = 256;
  for (std::size_t f = 0; f < 3; ++f) {
    if (!visible[f]) continue;
    const cv::Vec3d n = R * faces[f].outward;
    const double shade = 0.55 + 0.45 * std::max(0.0, n.dot(light));
    cv::Mat tex = detail::face_texture(tex_size, tones[f][0] * shade, tones[f][1] * shade);
    std::array<cv::Point2f, 4> src{cv::Point2f(-0.5f, -0.5f), cv::Point2f(tex_size - 0.5f, -0.5f),
                                   cv::Point2f(tex_size - 0.5f, tex_size - 0.5f), cv::Point2f(-0.5f, tex_size - 0.5f)};
    std::array<cv::Point2f, 4> dst{};
    std::vector<cv::Point> poly;
    for (std::size_t k = 0; k < 4; ++k) {
      const glm::dvec2 p = project(faces[f].corners[k]);
      dst[k] = cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y));
      poly.emplace_back(cvRound(p.x * 16.0), cvRound(p.y * 16.0));
    }
    const cv::Mat H = cv::getPerspectiveTransform(src.data(), dst.data());
    cv::Mat warped;
    cv::warpPerspective(tex, warped, H, view.picture.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::Mat mask = cv::Mat::zeros(view.picture.size(), CV_8U);
    cv::fillConvexPoly(mask, poly, cv::Scalar(255), cv::LINE_AA, 4);
    cv::Mat m3;
    cv::cvtColor(mask, m3, cv::COLOR_GRAY2BGR);
    cv::Mat pic_f;
    cv::Mat warp_f;
    cv::Mat alpha;
    view.picture.convertTo(pic_f, CV_32FC3);
    warped.convertTo(warp_f, CV_32FC3);
    m3.convertTo(alpha, CV_32FC3, 1.0 / 255.0);
    pic_f = pic_f.mul(cv::Scalar::all(1.0) - alpha) + warp_f.mul(alpha);
    pic_f.convertTo(view.picture, CV_8UC3);
  }
  return view;
}

/// Angle between two directions [deg].
[[nodiscard]] inline double angle_between_deg(glm::dvec3 a, glm::dvec3 b) noexcept {
  const double c = glm::dot(glm::normalize(a), glm::normalize(b));
  const double s = glm::length(glm::cross(glm::normalize(a), glm::normalize(b)));
  return std::atan2(s, c) * 180.0 / std::numbers::pi;
}

}  // namespace hapticfield
