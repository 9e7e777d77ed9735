// Helpers of the io tests (test_io*.cpp): a temporary folder, crafted files,
// the closed-form cube every format must give back, and independent mesh
// measures (area, bounds, signed volume, welded boundary edges).
#pragma once

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace io_test {

namespace fs = std::filesystem;

/// A fresh folder under the build's test tmp for one test.
inline fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::path(HAPTICFIELD_TEST_TMP) / "io" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// Expects a FileError whose message names the file and says `what`.
template <class F>
void expect_file_error(F&& f, const std::string& name, const std::string& what) {
  try {
    f();
    FAIL("no FileError for " << what);
  } catch (const hapticfield::FileError& e) {
    INFO(e.what());
    CHECK_THAT(e.what(), Catch::Matchers::Contains(name));
    CHECK_THAT(e.what(), Catch::Matchers::Contains(what));
  }
}

inline std::string write(const fs::path& path, std::string_view bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path.string();
}

/// The folder of the shared real files: $HAPTICFIELD_SHARED_DATA, else
/// ../shared/data beside the source tree; empty when absent.
inline fs::path shared_data() {
  if (const char* env = std::getenv("HAPTICFIELD_SHARED_DATA"); env && *env) return fs::path(env);
  const fs::path p = fs::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  return fs::is_directory(p) ? p : fs::path();
}

// --- little-endian bytes ------------------------------------------------------
inline void put32(std::string& s, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
inline void put16(std::string& s, std::uint16_t v) {
  s.push_back(static_cast<char>(v & 0xFF));
  s.push_back(static_cast<char>(v >> 8));
}
inline void putf(std::string& s, float v) {
  put32(s, std::bit_cast<std::uint32_t>(v));
}

inline std::string base64(std::string_view in) {
  static constexpr char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16 | std::uint32_t(std::uint8_t(in[i + 1])) << 8 |
                            std::uint8_t(in[i + 2]);
    for (int k = 3; k >= 0; --k)
      out.push_back(table[(v >> (6 * k)) & 63]);
  }
  if (i + 1 == in.size()) {
    const std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16;
    out += {table[(v >> 18) & 63], table[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16 | std::uint32_t(std::uint8_t(in[i + 1])) << 8;
    out += {table[(v >> 18) & 63], table[(v >> 12) & 63], table[(v >> 6) & 63], '='};
  }
  return out;
}

// --- the cube: [0, a]^3, 8 corners, 12 outward triangles -------------------------
/// Corner k has x = bit 0, y = bit 1, z = bit 2.
inline glm::dvec3 cube_corner(int k, double a) {
  return a * glm::dvec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
}

/// The six faces as quads counter-clockwise seen from outside.
inline constexpr std::array<std::array<int, 4>, 6> cube_quads{{
    {0, 2, 3, 1},  // z = 0, normal -z
    {4, 5, 7, 6},  // z = a, +z
    {0, 1, 5, 4},  // y = 0, -y
    {2, 6, 7, 3},  // y = a, +y
    {0, 4, 6, 2},  // x = 0, -x
    {1, 3, 7, 5},  // x = a, +x
}};
inline constexpr std::array<glm::dvec3, 6> cube_normals{
    {{0, 0, -1}, {0, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, 0}, {1, 0, 0}}};

/// The 12 triangles as corner numbers.
inline std::vector<std::array<int, 3>> cube_triangles() {
  std::vector<std::array<int, 3>> t;
  for (const auto& q : cube_quads) {
    t.push_back({q[0], q[1], q[2]});
    t.push_back({q[0], q[2], q[3]});
  }
  return t;
}

// --- measures ---------------------------------------------------------------------
inline double total_area(const hapticfield::TriangleMesh& m) {
  double area = 0.0;
  for (const auto& t : m.triangles)
    area += 0.5 * glm::length(glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
  return area;
}

/// Signed volume (divergence theorem): positive when faces point out.
inline double signed_volume(const hapticfield::TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles)
    v += glm::dot(m.positions[t[0]], glm::cross(m.positions[t[1]], m.positions[t[2]])) / 6.0;
  return v;
}

struct Bounds {
  glm::dvec3 lo{1e300};
  glm::dvec3 hi{-1e300};
  [[nodiscard]] glm::dvec3 size() const { return hi - lo; }
};
inline Bounds bounds(const hapticfield::TriangleMesh& m) {
  Bounds b;
  for (const auto& p : m.positions) {
    b.lo = glm::min(b.lo, p);
    b.hi = glm::max(b.hi, p);
  }
  return b;
}

using Key = std::tuple<double, double, double>;

/// The number of distinct positions.
inline std::size_t distinct_positions(const hapticfield::TriangleMesh& m) {
  std::set<Key> s;
  for (const auto& p : m.positions)
    s.emplace(p.x, p.y, p.z);
  return s.size();
}

/// After welding by exact position: edges used once (boundary), and edges
/// used twice the same way round (inconsistent orientation).
struct EdgeCount {
  std::size_t boundary = 0;
  std::size_t same_direction = 0;
};
inline EdgeCount welded_edges(const hapticfield::TriangleMesh& m) {
  std::map<Key, std::size_t> id;
  std::vector<std::size_t> weld(m.positions.size());
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    weld[i] = id.try_emplace(Key{m.positions[i].x, m.positions[i].y, m.positions[i].z}, id.size()).first->second;
  std::map<std::pair<std::size_t, std::size_t>, int> directed;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      ++directed[{weld[t[k]], weld[t[(k + 1) % 3]]}];
  EdgeCount c;
  for (const auto& [e, n] : directed) {
    const auto back = directed.find({e.second, e.first});
    const int reverse = back == directed.end() ? 0 : back->second;
    if (n + reverse == 1) ++c.boundary;
    if (n > 1) ++c.same_direction;
  }
  return c;
}

}  // namespace io_test
