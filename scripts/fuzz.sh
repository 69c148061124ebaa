#!/usr/bin/env bash
# Run every fuzz target (tests/fuzz, docs/processes-and-channels.md "Fuzzing")
# under libFuzzer, ASan and UBSan, each for N seconds:
#   edge       the message edge's decoding of every type (seeds: a sample of
#              each type; a custom mutator sets size fields)
#   logreader  the project's log reader (seeds: the logs of a short real run)
# Builds the targets with clang in BUILD/fuzz first (the main build does, with its tests). Per target, the corpus
# stays in BUILD/fuzz/<target>/corpus; a crash leaves its input in
# BUILD/fuzz/<target>/crashes/ and the script fails naming it; the fuzzer's
# whole output is in BUILD/fuzz/<target>/fuzz.log. The inputs of bugs found
# before (tests/fuzz/regressions/<target>) are run every time.
# Usage: scripts/fuzz.sh [--seconds N] [--build-dir BUILD] [--only TARGET]   (defaults: 300 each, build, all)
# Needs the main build in BUILD first (its generated LCM headers and `afford`) and clang.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=300
build=$root/build
only=
while (($#)); do
  case $1 in
    --seconds) seconds=${2:?--seconds needs a value}; shift 2 ;;
    --build-dir) build=${2:?--build-dir needs a value}; shift 2 ;;
    --only) only=${2:?--only needs a target}; shift 2 ;;
    -h | --help) sed -n '2,14p' "$0" | cut -c3-; exit 0 ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ $seconds =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds must be a positive integer" >&2; exit 2; }
[[ -z $only || $only == edge || $only == logreader ]] || { echo "fuzz.sh: --only edge or logreader" >&2; exit 2; }
# The fuzz targets compile against the main build's generated LCM headers.
[[ -f $build/lcmgen/cpp/afford/wire_bounds.hpp && -x $build/bin/afford ]] || {
  echo "fuzz.sh: no main build in $build: build the project first (cmake --build $build)" >&2
  exit 1
}
build=$(cd "$build" && pwd)
clangxx=$(command -v clang++ || command -v clang++-14 || true)
clang=$(command -v clang || command -v clang-14 || true)
[[ -n $clangxx && -n $clang ]] || { echo "fuzz.sh: clang not found (scripts/setup.sh installs it)" >&2; exit 1; }

fuzz=$build/fuzz
mkdir -p "$fuzz"
# Configured once (the main build with its tests does it, and builds them: then this is quick).
echo "fuzz.sh: building the fuzz targets in $fuzz"
if [[ ! -f $fuzz/CMakeCache.txt ]]; then
  cmake -S "$root/tests/fuzz" -B "$fuzz" -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" \
    -DAFFORD_MAIN_BUILD="$build" >"$fuzz/configure.log" 2>&1 || { cat "$fuzz/configure.log"; exit 1; }
fi
cmake --build "$fuzz" -j2 >"$fuzz/build.log" 2>&1 || { cat "$fuzz/build.log"; exit 1; }
echo "fuzz.sh: built in $SECONDS s"

# seeds_edge DIR: the sample of every type, sealed, in both contexts.
seeds_edge() { "$fuzz/fuzz_edge_seeds" "$1"; }
# seeds_logreader DIR: the log of a short real run (in this process, no network), whole and its first 64 KB.
seeds_logreader() {
  local run=$fuzz/logreader/seed-run
  rm -rf "$run"
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 12 --transport memq --no-reuse-agents --quiet \
    --progress none --run-prefix seed --out "$run/out" --log-root "$run/logs" >"$run.log" 2>&1 ||
    { cat "$run.log"; echo "fuzz.sh: the seed run failed" >&2; exit 1; }
  local log=$run/logs/seed-base-IMP-s1/log.00.lcm
  cp "$log" "$1/run.lcm"
  head -c 65536 "$log" >"$1/run-first-64k.lcm"
}

# fuzz TARGET [extra libFuzzer options]: one process; new inputs go to the corpus (the first folder).
fuzz_one() {
  local target=$1 dir=$fuzz/$1
  shift
  rm -rf "$dir/seeds"
  mkdir -p "$dir/corpus" "$dir/crashes" "$dir/seeds"
  "seeds_$target" "$dir/seeds"
  echo "fuzz.sh: $target: fuzzing for $seconds s (log: $dir/fuzz.log)"
  local status=0
  UBSAN_OPTIONS=print_stacktrace=1 "$fuzz/fuzz_$target" "$dir/corpus" "$dir/seeds" "$root/tests/fuzz/regressions/$target" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=256 \
    -artifact_prefix="$dir/crashes/" -print_final_stats=1 "$@" >"$dir/fuzz.log" 2>&1 || status=$?
  grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::number_of_executed_units|^fuzz_[a-z]+: ' "$dir/fuzz.log" | sed "s/^/  /" || true
  if ((status != 0)); then
    tail -n 60 "$dir/fuzz.log"
    local input
    input=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$dir/fuzz.log" | tail -n 1)
    echo "fuzz.sh: $target: the fuzzer failed (exit status $status)"
    [[ -n $input ]] && echo "fuzz.sh: reproducer: $input (run: $fuzz/fuzz_$target $input)"
    exit 1
  fi
  echo "fuzz.sh: $target: no crash, leak, UBSan report or allocation beyond 256 MB in $seconds s; corpus: $dir/corpus ($(ls "$dir/corpus" | wc -l) inputs)"
}

if [[ -z $only || $only == edge ]]; then
  fuzz_one edge
  mutations=$(sed -n 's/^fuzz_edge: custom mutator: .* \([0-9][0-9]*\) size-field mutations.*/\1/p' "$fuzz/edge/fuzz.log")
  if [[ -z $mutations || $mutations -eq 0 ]]; then
    echo "fuzz.sh: edge: the custom mutator set no size field" >&2
    exit 1
  fi
fi
[[ -z $only || $only == logreader ]] && fuzz_one logreader -max_len=131072
exit 0
