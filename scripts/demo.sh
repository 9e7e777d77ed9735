#!/usr/bin/env bash
# Builds the examples the README's first sections run (tangible_image and
# servo_demo) and feels the shipped photograph: ./scripts/demo.sh
# Writes the force pictures to out/tangible/ and prints where they went.
# ./scripts/demo.sh --dry-run prints the commands instead of running them.
set -euo pipefail
cd "$(dirname "$0")/.."
dry_run=false
case "${1:-}" in
  --dry-run) dry_run=true ;;
  "") ;;
  -h | --help) sed -n '2,5s/^# \{0,1\}//p' "$0"; exit 0 ;;
  *) echo "demo.sh: unknown option '$1' (--dry-run or --help)" >&2; exit 2 ;;
esac
run() {
  if $dry_run; then printf '%q ' "$@" | sed 's/ $//'; echo; else "$@"; fi
}
build=${HAPTICFIELD_BUILD_DIR:-build}
run ./scripts/deps.sh
run cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release
run cmake --build "$build" -j"$(nproc)" --target tangible_image servo_demo
run "$build/examples/tangible_image" examples/data/coffee.png --mask prewitt --size 17 --maps out/tangible
$dry_run || echo "next: $build/examples/servo_demo --seconds 10 --trace t.csv --plots plots (README, 'Device and servo loop')"
