#!/usr/bin/env bash
# What earlier releases wrote, read by this build (CHANGELOG.md, tests/compat/record.sh): for each corpus of
# tests/data/compat/, copied first (the corpus itself is never written to):
#   - every run's log replays, equal to the record, to the weights checksum its experiment kept;
#   - every extrinsic test's log is explained;
#   - the experiment folder reports and plots, and afford.load reads it; afford.read_log reads every log;
#   - the experiment cut short resumes and finishes, its finished run kept as it was;
#   - the study reports.
#   tests/compat/read.sh BUILD_DIR WORK_DIR [VERSION...]   (default: every corpus)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:?usage: read.sh BUILD_DIR WORK_DIR [VERSION...]}" && pwd)
mkdir -p "${2:?usage: read.sh BUILD_DIR WORK_DIR [VERSION...]}"
work=$(cd "$2" && pwd)
shift 2
afford=$build/bin/afford
export PYTHONPATH=$build/python AFFORD_BIN=$build/bin
versions=("$@")
if [[ ${#versions[@]} -eq 0 ]]; then
  for d in "$root"/tests/data/compat/*/; do versions+=("$(basename "$d")"); done
fi
[[ ${#versions[@]} -gt 0 ]] || { echo "read.sh: no corpus in $root/tests/data/compat"; exit 1; }
fail() { echo "read.sh: $version: $*" >&2; exit 1; }
kept_checksum() {  # RUN_ID: the weights checksum the experiment kept for it
  /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["outcome"]["weights_checksum"])' \
    "experiment/runs/$1.json"
}

for version in "${versions[@]}"; do
  rm -rf "${work:?}/$version"
  cp -a "$root/tests/data/compat/$version" "$work/$version"
  cd "$work/$version"
  echo "== $version ($(cat written-by)), read by $("$afford" --version 2>/dev/null || echo "a build without --version")"

  intrinsic=0 tests=0
  for log in experiment/logs/*/; do
    log=${log%/}
    id=$(basename "$log")
    [[ $id != agents ]] || continue
    [[ -f experiment/runs/$id.json ]] || fail "$log: no runs/$id.json beside it in the corpus"
    if [[ $id == *-e[0-9]* ]]; then
      "$afford" explain "$log" >"explain-$id.txt" 2>&1 || { cat "explain-$id.txt"; fail "afford explain $log failed"; }
      tests=$((tests + 1))
    else
      "$afford" replay "$log" >"replay-$id.txt" 2>&1 || { cat "replay-$id.txt"; fail "afford replay $log failed"; }
      grep -q "^replay equals the record" "replay-$id.txt" || { cat "replay-$id.txt"; fail "$log: not equal"; }
      sum=$(kept_checksum "$id")
      grep -q "^weights_checksum: $sum" "replay-$id.txt" ||
        { cat "replay-$id.txt"; fail "$log: does not replay to the kept checksum $sum"; }
      intrinsic=$((intrinsic + 1))
    fi
  done
  ((intrinsic > 0 && tests > 0)) || fail "the corpus holds $intrinsic run log(s) and $tests test log(s)"
  echo "replayed $intrinsic run log(s) to their checksums; explained $tests test log(s)"

  "$afford" report experiment --out report.md >report.txt 2>&1 || { cat report.txt; fail "afford report failed"; }
  "$afford" plot experiment >plot.txt 2>&1 || { cat plot.txt; fail "afford plot failed"; }
  /usr/bin/python3 - <<'PY' || fail "the Python package could not read the corpus"
import glob
import afford
r = afford.load("experiment")
assert len(r.runs) > 0, "no runs loaded"
for log in sorted(glob.glob("experiment/logs/*/log.00.lcm")):
    afford.read_log(log.rsplit("/", 1)[0])
print("afford.load and afford.read_log: read")
PY

  first=$(/usr/bin/python3 -c 'import glob, json; print(sorted(glob.glob("cut/runs/*.json"))[0])')
  before=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["outcome"]["weights_checksum"])' "$first")
  "$afford" experiment --resume --out cut >resume.txt 2>&1 || { cat resume.txt; fail "--resume of the cut experiment failed"; }
  grep -q '"state": "finished"' cut/experiment.json || fail "the resumed experiment is not finished"
  after=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["outcome"]["weights_checksum"])' "$first")
  [[ $before == "$after" ]] || fail "the run finished before the cut was run again ($before, now $after)"
  echo "the cut experiment resumed and finished"

  "$afford" tune --out study --report >study.txt 2>&1 || { cat study.txt; fail "the study does not report"; }
  echo "the study reports"
done
