// libFuzzer target for the glTF reader (parse_gltf through tinygltf, .gltf and .glb, the code behind load_gltf): any
// input must give a mesh that keeps LoadedMesh's promises (mesh_oracle.hpp) or a FileError; any other exception, crash,
// hang or sanitizer report is a finding. Built with clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the seed corpus
// (corpus_gltf/) also runs as a plain ctest test through corpus_runner.cpp.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "hapticfield/io/gltf.hpp"
#include "mesh_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hapticfield::io::MeshReadConfig config;
  config.max_triangles = 1'000'000;  // bounds the work of one input, not its memory (the reader does that)
  try {
    check_loaded_mesh(hapticfield::io::parse_gltf(bytes, "fuzz input", config));
  } catch (const hapticfield::FileError&) {
  }
  return 0;
}
