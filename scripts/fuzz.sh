#!/usr/bin/env bash
# Fuzz the message edge (tests/fuzz, docs/processes-and-channels.md "Fuzzing"):
# build the fuzz target with clang, libFuzzer, ASan and UBSan in BUILD/fuzz,
# write the seeds, run the fuzzer for N seconds. The corpus stays in
# BUILD/fuzz/corpus; a crash leaves its input in BUILD/fuzz/crashes/ and the
# script fails naming it. The whole output is in BUILD/fuzz/fuzz.log.
# Usage: scripts/fuzz.sh [--seconds N] [--build-dir BUILD]   (defaults: 300, build)
# Needs the main build in BUILD first (its generated LCM headers) and clang.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=300
build=$root/build
while (($#)); do
  case $1 in
    --seconds) seconds=${2:?--seconds needs a value}; shift 2 ;;
    --build-dir) build=${2:?--build-dir needs a value}; shift 2 ;;
    -h | --help) sed -n '2,9p' "$0" | cut -c3-; exit 0 ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ $seconds =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds must be a positive integer" >&2; exit 2; }
# The fuzz target compiles against the main build's generated LCM headers.
[[ -f $build/lcmgen/cpp/afford/wire_bounds.hpp ]] || {
  echo "fuzz.sh: no main build in $build: build the project first (cmake --build $build)" >&2
  exit 1
}
build=$(cd "$build" && pwd)
clangxx=$(command -v clang++ || command -v clang++-14 || true)
clang=$(command -v clang || command -v clang-14 || true)
[[ -n $clangxx && -n $clang ]] || { echo "fuzz.sh: clang not found (scripts/setup.sh installs it)" >&2; exit 1; }

fuzz=$build/fuzz
mkdir -p "$fuzz"
echo "fuzz.sh: building the fuzz target in $fuzz"
cmake -S "$root/tests/fuzz" -B "$fuzz" -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" -DAFFORD_MAIN_BUILD="$build" \
  >"$fuzz/configure.log" 2>&1 || { cat "$fuzz/configure.log"; exit 1; }
cmake --build "$fuzz" -j2 >"$fuzz/build.log" 2>&1 || { cat "$fuzz/build.log"; exit 1; }
echo "fuzz.sh: built in $SECONDS s"

rm -rf "$fuzz/seeds"
mkdir -p "$fuzz/corpus" "$fuzz/crashes"
"$fuzz/fuzz_edge_seeds" "$fuzz/seeds"

# One process: new inputs go to the corpus (the first folder); the seeds and
# the inputs of bugs found before (tests/fuzz/regressions) are read too.
echo "fuzz.sh: fuzzing for $seconds s (log: $fuzz/fuzz.log)"
status=0
UBSAN_OPTIONS=print_stacktrace=1 "$fuzz/fuzz_edge" "$fuzz/corpus" "$fuzz/seeds" "$root/tests/fuzz/regressions" \
  -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=256 \
  -artifact_prefix="$fuzz/crashes/" -print_final_stats=1 >"$fuzz/fuzz.log" 2>&1 || status=$?

grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::|^fuzz_edge: ' "$fuzz/fuzz.log" || true
if ((status != 0)); then
  tail -n 60 "$fuzz/fuzz.log"
  input=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$fuzz/fuzz.log" | tail -n 1)
  echo "fuzz.sh: the fuzzer failed (exit status $status)"
  [[ -n $input ]] && echo "fuzz.sh: reproducer: $input (run: $fuzz/fuzz_edge $input)"
  exit 1
fi
mutations=$(sed -n 's/^fuzz_edge: custom mutator: .* \([0-9][0-9]*\) size-field mutations.*/\1/p' "$fuzz/fuzz.log")
if [[ -z $mutations || $mutations -eq 0 ]]; then
  echo "fuzz.sh: the custom mutator set no size field" >&2
  exit 1
fi
echo "fuzz.sh: no crash, leak or UBSan report in $seconds s; corpus: $fuzz/corpus ($(ls "$fuzz/corpus" | wc -l) inputs)"
