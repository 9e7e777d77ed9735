#pragma once
// Generated meshes for the surface tests and benches: tessellated grids,
// boxes, icospheres and wavy sheets, each with closed-form geometry to
// check against.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec2.hpp>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield::test {

/// A probe at position [m] moving at velocity [m/s].
inline Probe probe_at(glm::dvec3 position, glm::dvec3 velocity = glm::dvec3{0.0}) {
  Probe p;
  p.position = position;
  p.velocity = velocity;
  return p;
}

/// Appends an nu x nv grid of quads (two triangles each) spanning
/// origin + [0, 1] u_axis + [0, 1] v_axis, facing u_axis x v_axis, with uvs
/// (0..1) along the two axes.
inline void add_grid(TriangleMesh& mesh, glm::dvec3 origin, glm::dvec3 u_axis, glm::dvec3 v_axis, int nu, int nv) {
  const auto base = static_cast<std::uint32_t>(mesh.positions.size());
  const bool uvs = mesh.uvs.size() == mesh.positions.size();
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double s = static_cast<double>(i) / nu, t = static_cast<double>(j) / nv;
      mesh.positions.push_back(origin + s * u_axis + t * v_axis);
      if (uvs) mesh.uvs.emplace_back(s, t);
    }
  const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

/// A flat square sheet of side `side` [m] in the plane z = height, centred
/// on the z axis, facing +z, 2 n^2 triangles, with uvs.
inline TriangleMesh flat_sheet(double side, int n, double height = 0.0) {
  TriangleMesh mesh;  // empty: add_grid keeps uvs in step with the positions
  add_grid(mesh, {-side / 2, -side / 2, height}, {side, 0, 0}, {0, side, 0}, n, n);
  return mesh;
}

/// An axis-aligned box [lo, hi], faces outward, each face an n x n grid.
inline TriangleMesh box(glm::dvec3 lo, glm::dvec3 hi, int n = 1) {
  TriangleMesh mesh;
  const glm::dvec3 e = hi - lo;
  const glm::dvec3 X{e.x, 0, 0}, Y{0, e.y, 0}, Z{0, 0, e.z};
  add_grid(mesh, lo, Y, X, n, n);      // bottom, -z
  add_grid(mesh, lo + Z, X, Y, n, n);  // top, +z
  add_grid(mesh, lo, X, Z, n, n);      // front, -y
  add_grid(mesh, lo + Y, Z, X, n, n);  // back, +y
  add_grid(mesh, lo, Z, Y, n, n);      // left, -x
  add_grid(mesh, lo + X, Y, Z, n, n);  // right, +x
  return mesh;
}

/// An icosphere: the icosahedron subdivided `levels` times, vertices on the
/// sphere, outward, with radial vertex normals. 20 * 4^levels triangles.
inline TriangleMesh icosphere(int levels, double radius, glm::dvec3 centre = glm::dvec3{0.0}) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                               {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  for (auto& x : v)
    x = glm::normalize(x);
  std::vector<TriangleIndices> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto middle = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      const auto k = static_cast<std::uint32_t>(v.size() - 1);
      mid.emplace(key, k);
      return k;
    };
    std::vector<TriangleIndices> g;
    g.reserve(f.size() * 4);
    for (const auto& t : f) {
      const std::uint32_t a = middle(t[0], t[1]), b = middle(t[1], t[2]), c = middle(t[2], t[0]);
      g.push_back({t[0], a, c});
      g.push_back({t[1], b, a});
      g.push_back({t[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  TriangleMesh mesh;
  for (const auto& x : v) {
    mesh.positions.push_back(centre + radius * x);
    mesh.normals.push_back(x);
  }
  mesh.triangles = std::move(f);
  return mesh;
}

/// The wavy sheet's height at (x, y) [m]: amplitude sin(2 pi x / wavelength)
/// sin(2 pi y / wavelength), as wavy_sheet() puts its vertices.
inline double wavy_height(double x, double y, double amplitude, double wavelength) {
  const double k = 2.0 * 3.14159265358979323846 / wavelength;
  return amplitude * std::sin(k * x) * std::sin(k * y);
}

/// A wavy sheet z = wavy_height(x, y) over [-side/2, side/2]^2, 2 n^2
/// triangles, facing +z.
inline TriangleMesh wavy_sheet(double side, int n, double amplitude, double wavelength) {
  TriangleMesh mesh = flat_sheet(side, n);
  for (auto& x : mesh.positions)
    x.z = wavy_height(x.x, x.y, amplitude, wavelength);
  return mesh;
}

/// A mesh scaled to `diagonal` [m] across its box, about the box's centre
/// (real models, whatever their units, made hand-sized).
inline TriangleMesh fitted(TriangleMesh m, double diagonal = 0.2) {
  glm::dvec3 lo{1e300}, hi{-1e300};
  for (const auto& p : m.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const double s = diagonal / glm::length(hi - lo);
  for (auto& p : m.positions)
    p = (p - 0.5 * (lo + hi)) * s;
  return m;
}

}  // namespace hapticfield::test
