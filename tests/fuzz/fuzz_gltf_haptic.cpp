// libFuzzer target for the glTF MPEG_haptic_material reader (io/gltf_haptic_material.hpp): any input must give
// a model whose haptic materials turn into material maps, or one FileError (std::invalid_argument for a range
// that makes a stiffness <= 0); any other exception, crash, hang or sanitizer report is a finding. Built with
// clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the seed corpus (corpus_gltf_haptic/) also runs as a plain ctest
// test through corpus_runner.cpp.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "hapticfield/io/gltf_haptic_material.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  hapticfield::io::HapticMaterialReadConfig config;
  config.mesh.max_triangles = 100'000;
  config.max_texture_pixels = 1u << 16;  // bounds the decoding work of one input
  try {
    const auto model = hapticfield::io::parse_gltf_haptic(bytes, "fuzz input", config);  // no folder: no files
    for (const auto& m : model.haptics.materials) {
      const auto layers = hapticfield::io::haptic_material_layers(m);
      (void)layers.maps.stiffness.at({0.3, 0.7});
    }
  } catch (const hapticfield::FileError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
