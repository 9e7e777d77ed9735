#pragma once
/// @file gltf.hpp
/// glTF 2.0 (.gltf with embedded or external buffers, and .glb) into a
/// TriangleMesh through tinygltf (Debian's libtinygltf-dev 2.7; CMake
/// target hapticfield::gltf). With io/gltf_haptic_material.hpp, the only
/// headers that include tinygltf.
///
/// The default scene (else the first, else every root node) is walked and
/// each mesh placed in world space by its node transforms (matrix or
/// translation-rotation-scale), in metres as glTF is; MeshReadConfig::scale
/// multiplies after that. Read per primitive: POSITION, NORMAL and
/// TEXCOORD_0 (v flipped to "v up": the mesh's (u, 1 - v)), triangles,
/// strips and fans, and the primitive's material as an index into
/// LoadedMesh::material_names. A mirroring transform reverses the winding
/// so faces still point out. Textures are not decoded.
///
/// Hostile files: the file and every external buffer are read through our
/// size-limited reader, only from the file's own folder (tinygltf's own
/// file access is replaced); the .glb chunk layout and the JSON nesting
/// depth are checked before tinygltf parses; every accessor's count x
/// stride is checked against its buffer view and buffer before anything is
/// allocated for it. Never used in a tick.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <new>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include <tiny_gltf.h>

#include "hapticfield/core/error.hpp"
#include "hapticfield/io/mesh_read.hpp"

namespace hapticfield::io {

/// Deepest JSON nesting accepted in a glTF file (a valid file needs about 8).
inline constexpr int max_gltf_json_depth = 64;

namespace detail {

[[nodiscard]] inline std::uint32_t gltf_le32(const unsigned char* p) noexcept {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}

/// Checks a .glb's header and chunk layout; returns the JSON chunk.
[[nodiscard]] inline std::string_view check_glb(std::string_view bytes, const std::string& name) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  if (bytes.size() < 20) throw mesh_error(name, "truncated .glb: " + std::to_string(bytes.size()) + " bytes");
  const std::uint32_t version = gltf_le32(p + 4);
  const std::uint64_t length = gltf_le32(p + 8);
  const std::uint64_t json_length = gltf_le32(p + 12);
  if (version != 2) throw mesh_error(name, ".glb version " + std::to_string(version) + ", not 2");
  if (length > bytes.size())
    throw mesh_error(name, "truncated .glb: the header declares " + std::to_string(length) + " bytes, the file has " +
                               std::to_string(bytes.size()));
  if (gltf_le32(p + 16) != 0x4E4F534Au) throw mesh_error(name, "the first .glb chunk is not JSON");
  if (json_length == 0 || 20 + json_length > length)
    throw mesh_error(name, "the .glb JSON chunk declares " + std::to_string(json_length) + " bytes in a file of " +
                               std::to_string(length));
  std::uint64_t at = 20 + ((json_length + 3) & ~std::uint64_t{3});
  if (at < length) {  // the BIN chunk
    if (at + 8 > length) throw mesh_error(name, "truncated .glb: a chunk header is cut off");
    const std::uint64_t bin_length = gltf_le32(p + at);
    if (at + 8 + bin_length > length)
      throw mesh_error(name, "truncated .glb: the BIN chunk declares " + std::to_string(bin_length) +
                                 " bytes, the file has " + std::to_string(length - at - 8) + " after its header");
  }
  return bytes.substr(20, static_cast<std::size_t>(json_length));
}

/// Refuses JSON nested deeper than max_gltf_json_depth (before a recursive
/// parser or destructor sees it).
inline void check_json_depth(std::string_view json, const std::string& name) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_gltf_json_depth)
        throw mesh_error(name, "JSON nested deeper than " + std::to_string(max_gltf_json_depth) + " levels");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

/// tinygltf's file access, replaced: our size-limited reader, only inside
/// the glTF file's folder, with one budget for every external file.
struct GltfFiles {
  std::string dir;              ///< empty: no external files at all
  std::uintmax_t budget = 0;    ///< bytes left for external files
  std::uintmax_t per_file = 0;  ///< largest single file
  std::vector<std::string> refused;

  static bool exists(const std::string& path, void* self) {
    auto* files = static_cast<GltfFiles*>(self);
    if (files->dir.empty() || !inside_folder(files->dir, path)) {
      if (files->refused.size() < 8) files->refused.push_back(path);
      return false;
    }
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
  }
  static std::string expand(const std::string& path, void*) { return path; }  // no shell expansion
  static bool read(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* self) {
    auto* files = static_cast<GltfFiles*>(self);
    if (files->dir.empty() || !inside_folder(files->dir, path)) {
      if (err) *err += "not inside the glTF file's folder";
      return false;
    }
    try {
      const std::string bytes = read_file(path, std::min(files->budget, files->per_file));
      files->budget -= bytes.size();
      out->assign(bytes.begin(), bytes.end());
      return true;
    } catch (const FileError& e) {
      if (err) *err += e.what();
      return false;
    }
  }
  static bool write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing is not allowed";
    return false;
  }
};

/// Textures are not decoded here: their encoded bytes (bounded by the
/// file's size) are kept as they are, for LoadedMesh::base_colour_textures.
inline bool keep_gltf_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                            const unsigned char* bytes, int size, void*) {
  if (image != nullptr && bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

/// One triangle primitive of a mesh, in the mesh's own frame, with only
/// the vertices its triangles use.
struct GltfPart {
  std::vector<glm::dvec3> positions;
  std::vector<glm::dvec3> normals;  ///< empty: the primitive has none
  std::vector<glm::dvec2> uvs;      ///< empty: the primitive has none
  std::vector<TriangleIndices> triangles;
  std::uint32_t material = 0;
};

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, const std::string& name, const MeshReadConfig& config, LoadedMesh& out)
      : model_(model), name_(name), limit_(triangle_limit(config)), out_(out) {}

  void run() {
    for (const std::string& ext : model_.extensionsRequired) {
      if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression" || ext == "KHR_mesh_quantization" ||
          ext == "EXT_mesh_gpu_instancing")
        throw mesh_error(name_, "requires the extension " + ext + ", which this reader does not support");
      warn(MeshWarningKind::reader, "the required extension " + ext + " is ignored");
    }
    default_material_ = static_cast<std::uint32_t>(model_.materials.size());
    for (std::size_t i = 0; i < model_.materials.size(); ++i)
      out_.material_names.push_back(model_.materials[i].name.empty() ? "material " + std::to_string(i)
                                                                     : model_.materials[i].name);
    for (const tinygltf::Material& m : model_.materials)
      out_.base_colour_textures.push_back(base_colour_of(m));
    parts_.resize(model_.meshes.size());
    converted_.assign(model_.meshes.size(), false);
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      const auto scene =
          model_.defaultScene >= 0 && static_cast<std::size_t>(model_.defaultScene) < model_.scenes.size()
              ? static_cast<std::size_t>(model_.defaultScene)
              : 0;
      roots = model_.scenes[scene].nodes;
    } else {
      std::vector<bool> child(model_.nodes.size(), false);
      for (const tinygltf::Node& n : model_.nodes)
        for (const int c : n.children)
          if (c >= 0 && static_cast<std::size_t>(c) < child.size()) child[static_cast<std::size_t>(c)] = true;
      for (std::size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(static_cast<int>(i));
    }
    walk(roots);
    if (skipped_ > 0)
      warn(MeshWarningKind::skipped_primitives,
           std::to_string(skipped_) + " primitives that are not triangles (points, lines) were left out");
    if (uv_missing_ > 0)
      warn(MeshWarningKind::missing_uvs, std::to_string(uv_missing_) + " of " +
                                             std::to_string(out_.mesh.positions.size()) +
                                             " vertices have no TEXCOORD_0: (0, 0) given");
    if (model_.materials.empty()) {  // one material: no list
      out_.material_names.clear();
      out_.base_colour_textures.clear();
      out_.mesh.materials.clear();
    } else if (use_default_material_) {
      out_.material_names.emplace_back("(default)");
      out_.base_colour_textures.emplace_back();
    }
  }

  /// The encoded picture of a material's baseColorTexture (empty: none).
  [[nodiscard]] std::vector<unsigned char> base_colour_of(const tinygltf::Material& m) const {
    const int texture = m.pbrMetallicRoughness.baseColorTexture.index;
    if (texture < 0 || static_cast<std::size_t>(texture) >= model_.textures.size()) return {};
    const int image = model_.textures[static_cast<std::size_t>(texture)].source;
    if (image < 0 || static_cast<std::size_t>(image) >= model_.images.size()) return {};
    return model_.images[static_cast<std::size_t>(image)].image;
  }

  [[nodiscard]] std::vector<bool> take_normal_missing() { return std::move(normal_missing_); }

 private:
  void warn(MeshWarningKind kind, std::string message) { out_.warnings.push_back({kind, std::move(message)}); }

  [[nodiscard]] glm::dmat4 local_transform(const tinygltf::Node& node, std::size_t index) const {
    const std::string where = "node " + std::to_string(index);
    const auto finite = [&](const std::vector<double>& v) {
      for (const double x : v)
        if (!std::isfinite(x)) throw mesh_error(name_, where + " has a non-finite transform");
    };
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16)
        throw mesh_error(name_, where + ": matrix of " + std::to_string(node.matrix.size()) + " numbers, not 16");
      finite(node.matrix);
      return glm::make_mat4(node.matrix.data());  // column-major, as glTF stores it
    }
    glm::dmat4 m{1.0};
    if (!node.translation.empty()) {
      if (node.translation.size() != 3) throw mesh_error(name_, where + ": translation is not 3 numbers");
      finite(node.translation);
      m[3] = glm::dvec4{node.translation[0], node.translation[1], node.translation[2], 1.0};
    }
    if (!node.rotation.empty()) {
      if (node.rotation.size() != 4) throw mesh_error(name_, where + ": rotation is not 4 numbers");
      finite(node.rotation);
      glm::dquat q{node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]};  // w, x, y, z
      const double len = glm::length(q);
      if (!(len > 0.0) || !std::isfinite(len)) throw mesh_error(name_, where + ": rotation is a zero quaternion");
      m = m * glm::dmat4(glm::mat4_cast(q / len));
    }
    if (!node.scale.empty()) {
      if (node.scale.size() != 3) throw mesh_error(name_, where + ": scale is not 3 numbers");
      finite(node.scale);
      m[0] *= node.scale[0];
      m[1] *= node.scale[1];
      m[2] *= node.scale[2];
    }
    return m;
  }

  void walk(const std::vector<int>& roots) {
    std::vector<bool> seen(model_.nodes.size(), false);
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it)
      stack.emplace_back(*it, glm::dmat4{1.0});
    while (!stack.empty()) {
      const auto [index, parent] = stack.back();
      stack.pop_back();
      if (index < 0 || static_cast<std::size_t>(index) >= model_.nodes.size())
        throw mesh_error(name_, "node " + std::to_string(index) + " does not exist (" +
                                    std::to_string(model_.nodes.size()) + " nodes)");
      const auto i = static_cast<std::size_t>(index);
      if (seen[i])
        throw mesh_error(name_, "node " + std::to_string(i) + " is reached twice (a cycle or a shared child)");
      seen[i] = true;
      const tinygltf::Node& node = model_.nodes[i];
      const glm::dmat4 world = parent * local_transform(node, i);
      if (node.mesh >= 0) {
        if (static_cast<std::size_t>(node.mesh) >= model_.meshes.size())
          throw mesh_error(name_, "node " + std::to_string(i) + " uses mesh " + std::to_string(node.mesh) + " of " +
                                      std::to_string(model_.meshes.size()));
        place(static_cast<std::size_t>(node.mesh), world);
      }
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
        stack.emplace_back(*c, world);
    }
  }

  /// Appends mesh m's parts under the world transform.
  void place(std::size_t m, const glm::dmat4& world) {
    if (!converted_[m]) {
      convert(m);
      converted_[m] = true;
    }
    const glm::dmat3 linear(world);
    const double det = glm::determinant(linear);
    // cofactor matrix = det * inverse transpose: maps normals, and stays
    // defined for a singular transform (the normal then comes out zero).
    const glm::dmat3 cofactor(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]),
                              glm::cross(linear[0], linear[1]));
    const double sign = det < 0.0 ? -1.0 : 1.0;
    TriangleMesh& mesh = out_.mesh;
    for (const GltfPart& part : parts_[m]) {
      if (part.triangles.size() > limit_ - mesh.triangles.size())
        throw mesh_error(name_, "more than " + std::to_string(limit_) +
                                    " triangles after placing every node (raise MeshReadConfig::max_triangles)");
      if (part.positions.size() > max_mesh_elements - mesh.positions.size())
        throw mesh_error(name_, "more than 2^30 vertices after placing every node");
      const auto base = static_cast<std::uint32_t>(mesh.positions.size());
      if (!part.normals.empty() && !any_normals_) {
        any_normals_ = true;
        mesh.normals.assign(mesh.positions.size(), glm::dvec3{0.0});
        normal_missing_.assign(mesh.positions.size(), true);
      }
      if (!part.uvs.empty() && !any_uvs_) {
        any_uvs_ = true;
        uv_missing_ = mesh.positions.size();
        mesh.uvs.assign(mesh.positions.size(), glm::dvec2{0.0});
      }
      for (const glm::dvec3& p : part.positions)
        mesh.positions.push_back(glm::dvec3(world * glm::dvec4(p, 1.0)));
      if (any_normals_) {
        for (std::size_t k = 0; k < part.positions.size(); ++k) {
          mesh.normals.push_back(part.normals.empty() ? glm::dvec3{0.0} : sign * (cofactor * part.normals[k]));
          normal_missing_.push_back(part.normals.empty());
        }
      }
      if (any_uvs_) {
        if (part.uvs.empty()) {
          mesh.uvs.resize(mesh.positions.size(), glm::dvec2{0.0});
          uv_missing_ += part.positions.size();
        } else {
          mesh.uvs.insert(mesh.uvs.end(), part.uvs.begin(), part.uvs.end());
        }
      }
      for (const TriangleIndices& t : part.triangles) {
        if (det < 0.0)
          mesh.triangles.push_back({base + t[0], base + t[2], base + t[1]});  // a mirror: keep faces pointing out
        else
          mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
        mesh.materials.push_back(part.material);
      }
    }
  }

  /// Checks accessor a (count x stride within its buffer view and buffer,
  /// component type among allowed) and returns its element count; nothing
  /// is allocated before these checks pass.
  struct View {
    const unsigned char* data = nullptr;
    std::size_t count = 0;
    std::size_t stride = 0;
    int component = 0;
    std::size_t component_bytes = 0;
    bool normalized = false;
  };
  [[nodiscard]] View view(int a, const char* what, int type, std::initializer_list<int> components) const {
    const std::string where = std::string(what) + " accessor " + std::to_string(a);
    if (a < 0 || static_cast<std::size_t>(a) >= model_.accessors.size())
      throw mesh_error(name_, where + " does not exist (" + std::to_string(model_.accessors.size()) + " accessors)");
    const tinygltf::Accessor& acc = model_.accessors[static_cast<std::size_t>(a)];
    if (acc.sparse.isSparse) throw mesh_error(name_, where + " is sparse, which this reader does not support");
    if (acc.type != type) throw mesh_error(name_, where + " has the wrong type");
    if (std::find(components.begin(), components.end(), acc.componentType) == components.end())
      throw mesh_error(name_, where + " has component type " + std::to_string(acc.componentType) +
                                  ", not one this attribute allows");
    if (acc.count == 0) throw mesh_error(name_, where + " has no elements");
    if (acc.bufferView < 0 || static_cast<std::size_t>(acc.bufferView) >= model_.bufferViews.size())
      throw mesh_error(name_, where + " has no buffer view");
    const tinygltf::BufferView& bv = model_.bufferViews[static_cast<std::size_t>(acc.bufferView)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model_.buffers.size())
      throw mesh_error(name_, where + ": its buffer view uses buffer " + std::to_string(bv.buffer) + " of " +
                                  std::to_string(model_.buffers.size()));
    const std::vector<unsigned char>& buffer = model_.buffers[static_cast<std::size_t>(bv.buffer)].data;
    if (bv.byteOffset > buffer.size() || bv.byteLength > buffer.size() - bv.byteOffset)
      throw mesh_error(name_, where + ": its buffer view (" + std::to_string(bv.byteOffset) + " + " +
                                  std::to_string(bv.byteLength) + " bytes) is outside its buffer of " +
                                  std::to_string(buffer.size()) + " bytes");
    const std::size_t cbytes =
        acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT || acc.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT
            ? 4
        : acc.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                                                                      : 1;
    const std::size_t ncomp = type == TINYGLTF_TYPE_SCALAR ? 1 : type == TINYGLTF_TYPE_VEC2 ? 2 : 3;
    const std::size_t element = cbytes * ncomp;
    const std::size_t stride = bv.byteStride == 0 ? element : bv.byteStride;
    if (stride < element)
      throw mesh_error(name_, where + ": byteStride " + std::to_string(stride) + " is smaller than an element (" +
                                  std::to_string(element) + " bytes)");
    // byteOffset + (count - 1) x stride + element <= byteLength, without overflow
    std::uint64_t span = 0;
    if (acc.byteOffset > bv.byteLength || !checked_mul(acc.count - 1, stride, bv.byteLength - acc.byteOffset, span) ||
        element > bv.byteLength - acc.byteOffset - span)
      throw mesh_error(name_, where + ": " + std::to_string(acc.count) + " elements of stride " +
                                  std::to_string(stride) + " from offset " + std::to_string(acc.byteOffset) +
                                  " do not fit its buffer view of " + std::to_string(bv.byteLength) + " bytes");
    return View{
        buffer.data() + bv.byteOffset + acc.byteOffset, acc.count, stride, acc.componentType, cbytes, acc.normalized};
  }

  [[nodiscard]] static double component(const View& v, std::size_t i, std::size_t c) noexcept {
    const unsigned char* p = v.data + i * v.stride + c * v.component_bytes;
    switch (v.component) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        std::uint32_t bits = gltf_le32(p);
        float f = 0.0f;
        std::memcpy(&f, &bits, 4);
        return static_cast<double>(f);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return static_cast<double>(gltf_le32(p));
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        const double x = static_cast<double>(std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8);
        return v.normalized ? x / 65535.0 : x;
      }
      default:
        return v.normalized ? p[0] / 255.0 : static_cast<double>(p[0]);
    }
  }

  void convert(std::size_t m) {
    const tinygltf::Mesh& mesh = model_.meshes[m];
    for (std::size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = mesh.primitives[pi];
      const std::string where = "mesh " + std::to_string(m) + " primitive " + std::to_string(pi);
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++skipped_;
        continue;
      }
      const auto attribute = [&](const char* key) {
        const auto it = prim.attributes.find(key);
        return it == prim.attributes.end() ? -1 : it->second;
      };
      const int position_accessor = attribute("POSITION");
      if (position_accessor < 0) throw mesh_error(name_, where + " has no POSITION");
      const View pos = view(position_accessor, "POSITION", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
      // Every converted mesh is placed at least once: the triangles of all of
      // them count against the limit before any is built, so many primitives
      // over one large accessor cannot multiply the work or the memory.
      View idx;
      if (prim.indices >= 0)
        idx = view(prim.indices, "index", TINYGLTF_TYPE_SCALAR,
                   {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                    TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
      const std::size_t corner_count = prim.indices >= 0 ? idx.count : pos.count;
      const std::size_t will_make = mode == TINYGLTF_MODE_TRIANGLES ? corner_count / 3
                                    : corner_count >= 3             ? corner_count - 2
                                                                    : 0;
      if (will_make > limit_ - converted_triangles_)
        throw mesh_error(name_, where + ": more than " + std::to_string(limit_) +
                                    " triangles (raise MeshReadConfig::max_triangles)");
      converted_triangles_ += will_make;
      std::vector<std::uint32_t> corners;  // indices into the primitive's vertices
      if (prim.indices >= 0) {
        corners.reserve(idx.count);
        for (std::size_t i = 0; i < idx.count; ++i) {
          const double k = component(idx, i, 0);
          if (k >= static_cast<double>(pos.count))
            throw mesh_error(name_, where + ": index " + std::to_string(i) + " is " +
                                        std::to_string(static_cast<std::uint64_t>(k)) + ", out of range for " +
                                        std::to_string(pos.count) + " vertices");
          corners.push_back(static_cast<std::uint32_t>(k));
        }
      } else {
        if (pos.count > max_mesh_elements) throw mesh_error(name_, where + ": more than 2^30 vertices");
        corners.resize(pos.count);
        for (std::size_t i = 0; i < pos.count; ++i)
          corners[i] = static_cast<std::uint32_t>(i);
      }
      std::vector<std::array<std::uint32_t, 3>> triangles;
      const std::size_t n = corners.size();
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (n % 3 != 0)
          warn(MeshWarningKind::reader,
               where + ": " + std::to_string(n % 3) + " indices after the last triangle ignored");
        for (std::size_t i = 0; i + 2 < n; i += 3)
          triangles.push_back({corners[i], corners[i + 1], corners[i + 2]});
      } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (std::size_t i = 0; i + 2 < n; ++i)
          triangles.push_back(i % 2 == 0 ? std::array{corners[i], corners[i + 1], corners[i + 2]}
                                         : std::array{corners[i], corners[i + 2], corners[i + 1]});
      } else {
        for (std::size_t i = 1; i + 1 < n; ++i)
          triangles.push_back({corners[i], corners[i + 1], corners[0]});
      }
      if (triangles.empty()) continue;
      // Keep only the vertices the triangles use, so a primitive's size is its
      // triangles'. One table for every primitive, reset where it was written.
      if (remap_.size() < pos.count) remap_.resize(pos.count, std::numeric_limits<std::uint32_t>::max());
      std::vector<std::uint32_t>& remap = remap_;
      std::vector<std::uint32_t> used;
      GltfPart part;
      part.triangles.reserve(triangles.size());
      for (const auto& t : triangles) {
        TriangleIndices out{};
        for (std::size_t c = 0; c < 3; ++c) {
          std::uint32_t& r = remap[t[c]];
          if (r == std::numeric_limits<std::uint32_t>::max()) {
            r = static_cast<std::uint32_t>(used.size());
            used.push_back(t[c]);
          }
          out[c] = r;
        }
        part.triangles.push_back(out);
      }
      for (const std::uint32_t k : used)
        remap[k] = std::numeric_limits<std::uint32_t>::max();
      part.positions.reserve(used.size());
      for (const std::uint32_t k : used) {
        const glm::dvec3 p{component(pos, k, 0), component(pos, k, 1), component(pos, k, 2)};
        if (!finite3(p))
          throw mesh_error(name_, where + ": POSITION " + std::to_string(k) + " is not finite " + to_text(p));
        part.positions.push_back(p);
      }
      if (const int a = attribute("NORMAL"); a >= 0) {
        const View nv = view(a, "NORMAL", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
        if (nv.count != pos.count)
          throw mesh_error(name_, where + ": " + std::to_string(nv.count) + " normals for " +
                                      std::to_string(pos.count) + " positions");
        for (const std::uint32_t k : used) {
          const glm::dvec3 nrm{component(nv, k, 0), component(nv, k, 1), component(nv, k, 2)};
          if (!finite3(nrm))
            throw mesh_error(name_, where + ": NORMAL " + std::to_string(k) + " is not finite " + to_text(nrm));
          part.normals.push_back(nrm);
        }
      }
      if (const int a = attribute("TEXCOORD_0"); a >= 0) {
        const View tv = view(a, "TEXCOORD_0", TINYGLTF_TYPE_VEC2,
                             {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                              TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
        if (tv.count != pos.count)
          throw mesh_error(name_, where + ": " + std::to_string(tv.count) + " texture coordinates for " +
                                      std::to_string(pos.count) + " positions");
        for (const std::uint32_t k : used) {
          const glm::dvec2 uv{component(tv, k, 0), 1.0 - component(tv, k, 1)};  // glTF's v points down
          if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
            throw mesh_error(name_, where + ": TEXCOORD_0 " + std::to_string(k) + " is not finite");
          part.uvs.push_back(uv);
        }
      }
      if (prim.material >= 0) {
        if (static_cast<std::size_t>(prim.material) >= model_.materials.size())
          throw mesh_error(name_, where + " uses material " + std::to_string(prim.material) + " of " +
                                      std::to_string(model_.materials.size()));
        part.material = static_cast<std::uint32_t>(prim.material);
      } else {
        part.material = default_material_;
        use_default_material_ = true;
      }
      parts_[m].push_back(std::move(part));
    }
  }

  const tinygltf::Model& model_;
  const std::string& name_;
  std::size_t limit_;
  LoadedMesh& out_;
  std::vector<std::vector<GltfPart>> parts_;
  std::vector<bool> converted_;
  std::vector<std::uint32_t> remap_;     ///< file vertex -> part vertex, all unset between primitives
  std::size_t converted_triangles_ = 0;  ///< triangles of every converted primitive
  std::vector<bool> normal_missing_;
  std::uint32_t default_material_ = 0;
  bool use_default_material_ = false;
  bool any_normals_ = false;
  bool any_uvs_ = false;
  std::size_t uv_missing_ = 0;
  std::size_t skipped_ = 0;
};

}  // namespace detail

/// The tinygltf model of a .gltf or .glb in memory, read with every check
/// parse_gltf() makes before tinygltf parses (size, .glb layout, nesting,
/// external files only from resource_dir within config.max_file_bytes);
/// images are kept encoded (Image::image holds the PNG or JPEG bytes).
/// For readers of glTF extensions (io/gltf_haptic_material.hpp).
/// @throws FileError as parse_gltf() for what tinygltf refuses.
[[nodiscard]] inline tinygltf::Model read_gltf_model(std::string_view bytes, const std::string& name,
                                                     const MeshReadConfig& config, const std::string& resource_dir,
                                                     std::string& warn) {
  using namespace detail;
  check_config(config);
  if (bytes.size() > std::numeric_limits<std::uint32_t>::max() / 2)
    throw mesh_error(name, "larger than 2 GiB, the most a glTF file can hold here");
  const bool binary = bytes.size() >= 4 && bytes.substr(0, 4) == "glTF";
  check_json_depth(binary ? check_glb(bytes, name) : bytes, name);

  GltfFiles files;
  files.dir = resource_dir;
  files.per_file = config.max_file_bytes;
  files.budget = config.max_file_bytes > bytes.size() ? config.max_file_bytes - bytes.size() : 0;
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks(
      tinygltf::FsCallbacks{&GltfFiles::exists, &GltfFiles::expand, &GltfFiles::read, &GltfFiles::write, &files});
  loader.SetImageLoader(&keep_gltf_image, nullptr);
  tinygltf::Model model;
  std::string err;
  bool ok = false;
  try {
    const auto length = static_cast<unsigned int>(bytes.size());
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                              length, resource_dir)
                : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), length, resource_dir);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw mesh_error(name, e.what());
  }
  if (!ok) {
    std::string why = first_line(err);
    // tinygltf joins an absolute uri to the folder and then says "File not found" even when the file exists
    static constexpr std::string_view not_found = "File not found : ";
    const std::string missing = why.rfind(not_found, 0) == 0 ? why.substr(not_found.size()) : std::string();
    const std::filesystem::path uri(missing);
    if (!missing.empty() && (uri.is_absolute() || uri.has_root_name() || uri.has_root_directory()))
      throw mesh_error(name, "external buffer '" + missing +
                                 "' is an absolute path: not read (a buffer's uri must be relative to the glTF "
                                 "file, inside its folder)");
    if (!files.refused.empty()) why += " (refused to read '" + files.refused.front() + "': outside the file's folder)";
    throw mesh_error(name, why);
  }
  return model;
}

/// Reads a .gltf or .glb already in memory (a .glb is told by its "glTF"
/// magic).
/// @param name          the file's name for messages
/// @param resource_dir  the folder external buffers are read from (never
///                      outside it); empty: only embedded data is allowed
/// @throws FileError naming the file for anything tinygltf refuses, an
///         external buffer given by an absolute path (uris must be relative
///         to the file, inside its folder), a
///         broken .glb layout, JSON nested too deeply, an accessor whose
///         count x stride overruns its buffer, indices out of range,
///         non-finite values, cycles in the node graph, required
///         extensions that change geometry (Draco, meshopt, quantization,
///         GPU instancing), sparse accessors, no triangles, or more than
///         config.max_triangles.
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline LoadedMesh parse_gltf(std::string_view bytes, const std::string& name,
                                           const MeshReadConfig& config = {}, const std::string& resource_dir = {}) {
  std::string warn;
  const tinygltf::Model model = read_gltf_model(bytes, name, config, resource_dir, warn);
  LoadedMesh out;
  detail::add_reader_warnings(out, warn);
  detail::GltfReader reader(model, name, config, out);
  reader.run();
  detail::finish_mesh(out, name, config, reader.take_normal_missing());
  return out;
}

/// Reads a .gltf or .glb file of at most config.max_file_bytes, with its
/// external buffers from the same folder (their sum within the same limit).
/// @throws FileError as parse_gltf(), or when the file is missing, not a
///         regular file, unreadable or too large.
[[nodiscard]] inline LoadedMesh load_gltf(const std::string& path, const MeshReadConfig& config = {}) {
  detail::check_config(config);
  const std::string bytes = read_file(path, config.max_file_bytes);
  return parse_gltf(bytes, path, config, detail::folder_of(path));
}

}  // namespace hapticfield::io
