// libFuzzer target for the HaTT model-file reader (parse_hatt_model_set,
// the code behind load_hatt_model_set): any input must give a model set
// that HattTexture accepts and renders with finite forces, or a
// HattFileError; any other exception, crash, hang or sanitizer report is a
// finding. The audio path (HattSource) plays it too, within its bound of
// model steps per audio frame. Built with clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the
// seed corpus (corpus_hatt/) also runs as a plain ctest test through
// corpus_runner.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/vibration/hatt_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapticfield;
  using namespace hapticfield::texture;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  HattModelSet set;
  try {
    set = parse_hatt_model_set(text, "fuzz input");
  } catch (const HattFileError&) {
    return 0;
  }
  // a set the reader accepts must be one the renderer accepts (orders are
  // capped at max_hatt_order), and its forces must stay finite
  HattTexture<max_hatt_order> tex(set, HattConfig{});
  Probe p;
  p.period = 1e-3;
  for (int i = 0; i < 64; ++i) {
    p.velocity = {0.001 + 0.5 * (i % 16) / 16.0, 0.0, 0.0};  // [m/s]
    p.normal_force = 0.1 * (i % 7);                          // [N]
    if (!is_finite(tex.force(p))) std::abort();
  }
  // and on the audio path: finite output, bounded work per frame
  vibration::HattSource<max_hatt_order> source(set, {});
  source.prepare(8000.0);
  for (int i = 0; i < 256; ++i) {
    const vibration::ContactState c{0.001 + 0.5 * (i % 16) / 16.0, 0.1 * (i % 7), 0, true};
    if (!std::isfinite(source.next(c))) std::abort();
  }
  if (source.model_steps() > 256u * static_cast<unsigned>(vibration::max_hatt_steps_per_sample)) std::abort();
  return 0;
}
