#!/usr/bin/env bash
# Checks that every C++ file git tracks is formatted as .clang-format says
# (120 columns, Google-based): ./scripts/check-format.sh
# With --fix it formats them in place instead.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  -h|--help) echo "usage: scripts/check-format.sh [--fix]   check (or fix) the C++ formatting of every tracked file"; exit 0 ;;
  --fix) mode=(-i) ;;
  "") mode=(--dry-run --Werror) ;;
  *) echo "check-format.sh: unknown option '$1' (--help shows the usage)" >&2; exit 2 ;;
esac
command -v clang-format >/dev/null || { echo "check-format.sh: clang-format is not installed (apt-get install clang-format)" >&2; exit 1; }
git ls-files -z '*.hpp' '*.cpp' '*.h' | xargs -0 clang-format "${mode[@]}"
echo "formatting: $(git ls-files '*.hpp' '*.cpp' '*.h' | wc -l) files checked"
