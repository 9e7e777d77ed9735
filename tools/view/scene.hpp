#pragma once
/// @file scene.hpp
/// What the viewer shows and the servo loop feels: a field chosen by name
/// with its main parameters (SceneConfig), built from a picture (or the
/// frame of a video shown now) into a Scene (the field plus the picture drawn under the
/// probe). Built on the viewer's thread (allocates, may throw); the field is
/// then handed to the servo thread through a LiveField.
///
/// A video is felt through its own VideoField (see video_player.hpp); the
/// still fields can be built from any of its frames.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "hapticfield/core.hpp"
#include "hapticfield/image.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/normals.hpp"
#include "hapticfield/texture/lattice.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/texture/texture_field.hpp"
#include "hapticfield/video/denoise.hpp"

namespace hapticfield::view {

/// video: a video file felt frame by frame (VideoField); the others are
/// still fields of a picture or of the video frame shown.
enum class FieldKind { tangible, normals, texture, video };

[[nodiscard]] inline const char* field_name(FieldKind k) noexcept {
  switch (k) {
    case FieldKind::tangible:
      return "tangible";
    case FieldKind::normals:
      return "normals";
    case FieldKind::texture:
      return "texture";
    case FieldKind::video:
      return "video";
  }
  return "?";
}

/// The field and its main parameters; the viewer's keys change them.
struct SceneConfig {
  FieldKind kind{FieldKind::tangible};
  // tangible images
  MaskKind mask{MaskKind::prewitt};
  int size{17};  ///< mask size [px]
  Border border{Border::fade};
  double denoise_px{0.0};  ///< Gaussian blur of the picture before the masks, sigma [px]; 0: none
  DenoiseMode video_denoise{DenoiseMode::temporal};  ///< the video's compression-noise filter
  double gain{1.0};                                  ///< force at a black/white edge [N]
  // normals from a picture
  std::vector<std::vector<glm::dvec2>> faces;    ///< 4 corners per face [px]
  double focal_px{0.0};                          ///< focal length [px]; 0: a 60 degree field of view
  double normals_max_force{kim_kwon_max_force};  ///< [N]
  // stochastic texture
  double grain_mm{2.0};      ///< lattice spacing [mm]
  double texture_gain{0.5};  ///< force per texture unit [N]
  std::uint32_t seed{1};
};

/// Mask sizes each mask accepts: (min, max, step).
struct SizeRange {
  int lo, hi, step;
};
[[nodiscard]] inline SizeRange size_range(MaskKind m) noexcept {
  switch (m) {
    case MaskKind::roberts:
      return {2, 2, 1};
    case MaskKind::scharr:
      return {3, 3, 2};
    case MaskKind::sobel:
      return {3, 31, 2};
    default:
      return {3, 129, 2};
  }
}

/// Moves a mask size by `steps` steps within its mask's range.
[[nodiscard]] inline int step_size(MaskKind m, int size, int steps) noexcept {
  const SizeRange r = size_range(m);
  const int s = size + steps * r.step;
  return std::clamp(s, r.lo, r.hi);
}

/// A field and what the viewer draws under the probe.
struct Scene {
  AnyField field;
  cv::Mat underlay;   ///< BGR, the picture's size
  std::string label;  ///< one line: the field and its parameters
};

/// The field the f key goes to after `k`: tangible, normals (with faces),
/// texture, video (for a video source), and round again.
[[nodiscard]] inline FieldKind next_kind(FieldKind k, bool have_faces, bool have_video) noexcept {
  for (int i = 1; i <= 4; ++i) {
    const auto next = static_cast<FieldKind>((static_cast<int>(k) + i) % 4);
    if ((next == FieldKind::normals && !have_faces) || (next == FieldKind::video && !have_video)) continue;
    return next;
  }
  return k;
}

/// What the d key does: the video's denoise mode goes none, temporal,
/// spatial, both, none; a picture's blur sigma goes 0, 1, 2, 4, 0 px.
inline void next_denoise(SceneConfig& c) noexcept {
  if (c.kind == FieldKind::video)
    c.video_denoise = static_cast<DenoiseMode>((static_cast<int>(c.video_denoise) + 1) % 4);
  else
    c.denoise_px = c.denoise_px == 0.0 ? 1.0 : c.denoise_px >= 4.0 ? 0.0 : c.denoise_px * 2.0;
}

/// One line naming the field and its parameters.
[[nodiscard]] inline std::string scene_label(const SceneConfig& c) {
  char label[160];
  switch (c.kind) {
    case FieldKind::tangible:
      std::snprintf(label, sizeof label, "tangible: %s %d px, border %s, denoise %.1f px, %.2f N at an edge",
                    to_string(c.mask), c.size, to_string(c.border), c.denoise_px, c.gain);
      break;
    case FieldKind::normals:
      std::snprintf(label, sizeof label, "normals: %zu face(s), up to %.2f N along the motion", c.faces.size(),
                    c.normals_max_force);
      break;
    case FieldKind::texture:
      std::snprintf(label, sizeof label, "texture: Gaussian lattice %.2f mm, cubic, %.2f N", c.grain_mm,
                    c.texture_gain);
      break;
    case FieldKind::video:
      std::snprintf(label, sizeof label, "video: %s %d px, border %s, denoise %s, %.2f N at an edge", to_string(c.mask),
                    c.size, to_string(c.border), to_string(c.video_denoise), c.gain);
      break;
  }
  return label;
}

namespace detail {

inline AnyField tangible(const cv::Mat& frame, const SceneConfig& c, const PlaneMapping& mapping, cv::Mat& underlay) {
  cv::Mat source;  // a new buffer: the frame itself is never blurred in place
  if (c.denoise_px > 0.0)
    cv::GaussianBlur(frame, source, cv::Size(), c.denoise_px);
  else
    source = frame;
  TangibleConfig options;
  options.mask = c.mask;
  options.size = c.size;
  options.border = c.border;
  underlay = source.clone();
  return AnyField(TangibleImageField(TangibleImage(to_gray(source), options), mapping, c.gain));
}

/// Normal direction as a colour: x to red, y to green, toward the camera to blue.
inline cv::Scalar normal_colour(glm::dvec3 n) {
  return cv::Scalar(127.5 * (1.0 - n.z), 127.5 * (1.0 + n.y), 127.5 * (1.0 + n.x));
}

inline AnyField normals(const cv::Mat& frame, const SceneConfig& c, const PlaneMapping& mapping, cv::Mat& underlay) {
  if (c.faces.empty()) throw std::invalid_argument("--field normals needs at least one --face");
  const Camera camera = c.focal_px > 0.0 ? Camera::from_focal(c.focal_px, Camera::image_centre(frame.cols, frame.rows))
                                         : Camera::from_field_of_view(60.0, frame.cols, frame.rows);
  std::vector<ImageFace> faces;
  cv::Mat tint = frame.clone();
  for (std::size_t i = 0; i < c.faces.size(); ++i) {
    FacePose pose;
    try {
      pose = estimate_rectangle_pose(camera, c.faces[i]);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("face " + std::to_string(i + 1) + ": " + e.what());
    }
    faces.push_back({c.faces[i], pose.normal});
    std::vector<cv::Point> polygon;
    for (const glm::dvec2& p : c.faces[i])
      polygon.emplace_back(cvRound(p.x), cvRound(p.y));
    cv::fillPoly(tint, std::vector<std::vector<cv::Point>>{polygon}, normal_colour(pose.normal));
  }
  cv::addWeighted(frame, 0.45, tint, 0.55, 0.0, underlay);
  NormalFieldConfig options;
  options.max_force = c.normals_max_force;
  return AnyField(NormalField(frame.cols, frame.rows, std::move(faces), options, mapping));
}

inline AnyField texture_field(const cv::Mat& frame, const SceneConfig& c, const PlaneMapping& mapping,
                              cv::Mat& underlay) {
  using namespace hapticfield::texture;
  const double grain = c.grain_mm * 1e-3;  // [m]
  NoiseLattice<GaussianNoise, 2> lattice(GaussianNoise(0.5), c.seed, glm::dvec3{grain}, Interpolation::cubic);
  // the patch: the texture's x and y components over the picture, blue and green
  underlay.create(frame.rows, frame.cols, CV_8UC3);
  for (int y = 0; y < frame.rows; ++y)
    for (int x = 0; x < frame.cols; ++x) {
      const glm::dvec3 g = lattice(mapping.to_device(glm::dvec2{x, y}));
      underlay.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<uchar>(128.0 + 110.0 * g.x), cv::saturate_cast<uchar>(128.0 + 110.0 * g.y), 110);
    }
  TextureConfig params;
  params.gain = c.texture_gain;
  params.axes = {1.0, 1.0, 0.0};
  return AnyField(TextureField(SpatialSource(lattice), params));
}

}  // namespace detail

/// Builds the scene for `frame` (BGR) in the picture's mapping; a video
/// field is built by a VideoPlayer instead.
/// @throws std::invalid_argument for parameters the field refuses, and for
///         FieldKind::video.
[[nodiscard]] inline Scene build_scene(const cv::Mat& frame, const SceneConfig& c, const PlaneMapping& mapping) {
  Scene s;
  switch (c.kind) {
    case FieldKind::tangible:
      s.field = detail::tangible(frame, c, mapping, s.underlay);
      break;
    case FieldKind::normals:
      s.field = detail::normals(frame, c, mapping, s.underlay);
      break;
    case FieldKind::texture:
      s.field = detail::texture_field(frame, c, mapping, s.underlay);
      break;
    case FieldKind::video:
      throw std::invalid_argument("a video field is built from a video, not from one frame");
  }
  s.label = scene_label(c);
  return s;
}

}  // namespace hapticfield::view
