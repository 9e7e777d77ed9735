#pragma once
/// @file mesh_render.hpp
/// A software renderer for the 3D view: no GPU, no display. Each frame
/// projects the vertices once through an OrbitCamera, drops the triangles
/// that face away (back-face culling: meshes are counter-clockwise seen from
/// outside) or reach behind the near plane, and fills the rest with a
/// z-buffer of inverse depth (linear in the image, so the depth test is
/// exact for planar triangles). A pixel is covered when its centre is
/// inside the triangle (edge functions, Pineda 1988). Flat Lambert
/// shading: one colour per triangle, ambient plus the cosine to a light
/// that sits above and to the left of the eye.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <opencv2/core.hpp>

#include "view/display_mesh.hpp"
#include "view/orbit_camera.hpp"

namespace hapticfield::view {

struct RenderConfig {
  cv::Vec3f colour{215.0f, 175.0f, 140.0f};  ///< surface colour lit head-on (BGR)
  float ambient{0.25f};                      ///< share of the colour with no light [0, 1]
  cv::Vec3b background{48, 44, 40};          ///< (BGR)
  double near{1e-4};                         ///< triangles with a vertex nearer than this are dropped [m]
};

/// What one frame drew.
struct RenderStats {
  std::size_t drawn{0};   ///< triangles rasterised
  std::size_t culled{0};  ///< facing away, behind the near plane or of no area
  std::size_t pixels{0};  ///< pixels written (a pixel may be written more than once)
};

/// The image and its depth buffer, kept between frames (no allocation per
/// frame once sized).
struct RenderTarget {
  cv::Mat image;                     ///< CV_8UC3, the camera's width x height
  std::vector<float> inverse_depth;  ///< 1 / depth [1/m] per pixel; 0: nothing drawn
  std::vector<glm::vec3> screen;     ///< per vertex: x, y [px], 1 / depth (0: behind the near plane)

  /// The inverse depth at pixel (x, y) [1/m], 0 where nothing was drawn.
  [[nodiscard]] float depth_at(int x, int y) const {
    return inverse_depth[static_cast<std::size_t>(y) * image.cols + x];
  }
};

/// Draws `mesh` as `camera` sees it into `target` (cleared first).
inline RenderStats render_mesh(const DisplayMesh& mesh, const OrbitCamera& camera, RenderTarget& target,
                               const RenderConfig& config = {}) {
  const int w = camera.width, h = camera.height;
  target.image.create(h, w, CV_8UC3);
  target.image.setTo(cv::Scalar(config.background[0], config.background[1], config.background[2]));
  target.inverse_depth.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0.0f);
  target.screen.resize(mesh.positions.size());
  // vertices: camera frame in double, stored in float
  const glm::dvec3 eye = camera.eye(), f = camera.forward(), r = camera.right(), u = camera.up();
  const double focal = camera.focal(), cx = 0.5 * w, cy = 0.5 * h;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const glm::dvec3 c = glm::dvec3(mesh.positions[i]) - eye;
    const double z = glm::dot(c, f);
    if (!(z > config.near)) {
      target.screen[i] = glm::vec3{0.0f};
      continue;
    }
    const double s = focal / z;
    target.screen[i] = glm::vec3{static_cast<float>(cx + s * glm::dot(c, r)),
                                 static_cast<float>(cy - s * glm::dot(c, u)), static_cast<float>(1.0 / z)};
  }
  // the light: above and to the left of the eye, toward the scene
  const glm::vec3 light = glm::vec3(glm::normalize(-f + 0.45 * u - 0.35 * r));
  RenderStats stats;
  auto* pixels = target.image.ptr<cv::Vec3b>(0);
  float* depth = target.inverse_depth.data();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [ia, ib, ic] = mesh.triangles[t];
    const glm::vec3 a = target.screen[ia], b = target.screen[ib], c = target.screen[ic];
    if (a.z == 0.0f || b.z == 0.0f || c.z == 0.0f) {
      ++stats.culled;
      continue;
    }
    // twice the signed area; image y points down, so a triangle that is
    // counter-clockwise toward the eye has a negative one
    const float area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if (!(area < 0.0f)) {
      ++stats.culled;
      continue;
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}) - 0.5f)));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}) - 0.5f)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}) - 0.5f)));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}) - 0.5f)));
    if (x0 > x1 || y0 > y1) {
      ++stats.culled;
      continue;
    }
    ++stats.drawn;
    const float lit = config.ambient + (1.0f - config.ambient) * std::max(0.0f, glm::dot(mesh.face_normals[t], light));
    const cv::Vec3b colour(cv::saturate_cast<std::uint8_t>(config.colour[0] * lit),
                           cv::saturate_cast<std::uint8_t>(config.colour[1] * lit),
                           cv::saturate_cast<std::uint8_t>(config.colour[2] * lit));
    // edge functions, positive inside (the area is negative)
    const float inv = 1.0f / area;
    const auto edge = [](const glm::vec3& p, const glm::vec3& q, float x, float y) {
      return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
    };
    for (int y = y0; y <= y1; ++y) {
      const float py = static_cast<float>(y) + 0.5f;
      for (int x = x0; x <= x1; ++x) {
        const float px = static_cast<float>(x) + 0.5f;
        const float wa = edge(b, c, px, py) * inv, wb = edge(c, a, px, py) * inv, wc = edge(a, b, px, py) * inv;
        if (wa < 0.0f || wb < 0.0f || wc < 0.0f) continue;
        const float z = wa * a.z + wb * b.z + wc * c.z;  // 1 / depth, linear in the image
        const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
        if (z <= depth[k]) continue;
        depth[k] = z;
        pixels[k] = colour;
        ++stats.pixels;
      }
    }
  }
  return stats;
}

}  // namespace hapticfield::view
