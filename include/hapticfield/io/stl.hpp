#pragma once
/// @file stl.hpp
/// STL (binary and ASCII) into a TriangleMesh, with our own reader: no
/// outside library. STL has no units (MeshReadConfig::scale), no uvs and no
/// vertex normals: a facet's normal is its face normal, so the mesh keeps
/// face normals only (TriangleMesh::normals stays empty) and the vertex
/// order defines outside. Vertices are welded by exact position, so a
/// closed solid comes back closed. Never used in a tick.

#include <array>
#include <bit>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <unordered_map>

#include "hapticfield/core/error.hpp"
#include "hapticfield/io/mesh_read.hpp"

namespace hapticfield::io {

namespace detail {

inline constexpr std::size_t stl_header_bytes = 84;  ///< 80-byte header + uint32 triangle count
inline constexpr std::size_t stl_facet_bytes = 50;   ///< normal, 3 vertices (12 float32) + uint16

[[nodiscard]] inline std::uint32_t stl_le32(const unsigned char* p) noexcept {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}
[[nodiscard]] inline double stl_float(const unsigned char* p) noexcept {
  return static_cast<double>(std::bit_cast<float>(stl_le32(p)));
}

/// Welds vertices by exact position (+0 and -0 are one position).
class PositionWelder {
 public:
  explicit PositionWelder(TriangleMesh& mesh, std::size_t expected) : mesh_(mesh) { index_.reserve(expected); }

  std::uint32_t add(const glm::dvec3& p) {
    const Key key{bits(p.x), bits(p.y), bits(p.z)};
    const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(mesh_.positions.size()));
    if (inserted) mesh_.positions.push_back(p);
    return it->second;
  }

 private:
  using Key = std::array<std::uint64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const noexcept {
      std::uint64_t h = 1469598103934665603ull;
      for (const std::uint64_t v : k)
        h = (h ^ v) * 1099511628211ull ^ (v >> 29);
      return static_cast<std::size_t>(h);
    }
  };
  static std::uint64_t bits(double v) noexcept { return std::bit_cast<std::uint64_t>(v == 0.0 ? 0.0 : v); }

  TriangleMesh& mesh_;
  std::unordered_map<Key, std::uint32_t, KeyHash> index_;
};

/// Adds one facet; counts the facets whose stored normal points against
/// the normal of their vertex order (a zero or non-finite stored normal
/// says nothing and is not counted).
inline void stl_add_facet(TriangleMesh& mesh, PositionWelder& welder, const glm::dvec3& normal,
                          const std::array<glm::dvec3, 3>& v, std::size_t& disagree) {
  mesh.triangles.push_back({welder.add(v[0]), welder.add(v[1]), welder.add(v[2])});
  if (!finite3(normal) || !finite3(v[0]) || !finite3(v[1]) || !finite3(v[2])) return;
  if (glm::dot(normal, glm::cross(v[1] - v[0], v[2] - v[0])) < 0.0) ++disagree;
}

/// A whitespace tokenizer over ASCII STL that knows its line number.
class StlTokens {
 public:
  explicit StlTokens(std::string_view text) : text_(text) {}

  /// The next token, or an empty view at the end.
  std::string_view next() {
    skip_blanks();
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && !blank(text_[pos_]))
      ++pos_;
    return text_.substr(begin, pos_ - begin);
  }
  /// Skips the rest of the current line (a solid's name).
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n')
      ++pos_;
  }
  [[nodiscard]] std::size_t line() const noexcept { return line_; }

 private:
  static bool blank(char c) noexcept {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
  }
  void skip_blanks() {
    while (pos_ < text_.size() && blank(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

[[nodiscard]] inline bool stl_iequal(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const char x = a[i] >= 'A' && a[i] <= 'Z' ? static_cast<char>(a[i] - 'A' + 'a') : a[i];
    if (x != b[i]) return false;
  }
  return true;
}

/// Does the text start (after blanks) with the word "solid"?
[[nodiscard]] inline bool stl_starts_with_solid(std::string_view bytes) noexcept {
  std::size_t i = 0;
  while (i < bytes.size() && (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\r' || bytes[i] == '\n'))
    ++i;
  if (bytes.size() - i < 5 || !stl_iequal(bytes.substr(i, 5), "solid")) return false;
  return bytes.size() - i == 5 || bytes[i + 5] == ' ' || bytes[i + 5] == '\t' || bytes[i + 5] == '\r' ||
         bytes[i + 5] == '\n';
}

inline void parse_ascii_stl(std::string_view text, const std::string& name, const MeshReadConfig& config,
                            LoadedMesh& out, std::size_t& disagree) {
  StlTokens in(text);
  const auto fail = [&](const std::string& what) {
    return mesh_error(name, "line " + std::to_string(in.line()) + ": " + what);
  };
  const auto expect = [&](std::string_view word) {
    const std::string_view t = in.next();
    if (!stl_iequal(t, word))
      throw fail(
          "expected '" + std::string(word) + "', found " +
          (t.empty() ? std::string("the end of the file (truncated)") : "'" + std::string(t.substr(0, 40)) + "'"));
  };
  const auto number = [&]() {
    const std::string_view t = in.next();
    if (t.empty()) throw fail("expected a number, found the end of the file (truncated)");
    double v = 0.0;
    const char* first = t.data();
    if (*first == '+') ++first;  // from_chars takes no '+'
    const auto [ptr, ec] = std::from_chars(first, t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size())
      throw fail("expected a number, found '" + std::string(t.substr(0, 40)) + "'");
    return v;
  };
  const std::size_t limit = triangle_limit(config);
  PositionWelder welder(out.mesh, 0);
  std::size_t solids = 0;
  while (true) {
    const std::string_view t = in.next();
    if (t.empty()) break;
    if (!stl_iequal(t, "solid")) throw fail("expected 'solid', found '" + std::string(t.substr(0, 40)) + "'");
    ++solids;
    in.skip_line();
    while (true) {
      const std::string_view w = in.next();
      if (w.empty()) throw fail("expected 'facet' or 'endsolid', found the end of the file (truncated)");
      if (stl_iequal(w, "endsolid")) {
        in.skip_line();
        break;
      }
      if (!stl_iequal(w, "facet"))
        throw fail("expected 'facet' or 'endsolid', found '" + std::string(w.substr(0, 40)) + "'");
      expect("normal");
      glm::dvec3 n{0.0};
      n.x = number();
      n.y = number();
      n.z = number();
      expect("outer");
      expect("loop");
      std::array<glm::dvec3, 3> v{glm::dvec3{0.0}, glm::dvec3{0.0}, glm::dvec3{0.0}};
      for (glm::dvec3& p : v) {
        expect("vertex");
        p.x = number();
        p.y = number();
        p.z = number();
        if (!finite3(p)) throw fail("vertex " + to_text(p) + " is not finite");
      }
      expect("endloop");
      expect("endfacet");
      if (out.mesh.triangles.size() >= limit)
        throw mesh_error(name,
                         "more than " + std::to_string(limit) + " triangles (raise MeshReadConfig::max_triangles)");
      stl_add_facet(out.mesh, welder, n, v, disagree);
    }
  }
  if (solids == 0) throw mesh_error(name, "empty ASCII STL (no 'solid')");
}

}  // namespace detail

/// Reads an STL file already in memory. ASCII when it starts with "solid"
/// and holds no NUL byte (unless its size is exactly 84 + 50 x the binary
/// header's triangle count); binary otherwise (some exporters start binary
/// files with "solid" too).
/// @param name  the file's name for messages
/// @throws FileError naming the file for a truncated file, a triangle count
///         the file's size cannot hold, non-finite vertices, a syntax
///         error (with its line), no triangles, or more than
///         config.max_triangles.
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline LoadedMesh parse_stl(std::string_view bytes, const std::string& name,
                                          const MeshReadConfig& config = {}) {
  using namespace detail;
  check_config(config);
  LoadedMesh out;
  std::size_t disagree = 0;
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  std::uint64_t declared = 0;  // the binary header's triangle count
  std::uint64_t binary_bytes = 0;
  if (bytes.size() >= stl_header_bytes) {
    declared = stl_le32(data + 80);
    binary_bytes = stl_header_bytes + stl_facet_bytes * declared;  // < 2^38: no overflow
  }
  // ASCII starts with "solid" and never holds a NUL byte; some binary files start with "solid" too.
  const bool exact_binary = bytes.size() >= stl_header_bytes && binary_bytes == bytes.size();
  const bool has_nul = bytes.find('\0') != std::string_view::npos;
  if (!exact_binary && stl_starts_with_solid(bytes) && (!has_nul || bytes.size() < stl_header_bytes)) {
    parse_ascii_stl(bytes, name, config, out, disagree);
  } else {
    if (bytes.size() < stl_header_bytes)
      throw mesh_error(name, std::to_string(bytes.size()) +
                                 " bytes: neither an ASCII STL (no 'solid') nor a binary STL (84-byte header)");
    if (declared == 0) throw mesh_error(name, "no triangles (the binary STL header declares 0)");
    if (binary_bytes > bytes.size())
      throw mesh_error(name, "truncated: the binary STL header declares " + std::to_string(declared) + " triangles (" +
                                 std::to_string(binary_bytes) + " bytes) but the file has " +
                                 std::to_string(bytes.size()) + " bytes");
    if (declared > triangle_limit(config))
      throw mesh_error(name, std::to_string(declared) + " triangles, more than the limit of " +
                                 std::to_string(triangle_limit(config)) + " (raise MeshReadConfig::max_triangles)");
    if (binary_bytes < bytes.size())
      out.warnings.push_back({MeshWarningKind::trailing_bytes, std::to_string(bytes.size() - binary_bytes) +
                                                                   " bytes after the " + std::to_string(declared) +
                                                                   " declared triangles were ignored"});
    const auto n = static_cast<std::size_t>(declared);
    out.mesh.triangles.reserve(n);
    out.mesh.positions.reserve(n / 2 + 3);  // a closed solid has about half as many vertices as triangles
    PositionWelder welder(out.mesh, n / 2 + 3);
    for (std::size_t f = 0; f < n; ++f) {
      const unsigned char* p = data + stl_header_bytes + f * stl_facet_bytes;
      const glm::dvec3 normal{stl_float(p), stl_float(p + 4), stl_float(p + 8)};
      std::array<glm::dvec3, 3> v{};
      for (int k = 0; k < 3; ++k) {
        const unsigned char* q = p + 12 + 12 * k;
        v[static_cast<std::size_t>(k)] = glm::dvec3{stl_float(q), stl_float(q + 4), stl_float(q + 8)};
        if (!finite3(v[static_cast<std::size_t>(k)]))
          throw mesh_error(name, "facet " + std::to_string(f) + " has a vertex that is not finite " +
                                     to_text(v[static_cast<std::size_t>(k)]));
      }
      stl_add_facet(out.mesh, welder, normal, v, disagree);
    }
  }
  if (disagree > 0)
    out.warnings.push_back({MeshWarningKind::facet_normals,
                            std::to_string(disagree) + " of " + std::to_string(out.mesh.triangles.size()) +
                                " facets store a normal against their vertex order (the vertex order is kept)"});
  finish_mesh(out, name, config);
  // STL facet normals are face normals: not having vertex normals is the format, not a loss.
  std::erase_if(out.warnings, [](const MeshWarning& w) { return w.kind == MeshWarningKind::no_normals; });
  return out;
}

/// Reads an STL file (binary or ASCII) of at most config.max_file_bytes.
/// @throws FileError as parse_stl(), or when the file is missing, not a
///         regular file, unreadable or too large.
[[nodiscard]] inline LoadedMesh load_stl(const std::string& path, const MeshReadConfig& config = {}) {
  detail::check_config(config);
  const std::string bytes = read_file(path, config.max_file_bytes);
  return parse_stl(bytes, path, config);
}

}  // namespace hapticfield::io
