#pragma once
/// @file obj.hpp
/// Wavefront OBJ into a TriangleMesh through tinyobjloader (Debian's
/// libtinyobjloader-dev 2.0rc10; CMake target hapticfield::obj). The only
/// header that includes tinyobjloader.
///
/// OBJ indexes positions (v), texture coordinates (vt) and normals (vn)
/// separately at each face corner; a TriangleMesh has one index per vertex,
/// so a vertex is made for each distinct (v, vt, vn) combination used
/// (vertices are split along uv seams and creases). OBJ has no units
/// (MeshReadConfig::scale). Polygons are triangulated here, after every
/// index is checked: tinyobjloader's own triangulation reads positions
/// without checking the indices. Materials (usemtl) come back as indices
/// into LoadedMesh::material_names, read from the mtllib files beside the
/// OBJ (never outside its folder). Never used in a tick.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>
#include <map>
#include <new>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <tiny_obj_loader.h>

#include "hapticfield/core/error.hpp"
#include "hapticfield/io/mesh_read.hpp"

namespace hapticfield::io {

namespace detail {

/// Reads mtllib files through our size-limited reader, only beside the OBJ.
class ObjMaterialReader : public tinyobj::MaterialReader {
 public:
  ObjMaterialReader(std::string dir, std::uintmax_t budget) : dir_(std::move(dir)), budget_(budget) {}

  bool operator()(const std::string& mat_id, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* mat_map, std::string* warn, std::string* err) override {
    (void)err;  // a missing material file is a warning, not an error
    const std::string path = path_inside(dir_, mat_id);
    if (path.empty()) {
      if (warn) *warn += "material file '" + mat_id + "' is not inside the OBJ's folder: not read\n";
      return false;
    }
    std::string text;
    try {
      text = read_file(path, budget_);
    } catch (const FileError& e) {
      if (warn) *warn += std::string(e.what()) + "\n";
      return false;
    }
    budget_ -= text.size();
    std::istringstream in(std::move(text));
    tinyobj::LoadMtl(mat_map, materials, &in, warn, err);
    return true;
  }

 private:
  std::string dir_;
  std::uintmax_t budget_;
};

/// One face corner: indices into the file's v, vt and vn lists (-1: none).
struct ObjCorner {
  int v = -1;
  int vt = -1;
  int vn = -1;
  bool operator==(const ObjCorner&) const = default;
};
struct ObjCornerHash {
  std::size_t operator()(const ObjCorner& c) const noexcept {
    std::uint64_t h = static_cast<std::uint32_t>(c.v);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(c.vt);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(c.vn);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

/// Triangulates a polygon of n >= 4 corners (as positions p) into out as
/// triples of corner numbers: a quad along its shorter diagonal, larger
/// polygons by ear clipping in the plane of their Newell normal (a fan when
/// the polygon is self-intersecting or degenerate). Returns false when it
/// had to fall back to a fan.
inline bool triangulate_polygon(const std::vector<glm::dvec3>& p, std::vector<std::array<std::size_t, 3>>& out) {
  const std::size_t n = p.size();
  if (n == 4) {
    if (glm::length(p[2] - p[0]) <= glm::length(p[3] - p[1])) {
      out.push_back({0, 1, 2});
      out.push_back({0, 2, 3});
    } else {
      out.push_back({0, 1, 3});
      out.push_back({1, 2, 3});
    }
    return true;
  }
  glm::dvec3 normal{0.0};
  for (std::size_t i = 0; i < n; ++i)
    normal += glm::cross(p[i], p[(i + 1) % n]);
  const double len = glm::length(normal);
  const auto fan = [&] {
    for (std::size_t i = 1; i + 1 < n; ++i)
      out.push_back({0, i, i + 1});
  };
  if (!(len > 0.0) || !std::isfinite(len)) {
    fan();
    return false;
  }
  normal /= len;
  const glm::dvec3 u = glm::normalize(std::abs(normal.x) > 0.9 ? glm::cross(normal, glm::dvec3{0, 1, 0})
                                                               : glm::cross(normal, glm::dvec3{1, 0, 0}));
  const glm::dvec3 v = glm::cross(normal, u);
  std::vector<glm::dvec2> q(n);
  for (std::size_t i = 0; i < n; ++i)
    q[i] = {glm::dot(p[i], u), glm::dot(p[i], v)};  // counter-clockwise about the normal
  const auto cross2 = [](const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  };
  std::vector<std::size_t> left(n);
  for (std::size_t i = 0; i < n; ++i)
    left[i] = i;
  const std::size_t first = out.size();
  std::size_t cursor = 0;  // where the last ear was cut: the next is usually beside it
  while (left.size() > 3) {
    bool clipped = false;
    const std::size_t m = left.size();
    for (std::size_t step = 0; step < m && !clipped; ++step) {
      const std::size_t i = (cursor + step) % m;
      const std::size_t a = left[(i + m - 1) % m];
      const std::size_t b = left[i];
      const std::size_t c = left[(i + 1) % m];
      if (cross2(q[a], q[b], q[c]) <= 0.0) continue;  // reflex or flat: not an ear
      bool inside = false;
      for (const std::size_t k : left) {
        if (k == a || k == b || k == c) continue;
        if (cross2(q[a], q[b], q[k]) >= 0.0 && cross2(q[b], q[c], q[k]) >= 0.0 && cross2(q[c], q[a], q[k]) >= 0.0) {
          inside = true;
          break;
        }
      }
      if (inside) continue;
      out.push_back({a, b, c});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(i));
      cursor = i == 0 ? 0 : i - 1;
      clipped = true;
    }
    if (!clipped) {  // self-intersecting: start again with a fan
      out.resize(first);
      fan();
      return false;
    }
  }
  out.push_back({left[0], left[1], left[2]});
  return true;
}

/// Checks every number of the v, vt and vn lines: tinyobjloader reads
/// "nan", "inf", an overflowing exponent or a word as 0 without a word, so
/// a broken file would load with vertices silently moved to the origin.
inline void check_obj_numbers(std::string_view text, const std::string& name) {
  std::size_t line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    ++line;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view l = text.substr(pos, end - pos);
    pos = end + 1;
    if (const std::size_t hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
    std::size_t i = l.find_first_not_of(" \t");
    if (i == std::string_view::npos || l[i] != 'v') continue;
    std::size_t k = i + 1;
    if (k < l.size() && (l[k] == 't' || l[k] == 'n')) ++k;
    if (k < l.size() && l[k] != ' ' && l[k] != '\t') continue;  // another keyword (vp, ...)
    while (k < l.size()) {
      k = l.find_first_not_of(" \t\r", k);
      if (k == std::string_view::npos) break;
      const std::size_t stop = std::min(l.find_first_of(" \t\r", k), l.size());
      const std::string_view t = l.substr(k, stop - k);
      k = stop;
      const char* first = t.data() + (t[0] == '+' ? 1 : 0);
      const char* last = t.data() + t.size();
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(first, last, v);  // locale-independent, as OBJ is
      bool finite = std::isfinite(v);
      if (ec == std::errc::result_out_of_range) {  // too large, or too small (that one reads as 0)
        const std::size_t e = t.find_first_of("eE");
        finite = e != std::string_view::npos && e + 1 < t.size() && t[e + 1] == '-';
      }
      const bool word = ptr != last || (ec != std::errc() && ec != std::errc::result_out_of_range);
      if (word || !finite)
        throw mesh_error(name, "line " + std::to_string(line) + ": '" + std::string(t.substr(0, 40)) + "' is " +
                                   (word ? "not a number" : "not finite"));
    }
  }
}

/// The faces of an OBJ text, checked and counted before tinyobjloader reads
/// it (which reads indices with atoi, so 4294967299 wraps to 3, and takes a
/// relative uv or normal index before the first one for "none"): every
/// face index is an integer that fits, not 0, and a relative (negative)
/// one names an element defined above it; every face has 3..255 corners.
/// Returns the triangles the faces make (n - 2 for n corners), refusing as
/// soon as they pass `limit`, before anything is allocated.
[[nodiscard]] inline std::size_t scan_obj_faces(std::string_view text, const std::string& name, std::size_t limit) {
  static constexpr std::string_view kinds[3] = {"vertex", "texture coordinate", "normal"};
  std::size_t defined[3] = {0, 0, 0};  // v, vt, vn lines so far (relative indices count back from here)
  std::size_t triangles = 0;
  std::size_t line = 0;
  std::size_t pos = 0;
  const auto fail = [&](const std::string& what) {
    throw mesh_error(name, "line " + std::to_string(line) + ": " + what);
  };
  while (pos < text.size()) {
    ++line;  // lines end at \n, \r\n or \r, as tinyobjloader splits them
    std::size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view l = text.substr(pos, end - pos);
    pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
    const std::size_t i = l.find_first_not_of(" \t");
    if (i == std::string_view::npos) continue;
    const auto space_at = [&](std::size_t k) { return k < l.size() && (l[k] == ' ' || l[k] == '\t'); };
    if (l[i] == 'v') {
      if (space_at(i + 1))
        ++defined[0];
      else if (l.size() > i + 1 && l[i + 1] == 't' && space_at(i + 2))
        ++defined[1];
      else if (l.size() > i + 1 && l[i + 1] == 'n' && space_at(i + 2))
        ++defined[2];
      continue;
    }
    if (l[i] != 'f' || !space_at(i + 1)) continue;
    std::size_t corners = 0;
    std::size_t k = i + 1;
    for (;;) {
      k = l.find_first_not_of(" \t", k);
      if (k == std::string_view::npos) break;
      const std::size_t stop = std::min(l.find_first_of(" \t", k), l.size());
      const std::string_view corner = l.substr(k, stop - k);
      k = stop;
      ++corners;
      std::size_t field = 0;
      std::size_t from = 0;
      for (;;) {  // v, v/vt, v//vn, v/vt/vn
        const std::size_t slash = std::min(corner.find('/', from), corner.size());
        const std::string_view number = corner.substr(from, slash - from);
        if (field > 2) fail("face corner '" + std::string(corner.substr(0, 40)) + "' has more than three indices");
        if (!(number.empty() && field == 1 && slash < corner.size())) {  // only vt may be left out (v//vn)
          const char* first = number.data() + (!number.empty() && number[0] == '+' ? 1 : 0);
          long long value = 0;
          const auto [ptr, ec] = std::from_chars(first, number.data() + number.size(), value);
          if (number.empty() || ec == std::errc::invalid_argument || ptr != number.data() + number.size())
            fail("face corner '" + std::string(corner.substr(0, 40)) + "' is not v, v/vt, v//vn or v/vt/vn indices");
          const std::string what = std::string(kinds[field]) + " index " + std::string(number.substr(0, 40));
          if (ec == std::errc::result_out_of_range || value > std::numeric_limits<int>::max() ||
              value < -static_cast<long long>(std::numeric_limits<int>::max()))
            fail(what + " is out of range");
          if (value == 0) fail(what + ": OBJ indices start at 1");
          if (value < 0 && static_cast<std::size_t>(-value) > defined[field])
            fail("relative " + what + " reaches before the first " + std::string(kinds[field]) + " (" +
                 std::to_string(defined[field]) + " above it)");
        }
        if (slash == corner.size()) break;
        from = slash + 1;
        ++field;
      }
    }
    if (corners < 3) fail("a face needs 3 corners, this one has " + std::to_string(corners));
    if (corners > 255) fail("a face of " + std::to_string(corners) + " corners: more than 255 corners");
    triangles += corners - 2;
    if (triangles > limit)
      throw mesh_error(name, "more than " + std::to_string(limit) + " triangles by line " + std::to_string(line) +
                                 " (raise MeshReadConfig::max_triangles)");
  }
  return triangles;
}

}  // namespace detail

/// Reads OBJ text already in memory.
/// @param name          the file's name for messages
/// @param material_dir  the folder mtllib files are read from (and never
///                      outside of); empty: material files are not read
/// @throws FileError naming the file for a syntax error tinyobjloader
///         reports, an index out of range (one that does not fit an int, or
///         a relative one before the first element: with its line), a face
///         of fewer than 3 or more than 255 corners, non-finite values, no
///         triangles, or more than config.max_triangles (counted from the
///         text before the file is parsed).
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline LoadedMesh parse_obj(std::string_view text, const std::string& name,
                                          const MeshReadConfig& config = {}, const std::string& material_dir = {}) {
  using namespace detail;
  check_config(config);
  const std::size_t limit = triangle_limit(config);
  const std::size_t triangles = scan_obj_faces(text, name, limit);  // counted and checked before any allocation
  check_obj_numbers(text, name);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn;
  std::string err;
  bool ok = false;
  {
    std::istringstream in{std::string(text)};
    ObjMaterialReader mtl(material_dir, config.max_file_bytes);
    try {
      // triangulate = false: the library's triangulation does not check indices
      ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, material_dir.empty() ? nullptr : &mtl,
                            false, false);
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {
      throw mesh_error(name, e.what());
    }
  }
  if (!ok) throw mesh_error(name, first_line(err));
  LoadedMesh out;
  add_reader_warnings(out, err);  // LoadObj succeeded: what it calls errors here (material files) are warnings
  add_reader_warnings(out, warn);
  if (material_dir.empty() && text.find("mtllib") != std::string_view::npos)
    out.warnings.push_back({MeshWarningKind::reader, "material files are not read from memory: one material"});

  const std::size_t nv = attrib.vertices.size() / 3;
  const std::size_t nt = attrib.texcoords.size() / 2;
  const std::size_t nn = attrib.normals.size() / 3;
  for (std::size_t i = 0; i < attrib.vertices.size(); ++i)
    if (!std::isfinite(static_cast<double>(attrib.vertices[i])))
      throw mesh_error(
          name, "vertex " + std::to_string(i / 3 + 1) + " (v line " + std::to_string(i / 3 + 1) + ") is not finite");
  for (std::size_t i = 0; i < attrib.texcoords.size(); ++i)
    if (!std::isfinite(static_cast<double>(attrib.texcoords[i])))
      throw mesh_error(name, "texture coordinate " + std::to_string(i / 2 + 1) + " is not finite");
  for (std::size_t i = 0; i < attrib.normals.size(); ++i)
    if (!std::isfinite(static_cast<double>(attrib.normals[i])))
      throw mesh_error(name, "normal " + std::to_string(i / 3 + 1) + " is not finite");

  TriangleMesh& mesh = out.mesh;
  mesh.triangles.reserve(triangles);
  std::vector<ObjCorner> corners;  // the new vertices
  std::unordered_map<ObjCorner, std::uint32_t, ObjCornerHash> index;
  std::vector<int> face_material;
  bool any_uv = false;
  bool any_normal = false;
  bool any_default_material = false;
  std::size_t fans = 0;
  std::size_t skipped = 0;
  std::size_t face_number = 0;
  std::vector<glm::dvec3> polygon;
  std::vector<std::array<std::size_t, 3>> pieces;
  std::vector<std::uint32_t> ids;
  for (const tinyobj::shape_t& shape : shapes) {
    skipped += shape.lines.num_line_vertices.size() + shape.points.indices.size();
    const tinyobj::mesh_t& m = shape.mesh;
    std::size_t offset = 0;
    if (m.material_ids.size() != m.num_face_vertices.size())
      throw mesh_error(name, "shape '" + shape.name + "': material list does not match its faces");
    for (std::size_t f = 0; f < m.num_face_vertices.size(); ++f, ++face_number) {
      const std::size_t count = m.num_face_vertices[f];
      if (count < 3 || offset + count > m.indices.size())
        throw mesh_error(name, "face " + std::to_string(face_number + 1) + " has more than 255 corners");
      ids.clear();
      polygon.clear();
      for (std::size_t k = 0; k < count; ++k) {
        const tinyobj::index_t& idx = m.indices[offset + k];
        const std::string where = "face " + std::to_string(face_number + 1) + " corner " + std::to_string(k + 1);
        if (idx.vertex_index < 0 || static_cast<std::size_t>(idx.vertex_index) >= nv)
          throw mesh_error(name, where + " uses vertex " +
                                     std::to_string(static_cast<long long>(idx.vertex_index) + 1) + " of " +
                                     std::to_string(nv));
        if (idx.texcoord_index >= 0 && static_cast<std::size_t>(idx.texcoord_index) >= nt)
          throw mesh_error(name, where + " uses texture coordinate " +
                                     std::to_string(static_cast<long long>(idx.texcoord_index) + 1) + " of " +
                                     std::to_string(nt));
        if (idx.normal_index >= 0 && static_cast<std::size_t>(idx.normal_index) >= nn)
          throw mesh_error(name, where + " uses normal " +
                                     std::to_string(static_cast<long long>(idx.normal_index) + 1) + " of " +
                                     std::to_string(nn));
        const ObjCorner c{idx.vertex_index, idx.texcoord_index < 0 ? -1 : idx.texcoord_index,
                          idx.normal_index < 0 ? -1 : idx.normal_index};
        any_uv = any_uv || c.vt >= 0;
        any_normal = any_normal || c.vn >= 0;
        const auto [it, inserted] = index.try_emplace(c, static_cast<std::uint32_t>(corners.size()));
        if (inserted) {
          if (corners.size() >= max_mesh_elements) throw mesh_error(name, "more than 2^30 vertices");
          corners.push_back(c);
        }
        ids.push_back(it->second);
        const auto v = static_cast<std::size_t>(c.v);
        polygon.emplace_back(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
      }
      offset += count;
      pieces.clear();
      if (count == 3) {
        pieces.push_back({0, 1, 2});
      } else if (!triangulate_polygon(polygon, pieces)) {
        ++fans;
      }
      const int material = m.material_ids[f];
      if (material >= 0 && static_cast<std::size_t>(material) >= materials.size())
        throw mesh_error(name, "face " + std::to_string(face_number + 1) + " uses material " +
                                   std::to_string(material) + " of " + std::to_string(materials.size()));
      any_default_material = any_default_material || material < 0;
      for (const auto& piece : pieces) {
        if (mesh.triangles.size() >= limit)
          throw mesh_error(name,
                           "more than " + std::to_string(limit) + " triangles (raise MeshReadConfig::max_triangles)");
        mesh.triangles.push_back({ids[piece[0]], ids[piece[1]], ids[piece[2]]});
        face_material.push_back(material);
      }
    }
    if (offset != m.indices.size())
      throw mesh_error(name, "shape '" + shape.name + "' has a face with more than 255 corners");
  }

  mesh.positions.reserve(corners.size());
  std::vector<bool> normal_missing;
  std::size_t uv_missing = 0;
  for (const ObjCorner& c : corners) {
    const auto v = static_cast<std::size_t>(c.v);
    mesh.positions.emplace_back(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
    if (any_uv) {
      if (c.vt >= 0) {
        const auto t = static_cast<std::size_t>(c.vt);
        mesh.uvs.emplace_back(attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]);
      } else {
        mesh.uvs.emplace_back(0.0, 0.0);
        ++uv_missing;
      }
    }
    if (any_normal) {
      if (c.vn >= 0) {
        const auto k = static_cast<std::size_t>(c.vn);
        mesh.normals.emplace_back(attrib.normals[3 * k], attrib.normals[3 * k + 1], attrib.normals[3 * k + 2]);
      } else {
        mesh.normals.emplace_back(0.0);
      }
      normal_missing.push_back(c.vn < 0);
    }
  }
  if (uv_missing > 0)
    out.warnings.push_back({MeshWarningKind::missing_uvs, std::to_string(uv_missing) + " of " +
                                                              std::to_string(corners.size()) +
                                                              " vertices have no texture coordinate: (0, 0) given"});
  if (!materials.empty()) {
    for (const tinyobj::material_t& m : materials) {
      out.material_names.push_back(m.name);
      out.base_colour_textures.emplace_back();  // map_Kd, read only from the OBJ's folder
      if (m.diffuse_texname.empty() || material_dir.empty()) continue;
      const std::string path = path_inside(material_dir, m.diffuse_texname);
      if (path.empty()) {
        out.warnings.push_back(
            {MeshWarningKind::reader, "texture '" + m.diffuse_texname + "' is not inside the OBJ's folder: not read"});
        continue;
      }
      try {
        const std::string bytes = read_file(path, config.max_file_bytes);
        out.base_colour_textures.back().assign(bytes.begin(), bytes.end());
      } catch (const FileError& e) {
        out.warnings.push_back(
            {MeshWarningKind::reader, std::string(e.what()) + ": texture of material '" + m.name + "' not read"});
      }
    }
    const auto fallback = static_cast<std::uint32_t>(materials.size());
    if (any_default_material) {
      out.material_names.emplace_back("(default)");
      out.base_colour_textures.emplace_back();
    }
    mesh.materials.reserve(face_material.size());
    for (const int id : face_material)
      mesh.materials.push_back(id < 0 ? fallback : static_cast<std::uint32_t>(id));
  }
  if (fans > 0)
    out.warnings.push_back(
        {MeshWarningKind::reader, std::to_string(fans) + " self-intersecting or flat polygons were split as fans"});
  if (skipped > 0)
    out.warnings.push_back({MeshWarningKind::skipped_primitives,
                            std::to_string(skipped) + " lines and points were left out (triangles only)"});
  finish_mesh(out, name, config, std::move(normal_missing));
  return out;
}

/// Reads an OBJ file of at most config.max_file_bytes, and its mtllib
/// files from the same folder.
/// @throws FileError as parse_obj(), or when the file is missing, not a
///         regular file, unreadable or too large.
[[nodiscard]] inline LoadedMesh load_obj(const std::string& path, const MeshReadConfig& config = {}) {
  detail::check_config(config);
  const std::string text = read_file(path, config.max_file_bytes);
  return parse_obj(text, path, config, detail::folder_of(path));
}

}  // namespace hapticfield::io
