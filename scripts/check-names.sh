#!/usr/bin/env bash
# Checks the naming of every public header with clang-tidy's
# readability-identifier-naming (.clang-tidy): ./scripts/check-names.sh
# One translation unit includes every header under include/hapticfield.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  -h|--help) echo "usage: scripts/check-names.sh   check the naming of every public header (.clang-tidy)"; exit 0 ;;
  "") ;;
  *) echo "check-names.sh: unknown option '$1' (--help shows the usage)" >&2; exit 2 ;;
esac
command -v clang-tidy >/dev/null || { echo "check-names.sh: clang-tidy is not installed (apt-get install clang-tidy)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
{
  echo '// Every public header, for the naming check.'
  git ls-files 'include/hapticfield/*.hpp' | sed 's|^include/\(.*\)|#include "\1"|'
  echo 'int main() { return 0; }'
} > "$work/all_headers.cpp"
clang-tidy --quiet --config-file=.clang-tidy "$work/all_headers.cpp" -- -std=c++20 -I"$PWD/include" \
  $(pkg-config --cflags opencv4 hidapi-hidraw 2>/dev/null) $(pkg-config --cflags libusb-1.0 2>/dev/null) >"$work/out.txt" 2>&1 || {
  grep -E "error:|warning:" "$work/out.txt" | sort -u >&2 || cat "$work/out.txt" >&2
  echo "check-names.sh: naming does not follow .clang-tidy (above)" >&2
  exit 1
}
echo "naming: $(git ls-files 'include/hapticfield/*.hpp' | wc -l) headers checked"
