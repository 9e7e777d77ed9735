#pragma once
/// @file triangle_mesh.hpp
/// TriangleMesh: an indexed triangle mesh in the shape's own frame [m], with
/// optional per-vertex normals and texture coordinates and an optional
/// material index per triangle. Plain data: the file readers (io/) fill it,
/// the acceleration structure and the proxy (surface/) read it. GLM only.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Three vertex indices, counter-clockwise seen from outside (the face
/// normal (b - a) x (c - a) points out of the solid, toward the user).
using TriangleIndices = std::array<std::uint32_t, 3>;

/// The most triangles (and vertices) a mesh may hold: indices are 32-bit and
/// every per-tick structure counts in them.
inline constexpr std::size_t max_mesh_elements = std::size_t{1} << 30;

struct TriangleMesh {
  std::vector<glm::dvec3> positions;       ///< vertex positions [m]
  std::vector<glm::dvec3> normals;         ///< per-vertex unit normals, or empty (face normals only)
  std::vector<glm::dvec2> uvs;             ///< per-vertex texture coordinates (u right, v up), or empty
  std::vector<TriangleIndices> triangles;  ///< indices into positions (and normals, uvs)
  std::vector<std::uint32_t> materials;    ///< a material index per triangle, or empty (all 0)

  [[nodiscard]] std::size_t triangle_count() const noexcept { return triangles.size(); }
  [[nodiscard]] std::size_t vertex_count() const noexcept { return positions.size(); }
  [[nodiscard]] bool has_normals() const noexcept { return !normals.empty(); }
  [[nodiscard]] bool has_uvs() const noexcept { return !uvs.empty(); }

  /// Checks what every consumer relies on: sizes agree, every index is in
  /// range, every position, normal and uv is finite. Degenerate triangles
  /// (zero area) are allowed: the consumers skip them.
  /// @throws std::invalid_argument naming the first offending element.
  void validate() const {
    if (positions.size() > max_mesh_elements || triangles.size() > max_mesh_elements)
      throw std::invalid_argument("TriangleMesh: more than 2^30 vertices or triangles");
    if (!normals.empty() && normals.size() != positions.size())
      throw std::invalid_argument("TriangleMesh: " + std::to_string(normals.size()) + " normals for " +
                                  std::to_string(positions.size()) + " vertices");
    if (!uvs.empty() && uvs.size() != positions.size())
      throw std::invalid_argument("TriangleMesh: " + std::to_string(uvs.size()) + " uvs for " +
                                  std::to_string(positions.size()) + " vertices");
    if (!materials.empty() && materials.size() != triangles.size())
      throw std::invalid_argument("TriangleMesh: " + std::to_string(materials.size()) + " materials for " +
                                  std::to_string(triangles.size()) + " triangles");
    const auto finite3 = [](const glm::dvec3& v) {
      return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    for (std::size_t i = 0; i < positions.size(); ++i)
      if (!finite3(positions[i]))
        throw std::invalid_argument("TriangleMesh: vertex " + std::to_string(i) + " is not finite");
    for (std::size_t i = 0; i < normals.size(); ++i)
      if (!finite3(normals[i]))
        throw std::invalid_argument("TriangleMesh: normal " + std::to_string(i) + " is not finite");
    for (std::size_t i = 0; i < uvs.size(); ++i)
      if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y))
        throw std::invalid_argument("TriangleMesh: uv " + std::to_string(i) + " is not finite");
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (const std::uint32_t k : triangles[t])
        if (k >= positions.size())
          throw std::invalid_argument("TriangleMesh: triangle " + std::to_string(t) + " uses vertex " +
                                      std::to_string(k) + " of " + std::to_string(positions.size()));
  }
};

}  // namespace hapticfield
