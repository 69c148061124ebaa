#!/usr/bin/env bash
# Records a release's compatibility corpus: what that release writes, kept under tests/data/compat/VERSION/ for
# every later build to read (tests/compat/read.sh, ctest Compat.*). Run it once per release, with a build of the
# release's own commit (docs/releases.md, "Making a release"), never with a later build.
#   tests/compat/record.sh BUILD_DIR VERSION
# It writes, each small and fast to make (memq: one process, no network):
#   experiment/  an IMP and a GOALS agent trained 200 steps and tested in scenario2 (summary.json, runs/,
#                CSV files, experiment.json), its logs/ (every run's LCM log and manifest) and the agents'
#                checkpoints and stored agents
#   cut/         an experiment of two runs stopped by SIGINT once its first run finished: --resume continues it
#   study/       a study of two trials (afford tune), its journal and report
#   components/  the components written against it, as its source tree has them: the example motivation
#                (C++, built unchanged by later builds) and the Python motivations of its tests
#   types.txt    the LCM fingerprint of each message type (what its logs hold at the head of each message)
#   written-by   the version and commit that wrote it all
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:?usage: record.sh BUILD_DIR VERSION}" && pwd)
version=${2:?usage: record.sh BUILD_DIR VERSION}
afford=$build/bin/afford
out=$root/tests/data/compat/$version
[[ ! -e $out ]] || { echo "record.sh: $out exists: a release's corpus is recorded once" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"  # every path below is relative: the corpus reads the same wherever the repository is

common=(--transport memq --reps 1 --seed 3 --extrinsic-reps 1 --scenarios scenario2 --quiet)
"$afford" experiment base --system IMP,GOALS --steps 200 "${common[@]}" --keep-logs all \
  --keep-checkpoints all --run-prefix compat --out experiment --log-root experiment/logs >experiment.txt 2>&1 ||
  { cat experiment.txt; exit 1; }

# The build's version, as it writes it (0.1.0's afford has no --version).
made=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["afford_version"])' \
  experiment/summary.json)
[[ $made == "$version+"* ]] || { echo "record.sh: $afford is $made, not $version" >&2; exit 2; }
[[ $made != *dirty* ]] || { echo "record.sh: $afford was built with uncommitted changes ($made)" >&2; exit 2; }

# Cut: SIGINT once the first of its two runs is done (the second is then under way, or not begun).
"$afford" experiment base --system IMP --reps 2 --steps 1500 --transport memq --seed 5 --extrinsic-reps 0 \
  --progress lines --keep-logs none --keep-checkpoints none --run-prefix cut --out cut --log-root cut/logs >cut.txt 2>&1 &
runner=$!
# (tail follows the output as it is written, and ends with the runner: no polling)
tail --pid="$runner" -n +1 -f cut.txt | grep -q -m 1 "\[1/2\] .* done" || true
kill -INT "$runner" 2>/dev/null || true
wait "$runner" && { cat cut.txt; echo "record.sh: the experiment to cut ended before the signal" >&2; exit 1; }
grep -q -- "--resume" cut.txt || { cat cut.txt; echo "record.sh: the cut experiment names no resume" >&2; exit 1; }

PYTHONPATH=$build/python AFFORD_BIN=$build/bin "$afford" tune base --out study --trials 2 --system IMP --reps 1 \
  --steps 200 --extrinsic-reps 0 --param motivation.leak=float:0.05:0.3 --keep-logs none >study.txt 2>&1 &&
  PYTHONPATH=$build/python AFFORD_BIN=$build/bin "$afford" tune --out study --report >>study.txt 2>&1 ||
  { cat study.txt; exit 1; }

printf '%s\n' "$made" >written-by
{ echo "# the LCM fingerprint of each message type of $version, by afford-type-fingerprints of $made"
  "$build/bin/afford-type-fingerprints"; } >types.txt
mkdir -p "$out"
cp -a experiment cut study written-by types.txt "$out/"
mkdir -p "$out/components"
cp "$root"/examples/random-motivation/*.cpp "$root/python/tests/motivations.py" "$out/components/"
echo "record.sh: the corpus of $version ($made) is in $out: $(du -sh "$out" | cut -f1)"
