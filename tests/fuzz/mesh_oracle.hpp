// What every mesh reader's fuzz target checks on a mesh the reader
// accepted: the promises of LoadedMesh (io/mesh_read.hpp). A broken one
// aborts, which libFuzzer reports as a finding.
#pragma once

#include <cmath>
#include <cstdlib>

#include "hapticfield/io/mesh_read.hpp"

inline void check_loaded_mesh(const hapticfield::io::LoadedMesh& m) {
  const hapticfield::TriangleMesh& mesh = m.mesh;
  try {
    mesh.validate();
  } catch (...) {
    std::abort();
  }
  if (mesh.triangles.empty()) std::abort();
  for (const auto& n : mesh.normals)
    if (std::abs(glm::length(n) - 1.0) > 1e-9) std::abort();  // unit normals
  if (!mesh.materials.empty()) {
    if (m.material_names.empty()) std::abort();
    for (const auto k : mesh.materials)
      if (k >= m.material_names.size()) std::abort();
  }
}
