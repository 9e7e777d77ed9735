// libFuzzer target for the example tools' CSV reader (tools/common/csv.hpp):
// the input is parsed as an x,y file and as an x,y,vx,vy file, with small
// bounds so long lines and many rows are reached. Any exception other than
// FileError, or a result that breaks the reader's promises, is a finding.
// Built with clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the seed corpus
// also runs as a plain ctest test through corpus_runner.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "common/csv.hpp"

namespace {

using namespace hapticfield;

template <std::size_t N>
void parse(std::string_view text, const cli::CsvConfig& config) {
  try {
    const auto rows = cli::parse_csv<N>(text, "fuzz.csv", config);
    if (rows.size() > config.max_rows) std::abort();
    if (rows.empty() && !config.allow_empty) std::abort();
    if (config.finite_only)
      for (const auto& row : rows)
        for (double v : row)
          if (!std::isfinite(v)) std::abort();
  } catch (const FileError& e) {
    const std::string message = e.what();
    if (message.rfind("fuzz.csv", 0) != 0) std::abort();  // every message names the file
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  parse<2>(text, {.columns = "x,y", .what = "probes", .max_line_bytes = 64, .max_rows = 50});
  parse<4>(text, {.columns = "x,y,vx,vy",
                  .what = "probes",
                  .max_line_bytes = 4096,
                  .max_rows = 1000,
                  .finite_only = true,
                  .allow_empty = true});
  return 0;
}
