#!/usr/bin/env bash
# What earlier releases wrote, read by this build (CHANGELOG.md, tests/compat/record.sh): for each corpus of
# tests/data/compat/, copied first (the corpus itself is never written to):
#   - every run's log replays, equal to the record, to the weights checksum its experiment kept;
#   - every extrinsic test's log is explained;
#   - the experiment folder reports and plots, and afford.load reads it; afford.read_log reads every log;
#   - the experiment cut short resumes and finishes, its finished run kept as it was;
#   - the study reports;
#   - every message type whose fingerprint changed since (types.txt) has its earlier form kept in
#     lcmtypes/compat/VERSION/ (docs/releases.md, "Message types across releases");
#   - the components written against it (components/: C++ built unchanged by tests/CMakeLists.txt as
#     compat-VERSION-NAME, Python as they are) run as the motivation of a run on the bus; the Python port of
#     the paper's IMP gives the weights of the shipped one.
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

  if [[ -f types.txt ]]; then
    "$build/bin/afford-type-fingerprints" >types-now.txt
    while read -r type then; do
      [[ $type != \#* ]] || continue
      now=$(awk -v t="$type" '$1 == t { print $2 }' types-now.txt)
      [[ $now == "$then" || -f $root/lcmtypes/compat/$version/$type.lcm ]] ||
        fail "message type $type changed since $version (fingerprint $then, now ${now:-gone}): its logs would read as foreign messages; keep $version's $type in lcmtypes/compat/$version/ and read it there (docs/releases.md)"
    done <types.txt
    echo "its message types: each as it was, or its earlier form kept"
  fi

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

  if [[ -d components ]]; then
    export AFFORD_NETNS=none  # (the bus: 239.255.76.67 from --base-port on, ttl=0: it stays on this machine)
    run_own() {  # NAME KIND COMMAND [EXTRA...]: a run with the component as its motivation
      local name=$1 kind=$2 command=$3
      shift 3
      "$afford" experiment base --system IMP --reps 1 --steps 300 --seed 4 --extrinsic-reps 0 --quiet \
        --transport udpm --base-port 7620 --keep-logs none --set motivation.kind="$kind" "$@" \
        --process motivation="$command" --out "own-$name" --log-root "own-$name-logs" >"own-$name.txt" 2>&1 ||
        { cat "own-$name.txt"; fail "a run with the component $name as its motivation failed"; }
    }
    checksum_of() { grep -o '"weights_checksum": "[0-9a-f]*"' "$1/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}'; }
    for src in components/*.cpp; do
      [[ -e $src ]] || continue
      name=$(basename "$src" .cpp)
      exe=$build/bin/compat-$version-${name//_/-}
      [[ -x $exe ]] || fail "$src was not built (expected $exe)"
      run_own "$name" random "$exe"
    done
    if [[ -f components/motivations.py ]]; then
      run_own py-paper py-paper "/usr/bin/python3 -m afford.process motivation $PWD/components/motivations.py:PyPaper" \
        --set predictors.memory.keep=never
      "$afford" experiment base --system IMP --reps 1 --steps 300 --seed 4 --extrinsic-reps 0 --quiet \
        --transport memq --keep-logs none --set predictors.memory.keep=never --out paper --log-root paper-logs \
        >paper.txt 2>&1 || { cat paper.txt; fail "the shipped IMP's run failed"; }
      own=$(checksum_of own-py-paper) paper=$(checksum_of paper)
      [[ -n $own && $own == "$paper" ]] ||
        fail "the Python IMP written against $version gave other weights ($own) than the shipped one ($paper)"
    fi
    echo "its components ran as the motivation: $(ls components | tr '\n' ' ')"
  fi
done
