#pragma once
/// @file mesh_read.hpp
/// What every mesh reader (stl.hpp, obj.hpp, gltf.hpp) shares: the settings
/// (MeshReadConfig), the result (LoadedMesh: the TriangleMesh, the material
/// names, the warnings as data) and the checks that turn a parsed file into
/// a mesh the surface code can trust. GLM only; never used in a tick.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield::io {

/// Largest mesh file read by default [bytes]: 512 MiB (a binary STL of 10.7
/// million triangles).
inline constexpr std::uintmax_t default_max_mesh_file_bytes = std::uintmax_t{512} << 20;

/// Most triangles a reader builds by default. A file's own size already
/// bounds STL and OBJ; glTF can place one mesh under many nodes, so this
/// caps what instancing can multiply. About 200 bytes per triangle at the
/// worst (three vertices with normals and uvs), so 4 GB at this limit.
inline constexpr std::size_t default_max_mesh_triangles = 20'000'000;

/// Settings of the mesh readers.
struct MeshReadConfig {
  /// Multiplies every position after the file's own transforms: the file's
  /// unit in metres (0.001 for an OBJ or STL in millimetres). glTF is in
  /// metres already (1.0). Must be finite and positive.
  double scale = 1.0;
  /// Largest file accepted [bytes] (glTF: each of the .gltf/.glb and its
  /// external buffers, and their sum).
  std::uintmax_t max_file_bytes = default_max_mesh_file_bytes;
  /// Most triangles accepted in the resulting mesh.
  std::size_t max_triangles = default_max_mesh_triangles;
};

/// What a warning is about, so a program can act on it without parsing text.
enum class MeshWarningKind {
  degenerate_triangles,  ///< triangles of zero area (kept: the surface code skips them)
  no_normals,            ///< the file has no vertex normals: the surface uses face normals
  computed_normals,      ///< some vertices had no (or a zero) normal: computed from the faces around them
  missing_uvs,           ///< some vertices had no texture coordinate: (0, 0) given
  skipped_primitives,    ///< points, lines or other non-triangle parts were left out
  facet_normals,         ///< STL facets whose stored normal disagrees with their vertex order
  trailing_bytes,        ///< bytes after the data the header declares (binary STL)
  reader,                ///< a warning of the outside reader (tinygltf, tinyobjloader), verbatim
};

struct MeshWarning {
  MeshWarningKind kind = MeshWarningKind::reader;
  std::string message;
};

/// A mesh read from a file.
struct LoadedMesh {
  TriangleMesh mesh;                        ///< positions [m], validated
  std::vector<std::string> material_names;  ///< names of mesh.materials' indices (empty: one material)
  std::vector<MeshWarning> warnings;        ///< what was accepted but may surprise
  /// Per entry of material_names: its base-colour texture as the file holds
  /// it, encoded (PNG, JPEG; glTF's baseColorTexture, embedded or beside
  /// the file; an OBJ's map_Kd, read only from the OBJ's folder), or empty
  /// when it has none or its file is missing (a warning). Decode with cv::imdecode
  /// (scenes/model_texture.hpp).
  std::vector<std::vector<unsigned char>> base_colour_textures;

  [[nodiscard]] bool has_warning(MeshWarningKind kind) const noexcept {
    return std::any_of(warnings.begin(), warnings.end(), [kind](const MeshWarning& w) { return w.kind == kind; });
  }
};

namespace detail {

/// "cannot load 'name': what"
[[nodiscard]] inline FileError mesh_error(const std::string& name, const std::string& what) {
  return FileError("cannot load '" + name + "': " + what);
}

/// Checks the settings.
/// @throws std::invalid_argument for a non-finite or non-positive scale, or zero limits.
inline void check_config(const MeshReadConfig& config) {
  if (!std::isfinite(config.scale) || config.scale <= 0.0)
    throw std::invalid_argument("MeshReadConfig: scale must be finite and positive, got " +
                                std::to_string(config.scale));
  if (config.max_file_bytes == 0) throw std::invalid_argument("MeshReadConfig: max_file_bytes must be positive");
  if (config.max_triangles == 0) throw std::invalid_argument("MeshReadConfig: max_triangles must be positive");
}

/// The smaller of the configured triangle limit and what 32-bit indices allow.
[[nodiscard]] inline std::size_t triangle_limit(const MeshReadConfig& config) noexcept {
  return std::min(config.max_triangles, max_mesh_elements);
}

/// a * b, or false when it exceeds limit (or overflows).
[[nodiscard]] inline bool checked_mul(std::uint64_t a, std::uint64_t b, std::uint64_t limit,
                                      std::uint64_t& out) noexcept {
  if (a != 0 && b > limit / a) return false;
  out = a * b;
  return out <= limit;
}

[[nodiscard]] inline bool finite3(const glm::dvec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

[[nodiscard]] inline std::string to_text(const glm::dvec3& v) {
  std::string s(1, '(');  // appended piece by piece: g++ 12 warns falsely on "(" + std::string
  s.append(std::to_string(v.x)).append(", ").append(std::to_string(v.y)).append(", ");
  s.append(std::to_string(v.z)).append(1, ')');
  return s;
}

/// Twice the area of triangle t [m^2] and whether it is degenerate: a
/// repeated index, or an area below 1e-12 of its longest edge squared.
[[nodiscard]] inline bool is_degenerate(const TriangleMesh& mesh, const TriangleIndices& t) noexcept {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const glm::dvec3& a = mesh.positions[t[0]];
  const glm::dvec3& b = mesh.positions[t[1]];
  const glm::dvec3& c = mesh.positions[t[2]];
  const double area2 = glm::length(glm::cross(b - a, c - a));
  const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  return !(area2 > 1e-12 * longest * longest);
}

/// Area-weighted vertex normals from the faces, written only where
/// need[v] is true; a vertex whose faces all have zero area gets (0, 0, 1).
inline void fill_face_normals(TriangleMesh& mesh, const std::vector<bool>& need) {
  std::vector<glm::dvec3> sum(mesh.positions.size(), glm::dvec3{0.0});
  for (const TriangleIndices& t : mesh.triangles) {
    if (!need[t[0]] && !need[t[1]] && !need[t[2]]) continue;
    const glm::dvec3 n = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                    mesh.positions[t[2]] - mesh.positions[t[0]]);  // length = 2 area
    for (const std::uint32_t k : t)
      sum[k] += n;
  }
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!need[v]) continue;
    const double len = glm::length(sum[v]);
    mesh.normals[v] = len > 0.0 && std::isfinite(len) ? sum[v] / len : glm::dvec3{0.0, 0.0, 1.0};
  }
}

/// Makes a parsed mesh one the surface code can trust, or says why not:
/// applies the scale, refuses an empty mesh, too many triangles, non-finite
/// positions, normals or uvs and out-of-range indices (all FileErrors naming
/// the file), renormalises normals (zero ones are computed from the faces,
/// with a warning) and counts degenerate triangles (a warning).
/// @param normal_missing  per vertex: the file gave no normal (empty: all given)
inline void finish_mesh(LoadedMesh& out, const std::string& name, const MeshReadConfig& config,
                        std::vector<bool> normal_missing = {}) {
  TriangleMesh& mesh = out.mesh;
  if (mesh.triangles.empty()) throw mesh_error(name, "no triangles");
  if (mesh.triangles.size() > triangle_limit(config))
    throw mesh_error(name, std::to_string(mesh.triangles.size()) + " triangles, more than the limit of " +
                               std::to_string(triangle_limit(config)) + " (raise MeshReadConfig::max_triangles)");
  if (mesh.positions.size() > max_mesh_elements)
    throw mesh_error(name, std::to_string(mesh.positions.size()) + " vertices, more than 2^30");
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    if (!finite3(mesh.positions[i]))
      throw mesh_error(name, "vertex " + std::to_string(i) + " is not finite " + to_text(mesh.positions[i]));
    mesh.positions[i] *= config.scale;
    if (!finite3(mesh.positions[i]))
      throw mesh_error(name, "vertex " + std::to_string(i) + " overflows at scale " + std::to_string(config.scale));
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (const std::uint32_t k : mesh.triangles[t])
      if (k >= mesh.positions.size())
        throw mesh_error(name, "triangle " + std::to_string(t) + " uses vertex " + std::to_string(k) + " of " +
                                   std::to_string(mesh.positions.size()));
  for (std::size_t i = 0; i < mesh.uvs.size(); ++i)
    if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
      throw mesh_error(name, "texture coordinate of vertex " + std::to_string(i) + " is not finite");

  if (!mesh.normals.empty()) {
    if (normal_missing.empty()) normal_missing.assign(mesh.positions.size(), false);
    std::size_t zero = 0;
    for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
      if (normal_missing[i]) continue;
      if (!finite3(mesh.normals[i]))
        throw mesh_error(name, "normal of vertex " + std::to_string(i) + " is not finite " + to_text(mesh.normals[i]));
      const double len = glm::length(mesh.normals[i]);
      if (len > 0.0 && std::isfinite(len)) {
        mesh.normals[i] /= len;
      } else {
        normal_missing[i] = true;
        ++zero;
      }
    }
    const auto missing = static_cast<std::size_t>(std::count(normal_missing.begin(), normal_missing.end(), true));
    if (missing > 0) {
      fill_face_normals(mesh, normal_missing);
      out.warnings.push_back(
          {MeshWarningKind::computed_normals, std::to_string(missing) + " of " + std::to_string(mesh.positions.size()) +
                                                  " vertices had " + (zero == missing ? "a zero normal" : "no normal") +
                                                  ": computed from the faces around them"});
    }
  } else {
    out.warnings.push_back({MeshWarningKind::no_normals, "no vertex normals: the surface uses face normals"});
  }

  std::size_t degenerate = 0;
  for (const TriangleIndices& t : mesh.triangles)
    if (is_degenerate(mesh, t)) ++degenerate;
  if (degenerate > 0)
    out.warnings.push_back({MeshWarningKind::degenerate_triangles,
                            std::to_string(degenerate) + " of " + std::to_string(mesh.triangles.size()) +
                                " triangles have zero area (kept; the surface skips them)"});
  try {
    mesh.validate();
  } catch (const std::invalid_argument& e) {
    throw mesh_error(name, e.what());
  }
}

/// Splits an outside reader's warning text into one warning per line.
inline void add_reader_warnings(LoadedMesh& out, const std::string& text) {
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(begin, end - begin);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '.'))
      line.pop_back();
    if (!line.empty() && out.warnings.size() < 100) out.warnings.push_back({MeshWarningKind::reader, line});
    begin = end + 1;
  }
}

/// Is path a file inside folder dir (after resolving "..", "." and symbolic links)?
[[nodiscard]] inline bool inside_folder(const std::string& dir, const std::string& path) {
  namespace fs = std::filesystem;
  if (dir.empty() || path.empty() || path.find('\0') != std::string::npos) return false;
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(fs::path(dir), ec);
  if (ec) return false;
  const fs::path full = fs::weakly_canonical(fs::path(path), ec);
  if (ec) return false;
  auto f = full.begin();
  for (auto b = base.begin(); b != base.end(); ++b, ++f)
    if (f == full.end() || *b != *f) return false;
  return f != full.end();  // not the folder itself
}

/// The path of a file a mesh file refers to (an OBJ's mtllib, a glTF
/// buffer's uri), or an empty string when it is absolute or leads out of
/// the referring file's folder: a model may only read its own neighbours.
[[nodiscard]] inline std::string path_inside(const std::string& dir, const std::string& relative) {
  namespace fs = std::filesystem;
  if (dir.empty() || relative.empty() || relative.find('\0') != std::string::npos) return {};
  const fs::path rel(relative);
  if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory()) return {};
  const fs::path full = fs::path(dir) / rel;
  return inside_folder(dir, full.string()) ? full.string() : std::string();
}

/// The folder of a file, for path_inside().
[[nodiscard]] inline std::string folder_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

/// The first line of an outside reader's error text, trimmed, capped.
[[nodiscard]] inline std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' '))
    line.pop_back();
  if (line.size() > 200) line = line.substr(0, 200) + "...";
  return line.empty() ? std::string("unknown error") : line;
}

}  // namespace detail
}  // namespace hapticfield::io
