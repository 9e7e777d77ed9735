#pragma once
/// @file scene3d.hpp
/// One frame of the 3D view of a shape: the shaded surface (mesh_render.hpp)
/// and on top of it, always visible (drawn over the surface): the proxy as
/// a filled magenta dot, or for a tool of radius r > 0 (ProxyConfig::radius)
/// as a magenta ball of that radius centred on the proxy (each pixel's ray
/// meets the sphere: the true perspective outline, Lambert-shaded under the
/// surface's light; a ball under the dot's size gets the dot as well), the
/// HIP (the handle's position) as a green ring, the line between them, and
/// the commanded force as an arrow from the HIP with a fixed scale (the
/// legend bar in the corner is 1 N; the arrow is the force's component in
/// the image plane). Viewer thread only.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <opencv2/imgproc.hpp>

#include "view/display_mesh.hpp"
#include "view/mesh_render.hpp"
#include "view/orbit_camera.hpp"

namespace hapticfield::view {

/// The proxy's fill colour (BGR): pure magenta, drawn without smoothing.
inline const cv::Scalar proxy_colour(255, 0, 255);
/// The HIP ring's colour (BGR): pure green, drawn without smoothing.
inline const cv::Scalar hip_colour(0, 255, 0);
/// The force arrow's colour (BGR).
inline const cv::Scalar force_colour(0, 200, 255);
/// Radius of the proxy dot and of the HIP ring [px].
inline constexpr int proxy_radius_px = 4;
inline constexpr int hip_radius_px = 8;

/// One servo tick as the 3D view draws it (device frame).
struct Sample3d {
  double t{0.0};          ///< loop time [s]
  glm::dvec3 hip{0.0};    ///< the handle [m]
  glm::dvec3 proxy{0.0};  ///< the proxy on the surface [m] (the HIP when free)
  glm::dvec3 force{0.0};  ///< commanded force [N]
  bool touching{false};
};

struct Scene3dConfig {
  double px_per_newton{60.0};  ///< arrow length per newton [px]
  double arrow_max_px{200.0};  ///< longest arrow [px]
  double tip_radius{0.0};      ///< the tool's radius [m]: 0 a dot, > 0 a ball at the proxy
  RenderConfig render{};
};

/// Where the markers ended up in the image [px] (for checks and reports).
struct Scene3dMarks {
  cv::Point proxy{-1, -1};
  cv::Point hip{-1, -1};
  std::size_t ball_pixels{0};  ///< pixels the tool's ball covers (0: drawn as a dot)
  RenderStats stats{};
};

namespace detail {
inline cv::Point to_point(const glm::dvec2& p) {
  const auto clampi = [](double v) { return static_cast<int>(std::lround(std::clamp(v, -1e6, 1e6))); };
  return {clampi(p.x - 0.5), clampi(p.y - 0.5)};  // the pixel whose centre is nearest
}

/// Draws the ball of `radius` [m] about `centre` (device frame) as `camera`
/// sees it: every pixel whose centre's ray meets the sphere, coloured
/// `colour` times ambient plus the cosine to mesh_render's light at the
/// nearer hit. Nothing when the eye is inside the ball or it is behind the
/// eye. Returns the pixels drawn.
inline std::size_t draw_ball(cv::Mat& image, const OrbitCamera& camera, const glm::dvec3& centre, double radius,
                             const cv::Scalar& colour, float ambient) {
  const glm::dvec3 eye = camera.eye(), f = camera.forward(), r = camera.right(), u = camera.up();
  const glm::dvec3 c = centre - eye;
  const double depth = glm::dot(c, f);
  if (!(radius > 0.0) || !(depth > radius) || glm::length(c) <= radius) return 0;
  // the ball lies in the box about it (camera axes), all in front of the eye:
  // the box's corners bound its image
  const double x = glm::dot(c, r), y = glm::dot(c, u), focal = camera.focal();
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (const double dz : {-radius, radius})
    for (const double dx : {-radius, radius})
      for (const double dy : {-radius, radius}) {
        const double s = focal / (depth + dz);
        const double px = 0.5 * camera.width + s * (x + dx), py = 0.5 * camera.height - s * (y + dy);
        x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
      }
  const int i0 = std::max(0, static_cast<int>(std::floor(x0))), i1 = std::min(image.cols - 1, static_cast<int>(x1));
  const int j0 = std::max(0, static_cast<int>(std::floor(y0))), j1 = std::min(image.rows - 1, static_cast<int>(y1));
  const glm::dvec3 light = glm::normalize(-f + 0.45 * u - 0.35 * r);  // as mesh_render's
  std::size_t drawn = 0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const glm::dvec3 ray = glm::normalize(camera.unproject({i + 0.5, j + 0.5}, 1.0) - eye);
      const double b = glm::dot(ray, c), q = b * b - (glm::dot(c, c) - radius * radius);
      if (q < 0.0) continue;
      const glm::dvec3 normal = (ray * (b - std::sqrt(q)) - c) / radius;
      const double lit = ambient + (1.0 - ambient) * std::max(0.0, glm::dot(normal, light));
      image.at<cv::Vec3b>(j, i) =
          cv::Vec3b(cv::saturate_cast<std::uint8_t>(colour[0] * lit), cv::saturate_cast<std::uint8_t>(colour[1] * lit),
                    cv::saturate_cast<std::uint8_t>(colour[2] * lit));
      ++drawn;
    }
  return drawn;
}
}  // namespace detail

/// Draws the shape, the proxy, the HIP and the force into target.image.
inline Scene3dMarks draw_scene3d(RenderTarget& target, const DisplayMesh& mesh, const OrbitCamera& camera,
                                 const Sample3d& now, const Scene3dConfig& config = {}) {
  Scene3dMarks marks;
  marks.stats = render_mesh(mesh, camera, target, config.render);
  cv::Mat& image = target.image;
  const Projected hip = camera.project(now.hip), proxy = camera.project(now.proxy);
  // the ball first: the HIP inside it, the line and the arrow stay visible
  if (config.tip_radius > 0.0)
    marks.ball_pixels =
        detail::draw_ball(image, camera, now.proxy, config.tip_radius, proxy_colour, config.render.ambient);
  if (hip.depth > 0.0 && proxy.depth > 0.0)
    cv::line(image, detail::to_point(hip.pixel), detail::to_point(proxy.pixel), cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
  if (hip.depth > 0.0) {
    marks.hip = detail::to_point(hip.pixel);
    glm::dvec2 arrow{glm::dot(now.force, camera.right()), -glm::dot(now.force, camera.up())};
    arrow *= config.px_per_newton;
    if (const double len = glm::length(arrow); len > config.arrow_max_px) arrow *= config.arrow_max_px / len;
    if (glm::length(arrow) >= 3.0) {
      const cv::Point tip =
          marks.hip + cv::Point(static_cast<int>(std::lround(arrow.x)), static_cast<int>(std::lround(arrow.y)));
      cv::arrowedLine(image, marks.hip, tip, cv::Scalar(0, 0, 0), 4, cv::LINE_AA, 0, 0.2);
      cv::arrowedLine(image, marks.hip, tip, force_colour, 2, cv::LINE_AA, 0, 0.2);
    }
    cv::circle(image, marks.hip, hip_radius_px, hip_colour, 2, cv::LINE_8);
  }
  if (proxy.depth > 0.0) marks.proxy = detail::to_point(proxy.pixel);
  constexpr double dot_area = std::numbers::pi * proxy_radius_px * proxy_radius_px;
  if (proxy.depth > 0.0 && static_cast<double>(marks.ball_pixels) < dot_area) {
    cv::circle(image, marks.proxy, proxy_radius_px + 1, cv::Scalar(0, 0, 0), 1, cv::LINE_8);
    cv::circle(image, marks.proxy, proxy_radius_px, proxy_colour, cv::FILLED, cv::LINE_8);
  }
  // legend: the 1 N bar, the markers, and what is drawn
  const int x = 12, y = image.rows - 14;
  const int bar = static_cast<int>(std::lround(config.px_per_newton));
  cv::line(image, {x, y}, {x + bar, y}, force_colour, 3, cv::LINE_8);
  cv::line(image, {x, y - 5}, {x, y + 5}, force_colour, 1, cv::LINE_8);
  cv::line(image, {x + bar, y - 5}, {x + bar, y + 5}, force_colour, 1, cv::LINE_8);
  const auto text = [&](const std::string& s, cv::Point at) {
    cv::putText(image, s, at, cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
  };
  text("force: 1 N", {x + bar + 8, y + 5});
  char line[160];
  if (config.tip_radius > 0.0)
    std::snprintf(line, sizeof line, "proxy (ball, r %.3g mm)  HIP (ring)", config.tip_radius * 1e3);
  else
    std::snprintf(line, sizeof line, "proxy (dot)  HIP (ring)");
  text(line, {x + bar + 100, y + 5});
  if (mesh.decimated())
    std::snprintf(line, sizeof line, "%zu of %zu triangles drawn (decimated for display; felt in full)",
                  mesh.triangles.size(), mesh.source_triangles);
  else
    std::snprintf(line, sizeof line, "%zu triangles", mesh.triangles.size());
  text(line, {x, 20});
  std::snprintf(line, sizeof line, "HIP %+.1f %+.1f %+.1f mm%s", now.hip.x * 1e3, now.hip.y * 1e3, now.hip.z * 1e3,
                now.touching ? "  touching" : "");
  text(line, {x, 38});
  return marks;
}

}  // namespace hapticfield::view
