#!/usr/bin/env bash
# scripts/main.sh, a newcomer's first command, installs and builds only what
# the main job runs: setup.sh --main's build is the processes and the front
# door, its configuration leaves out the tests, benchmarks, examples and the
# Python package (checked by configuring it in a folder of its own).
#   tests/setup/test_setup.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
rm -rf "$2" && mkdir -p "$2"
out=$(cd "$2" && pwd)

grep -q '^scripts/setup.sh --main$' "$root/scripts/main.sh" || { echo "main.sh does not set up with --main"; exit 1; }
"$root/scripts/setup.sh" --main --dry-run | tee "$out/dry-run.txt"
programs="afford afford-environment afford-eye afford-predictors afford-motivation afford-planner afford-logger"
grep -qx "would run: cmake --build build -j[0-9]* --target $programs" "$out/dry-run.txt" ||
  { echo "setup.sh --main builds more or less than the main job's programs"; exit 1; }
grep -qx "would run: \(sudo \)\?ln -sfn $root/build/bin/afford /usr/local/bin/afford" "$out/dry-run.txt" ||
  { echo "setup.sh --main does not put afford on the PATH"; exit 1; }
configure=$(sed -n 's/^would run: cmake \(-S .*\)$/\1/p' "$out/dry-run.txt")
[[ $configure == *"-DAFFORD_TESTS=OFF"* && $configure == *"-DAFFORD_EXTRAS=OFF"* ]] ||
  { echo "setup.sh --main configures with the tests or the extras: $configure"; exit 1; }

# That configuration, in a folder of its own: the main job's programs are targets, nothing else of ours is.
cd "$root"
# shellcheck disable=SC2086  # the options as setup.sh gives them
cmake ${configure/-B build/-B $out/main} >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; exit 1; }
cmake --build "$out/main" --target help >"$out/targets.txt"
for p in $programs; do grep -qx "\.\.\. $p" "$out/targets.txt" || { echo "no target $p"; exit 1; }; done
if grep -E '^\.\.\. (test_|_afford|afford_python|afford-bench|random-motivation)' "$out/targets.txt"; then
  echo "the main job's configuration has the targets above"; exit 1
fi
echo "setup.sh --main: the main job's $(wc -w <<<"$programs") programs, no tests, benchmarks, examples or Python"
