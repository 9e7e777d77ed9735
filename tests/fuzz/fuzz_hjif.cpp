// libFuzzer target for the .hjif reader and the synthesis behind it (io/hjif.hpp, material/band_synthesis.hpp): any
// input must give a media that renders to finite samples and writes back to text the reader takes again, or one
// FileError; any other exception, crash, hang or sanitizer report is a finding. Built with clang -fsanitize=fuzzer
// (HAPTICFIELD_FUZZ=ON); the seed corpus (corpus_hjif/) also runs as a plain ctest test through corpus_runner.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "hapticfield/io/hjif.hpp"
#include "hapticfield/material/band_synthesis.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hapticfield::io::HjifLimits limits;
  limits.max_values = 200'000;  // bounds the work of one input (rendering below is per keyframe and sample)
  try {
    const auto file = hapticfield::io::parse_hjif(bytes, "fuzz input", limits);
    const auto again = hapticfield::io::parse_hjif(hapticfield::io::write_hjif_string(file.media), "rewritten", limits);
    (void)again;
    if (hapticfield::material::media_duration(file.media) <= 2.0) {  // a short render at a low rate: bounded time
      const auto r = hapticfield::material::render_media(file.media, 1000.0);
      for (const auto& c : r.channels)
        for (double y : c)
          if (!std::isfinite(y)) std::abort();
    }
  } catch (const hapticfield::FileError&) {
  } catch (const std::invalid_argument&) {  // render_media's refusals (rate, timescale, length)
  }
  return 0;
}
