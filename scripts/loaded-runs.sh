#!/usr/bin/env bash
# Runs the test suite again and again beside busy processes, to show that no
# test depends on the machine being idle:
#
#   ./scripts/loaded-runs.sh [--ctest N] [--python N] [--busy B] [--build DIR]
#
#   --ctest N    whole ctest runs (default 10)
#   --python N   runs of the Python tests alone (default 30)
#   --busy B     busy processes beside them (default 2: 'while :; do :; done')
#   --build DIR  an existing build folder (default build; ./scripts/test.sh makes it)
#
# Prints one line per run and a closing "N passed, N failed" line; exits 1 when
# any run failed. The busy processes are stopped on exit, whatever happens.
set -euo pipefail
cd "$(dirname "$0")/.."

ctest_runs=10 python_runs=30 busy=2 build=build
usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    -h | --help) usage; exit 0 ;;
    --ctest | --python | --busy | --build)
      [ $# -ge 2 ] || { echo "loaded-runs.sh: $1 needs a value" >&2; exit 2; }
      case "$1" in
        --build) build=$2 ;;
        *)
          [[ "$2" =~ ^[0-9]+$ ]] || { echo "loaded-runs.sh: $1 takes a whole number, got '$2'" >&2; exit 2; }
          case "$1" in --ctest) ctest_runs=$2 ;; --python) python_runs=$2 ;; --busy) busy=$2 ;; esac ;;
      esac
      shift 2 ;;
    *) echo "loaded-runs.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -f "$build/CTestTestfile.cmake" ] || { echo "loaded-runs.sh: no build in '$build' (run ./scripts/test.sh first)" >&2; exit 1; }

pids=()
stop_busy() { [ ${#pids[@]} -eq 0 ] || kill "${pids[@]}" 2>/dev/null || true; }
trap stop_busy EXIT
for _ in $(seq 1 "$busy"); do
  sh -c 'while :; do :; done' &
  pids+=($!)
done
echo "loaded-runs: $busy busy processes beside the tests (pids ${pids[*]:-none}) on $(nproc) cores"

passed=0 failed=0
log=$(mktemp)
for i in $(seq 1 "$ctest_runs"); do
  start=$(date +%s)
  if ctest --test-dir "$build" -j"$(nproc)" --output-on-failure >"$log" 2>&1; then
    passed=$((passed + 1)); verdict=passed
  else
    failed=$((failed + 1)); verdict="FAILED: $(grep -E '\*\*\*Failed|Failed +[0-9.]+ sec|\(Failed\)' "$log" | tr -s ' ' | paste -sd ';' -)"
    cp "$log" "$build/loaded-ctest-$i.log"
  fi
  echo "ctest run $i: $verdict ($(($(date +%s) - start)) s)"
done
for i in $(seq 1 "$python_runs"); do
  start=$(date +%s)
  if ctest --test-dir "$build" -R '^python_bindings$' --output-on-failure >"$log" 2>&1; then
    passed=$((passed + 1)); verdict=passed
  else
    failed=$((failed + 1)); verdict="FAILED: $(grep -E '^FAILED|[0-9]+ failed' "$log" | paste -sd ';' -)"
    cp "$log" "$build/loaded-python-$i.log"
  fi
  echo "python run $i: $verdict ($(($(date +%s) - start)) s)"
done
rm -f "$log"
echo "loaded runs: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
