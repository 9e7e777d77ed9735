#!/usr/bin/env bash
# Builds the examples and feels the shipped photograph: ./scripts/demo.sh
# Writes the force pictures to out/tangible/ and prints where they went.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/deps.sh
build=${HAPTICFIELD_BUILD_DIR:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target tangible_image
"$build/examples/tangible_image" examples/data/coffee.png --mask prewitt --size 17 --maps out/tangible
