#pragma once
// A UV sphere as a TriangleMesh and as OBJ text: `slices` around +y,
// `stacks` from pole to pole, counter-clockwise seen from outside. The
// chord error (radius (1 - cos(pi / slices))) is the farthest its outline
// is from the true sphere's.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <sstream>
#include <string>

#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield::test {

inline TriangleMesh uv_sphere(double radius, int slices, int stacks) {
  TriangleMesh m;
  for (int j = 0; j <= stacks; ++j) {
    const double theta = std::numbers::pi * j / stacks;  // from +y
    for (int i = 0; i < slices; ++i) {
      const double phi = 2.0 * std::numbers::pi * i / slices;
      m.positions.emplace_back(radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta),
                               radius * std::sin(theta) * std::cos(phi));
    }
  }
  const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * slices + (i % slices)); };
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      if (j > 0) m.triangles.push_back({a, d, b});
      if (j + 1 < stacks) m.triangles.push_back({b, d, c});
    }
  return m;
}

inline std::string to_obj(const TriangleMesh& m) {
  std::ostringstream out;
  out.precision(9);
  for (const auto& p : m.positions)
    out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
  for (const auto& t : m.triangles)
    out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  return out.str();
}

}  // namespace hapticfield::test
