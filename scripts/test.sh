#!/usr/bin/env bash
# Builds hapticfield and runs every test: ./scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/deps.sh
build=${HAPTICFIELD_BUILD_DIR:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
