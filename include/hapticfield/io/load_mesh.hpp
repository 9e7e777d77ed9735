#pragma once
/// @file load_mesh.hpp
/// load_mesh(): one call for every mesh format, chosen by the file's
/// extension (.gltf, .glb, .obj, .stl). Needs tinygltf and tinyobjloader
/// (CMake target hapticfield::io). Never used in a tick.

#include <filesystem>
#include <string>

#include "hapticfield/io/gltf.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/io/obj.hpp"
#include "hapticfield/io/stl.hpp"

namespace hapticfield::io {

/// Reads a mesh file by its extension (case-insensitive): .gltf and .glb
/// (load_gltf), .obj (load_obj), .stl (load_stl).
/// @throws FileError for another extension, and as the reader it calls.
/// @throws std::invalid_argument for bad settings.
[[nodiscard]] inline LoadedMesh load_mesh(const std::string& path, const MeshReadConfig& config = {}) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext)
    c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (ext == ".gltf" || ext == ".glb") return load_gltf(path, config);
  if (ext == ".obj") return load_obj(path, config);
  if (ext == ".stl") return load_stl(path, config);
  throw detail::mesh_error(path, "unknown mesh format '" + ext + "' (.gltf, .glb, .obj or .stl)");
}

}  // namespace hapticfield::io
