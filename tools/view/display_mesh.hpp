#pragma once
/// @file display_mesh.hpp
/// DisplayMesh: the triangles the 3D view draws, in the device frame [m],
/// in float (drawing needs no more). Built from a TriangleMesh or a height
/// grid, moved by a shift. A mesh over the display budget is decimated for
/// drawing only by vertex clustering (Rossignac & Borrel, "Multi-resolution
/// 3D approximations for rendering complex scenes", 1993): vertices that
/// share a cell of a regular grid become one (their mean) and triangles
/// that collapse are dropped. A height grid over the budget is sampled on a
/// coarser grid. The proxy always feels the full shape.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield::view {

/// The default display budget [triangles].
inline constexpr std::size_t default_display_triangles = 300'000;

struct DisplayMesh {
  std::vector<glm::vec3> positions;                     ///< [m], device frame
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
  std::vector<glm::vec3> face_normals;                  ///< unit, one per triangle (zero: degenerate)
  std::size_t source_triangles{0};                      ///< triangles before decimation
  glm::vec3 lo{0.0f}, hi{0.0f};                         ///< bounding box [m]

  [[nodiscard]] bool decimated() const noexcept { return triangles.size() < source_triangles; }

  /// Face normals and the bounding box, after positions and triangles.
  void finish() {
    face_normals.resize(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const auto& [a, b, c] = triangles[t];
      const glm::vec3 n = glm::cross(positions[b] - positions[a], positions[c] - positions[a]);
      const float length = glm::length(n);
      face_normals[t] = length > 0.0f ? n / length : glm::vec3{0.0f};
    }
    lo = glm::vec3{std::numeric_limits<float>::max()};
    hi = -lo;
    for (const glm::vec3& p : positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    if (positions.empty()) lo = hi = glm::vec3{0.0f};
  }
};

namespace detail {

/// Vertex clustering on an n x n x n grid over the box [lo, hi].
inline DisplayMesh cluster_vertices(const TriangleMesh& mesh, const glm::dvec3& shift, const glm::dvec3& lo,
                                    const glm::dvec3& hi, int n) {
  DisplayMesh out;
  const glm::dvec3 extent = glm::max(hi - lo, glm::dvec3{1e-12});
  std::unordered_map<std::uint64_t, std::uint32_t> cell_vertex;
  std::vector<glm::dvec3> sums;
  std::vector<std::uint32_t> counts;
  std::vector<std::uint32_t> remap(mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const glm::dvec3 q = (mesh.positions[i] - lo) / extent * static_cast<double>(n);
    const auto cell = [&](double v) { return static_cast<std::uint64_t>(std::clamp(v, 0.0, n - 1.0)); };
    const std::uint64_t key =
        (cell(q.x) * static_cast<std::uint64_t>(n) + cell(q.y)) * static_cast<std::uint64_t>(n) + cell(q.z);
    const auto [it, added] = cell_vertex.try_emplace(key, static_cast<std::uint32_t>(sums.size()));
    if (added) {
      sums.emplace_back(0.0);
      counts.push_back(0);
    }
    sums[it->second] += mesh.positions[i];
    ++counts[it->second];
    remap[i] = it->second;
  }
  out.positions.reserve(sums.size());
  for (std::size_t k = 0; k < sums.size(); ++k)
    out.positions.emplace_back(sums[k] / static_cast<double>(counts[k]) + shift);
  for (const TriangleIndices& t : mesh.triangles) {
    const std::uint32_t a = remap[t[0]], b = remap[t[1]], c = remap[t[2]];
    if (a != b && b != c && a != c) out.triangles.push_back({a, b, c});
  }
  return out;
}

}  // namespace detail

/// The mesh moved by `shift` [m], decimated to at most `budget` triangles
/// when it has more.
inline DisplayMesh display_mesh(const TriangleMesh& mesh, const glm::dvec3& shift = glm::dvec3{0.0},
                                std::size_t budget = default_display_triangles) {
  DisplayMesh out;
  if (mesh.triangles.size() <= budget) {
    out.positions.reserve(mesh.positions.size());
    for (const glm::dvec3& p : mesh.positions)
      out.positions.emplace_back(p + shift);
    out.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  } else {
    glm::dvec3 lo{std::numeric_limits<double>::max()}, hi{-std::numeric_limits<double>::max()};
    for (const glm::dvec3& p : mesh.positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    // a surface of T triangles on an n^3 grid keeps about 4 n^2 of them
    // (2 per cell it crosses, about 2 n^2 cells): shrink n until it fits
    int n = std::max(2, static_cast<int>(std::sqrt(static_cast<double>(budget) / 2.0)));
    for (;; n = std::max(2, n * 4 / 5)) {
      out = detail::cluster_vertices(mesh, shift, lo, hi, n);
      if (out.triangles.size() <= budget || n == 2) break;
    }
  }
  out.source_triangles = mesh.triangles.size();
  out.finish();
  return out;
}

/// A height grid as triangles (two per cell, counter-clockwise seen from
/// +z): sample (i, j) at (i spacing_x, j spacing_y, height) + shift [m].
/// Over the budget, every s-th sample along both axes (and the last).
template <class Grid>
DisplayMesh display_height_grid(const Grid& grid, const glm::dvec3& shift = glm::dvec3{0.0},
                                std::size_t budget = default_display_triangles) {
  DisplayMesh out;
  const auto w = static_cast<std::size_t>(grid.width), h = static_cast<std::size_t>(grid.height);
  out.source_triangles = w > 1 && h > 1 ? 2 * (w - 1) * (h - 1) : 0;
  std::size_t step = 1;
  while (2 * ((w - 1) / step + 1) * ((h - 1) / step + 1) > budget)
    ++step;
  std::vector<std::size_t> xs, ys;
  for (std::size_t i = 0; i < w; i += step)
    xs.push_back(i);
  if (xs.back() != w - 1) xs.push_back(w - 1);
  for (std::size_t j = 0; j < h; j += step)
    ys.push_back(j);
  if (ys.back() != h - 1) ys.push_back(h - 1);
  for (const std::size_t j : ys)
    for (const std::size_t i : xs)
      out.positions.emplace_back(glm::dvec3{static_cast<double>(i) * grid.spacing_x,
                                            static_cast<double>(j) * grid.spacing_y, grid.heights[j * w + i]} +
                                 shift);
  const auto nx = static_cast<std::uint32_t>(xs.size());
  for (std::uint32_t j = 0; j + 1 < ys.size(); ++j)
    for (std::uint32_t i = 0; i + 1 < nx; ++i) {
      const std::uint32_t a = j * nx + i, b = a + 1, c = a + 1 + nx, d = a + nx;
      out.triangles.push_back({a, b, c});
      out.triangles.push_back({a, c, d});
    }
  out.finish();
  return out;
}

}  // namespace hapticfield::view
