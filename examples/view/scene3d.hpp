#pragma once
/// @file scene3d.hpp
/// One frame of the 3D view of a shape: the shaded surface (mesh_render.hpp)
/// and on top of it, always visible (drawn over the surface): the proxy as
/// a filled magenta dot, the HIP (the handle's position) as a green ring,
/// the line between them, and the commanded force as an arrow from the HIP
/// with a fixed scale (the legend bar in the corner is 1 N; the arrow is the
/// force's component in the image plane). Viewer thread only.

#include <algorithm>
#include <cmath>
#include <cstdio>
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
  RenderConfig render{};
};

/// Where the markers ended up in the image [px] (for checks and reports).
struct Scene3dMarks {
  cv::Point proxy{-1, -1};
  cv::Point hip{-1, -1};
  RenderStats stats{};
};

namespace detail {
inline cv::Point to_point(const glm::dvec2& p) {
  const auto clampi = [](double v) { return static_cast<int>(std::lround(std::clamp(v, -1e6, 1e6))); };
  return {clampi(p.x - 0.5), clampi(p.y - 0.5)};  // the pixel whose centre is nearest
}
}  // namespace detail

/// Draws the shape, the proxy, the HIP and the force into target.image.
inline Scene3dMarks draw_scene3d(RenderTarget& target, const DisplayMesh& mesh, const OrbitCamera& camera,
                                 const Sample3d& now, const Scene3dConfig& config = {}) {
  Scene3dMarks marks;
  marks.stats = render_mesh(mesh, camera, target, config.render);
  cv::Mat& image = target.image;
  const Projected hip = camera.project(now.hip), proxy = camera.project(now.proxy);
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
  if (proxy.depth > 0.0) {
    marks.proxy = detail::to_point(proxy.pixel);
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
  text("proxy (dot)  HIP (ring)", {x + bar + 100, y + 5});
  char line[160];
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
