#pragma once
// The seed of a property test: Catch's --rng-seed when given, else a new one
// each run (print it with INFO or on stdout so a failure can be replayed).
#include <cstdint>
#include <random>

#include <catch2/catch.hpp>

namespace hapticfield::test {

/// Catch's --rng-seed when given (non-zero), else a new random seed.
inline std::uint32_t run_seed() {
  const unsigned s = Catch::getCurrentContext().getConfig()->rngSeed();
  return s != 0 ? s : std::random_device{}();
}

}  // namespace hapticfield::test
