#!/usr/bin/env bash
# The Swap test N times in a row, each time with a random seed and kill step, while `stress` keeps both cores
# busy (issue 54: "a run ended done while its restarted motivation never took the run's configuration", seen now
# and then): every run must pass. A failing run's artefacts are kept in WORK_DIR/failed-K.
#   tests/swap/repeat.sh BUILD_DIR WORK_DIR [N] [random|python-imp] [STRESS_WORKERS]
# Not a ctest test (it takes an hour or more): its figures are in docs/performance.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
mkdir -p "$2"
out=$(cd "$2" && pwd)
n=${3:-100}
own=${4:-python-imp}
workers=${5:-2}
command -v stress >/dev/null || { echo "repeat.sh: needs stress (apt-get install stress)"; exit 2; }
stress --cpu "$workers" >/dev/null 2>&1 &
load=$!
trap 'kill $load 2>/dev/null || true' EXIT
failed=0
for ((k = 1; k <= n; k++)); do
  start=$SECONDS
  if bash "$root/tests/swap/test_swap.sh" "$build" "$out/run" any "$own" >"$out/run.txt" 2>&1; then
    echo "run $k: passed in $((SECONDS - start)) s: $(grep -o 'seed [0-9]*: killed the own motivation after step [0-9]*' "$out/run.txt")"
  else
    failed=$((failed + 1))
    rm -rf "$out/failed-$k" && mv "$out/run" "$out/failed-$k" && cp "$out/run.txt" "$out/failed-$k/"
    echo "run $k: FAILED in $((SECONDS - start)) s ($out/failed-$k): $(tail -n 1 "$out/run.txt")"
  fi
done
echo "$n runs of the Swap test ($own) under stress on $workers cores: $((n - failed)) passed, $failed failed"
((failed == 0))
