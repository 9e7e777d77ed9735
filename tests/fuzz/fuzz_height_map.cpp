// libFuzzer target for the height-map readers (load_depth_map and
// load_height_picture: the header's pixel limit, OpenCV's decoders, the
// conversion to a HeightGrid): any input, written to a file, must give a
// grid of at least 2 x 2 that validates or a FileError; any other exception, crash, hang or
// sanitizer report is a finding. Built with clang -fsanitize=fuzzer
// (HAPTICFIELD_FUZZ=ON); the seed corpus (corpus_height_map/) also runs as
// a plain ctest test through corpus_runner.cpp.
//
// Pictures are limited to 2^20 px here, and OpenCV's own decoders (for the
// formats whose size is not read from the header first) to 2^22 px through
// OPENCV_IO_MAX_IMAGE_PIXELS, so one input cannot take gigabytes.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "hapticfield/io/height_map.hpp"

namespace {

const bool opencv_limit_set = [] { return ::setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "4194304", 1) == 0; }();

const std::string& input_path() {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("hapticfield_fuzz_height_" + std::to_string(::getpid()) + ".img"))
          .string();
  return path;
}

void check(const hapticfield::io::HeightGrid& g) {
  if (g.width < 2 || g.height < 2) std::abort();  // a surface needs four heights: smaller is a FileError
  try {
    g.validate();
  } catch (...) {
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)opencv_limit_set;
  {
    std::FILE* f = std::fopen(input_path().c_str(), "wb");
    if (!f) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
  }
  hapticfield::io::DepthMapConfig depth;
  depth.max_pixels = std::uint64_t{1} << 20;
  depth.blur_sigma = size % 2 == 0 ? 0.0 : 1.5;
  hapticfield::io::PictureHeightConfig picture;
  picture.max_pixels = std::uint64_t{1} << 20;
  try {
    check(hapticfield::io::load_depth_map(input_path(), depth));
  } catch (const hapticfield::FileError&) {
  }
  try {
    check(hapticfield::io::load_height_picture(input_path(), picture));
  } catch (const hapticfield::FileError&) {
  }
  std::remove(input_path().c_str());
  return 0;
}
