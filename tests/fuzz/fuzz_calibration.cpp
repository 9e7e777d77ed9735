// libFuzzer target for the calibration reader (Camera::from_text, the code
// behind Camera::from_file): any input must give a valid Camera or a
// CalibrationError; any other exception, crash, hang or sanitizer report is
// a finding. Built with clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the
// seed corpus (corpus_calibration/) also runs as a plain ctest test through
// corpus_runner.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "hapticfield/normals/camera.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const hapticfield::Camera c = hapticfield::Camera::from_text(text, "fuzz input");
    const cv::Matx33d& k = c.matrix();
    for (int i = 0; i < 9; ++i)
      if (!std::isfinite(k.val[i])) std::abort();  // the constructor's checks must hold
    if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0) || k(2, 2) != 1.0) std::abort();
    const std::size_t n = c.distortion().size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) std::abort();
    if (c.width() < 0 || c.height() < 0) std::abort();
  } catch (const hapticfield::CalibrationError&) {
  }
  return 0;
}
