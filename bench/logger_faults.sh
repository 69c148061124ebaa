#!/usr/bin/env bash
# The logger's faults around a run's end, N times: each time a random fault
# (killed and started again after the run's last step, paused past
# close_timeout_ms, killed and started again 6 s later, paused 20 s), a random
# step and a random seed, on hand-started processes
# (tests/restart/test_logger_faults.sh). Counts the
# runs that completed, whose log replays to their weights, and whose weights
# are an undisturbed run's of the same seed.
#   bench/logger_faults.sh BUILD_DIR WORK_DIR [N] [FAULT...]
# One JSON line per run in WORK_DIR/runs.jsonl, then the counts per fault.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "$1" && pwd)
mkdir -p "$2"
out=$(cd "$2" && pwd)
n=${3:-30}
shift $(($# < 3 ? $# : 3))
faults=("$@")
((${#faults[@]})) || faults=(kill-late pause kill-6s pause-20s)
: >"$out/runs.jsonl"
for i in $(seq "$n"); do
  fault=${faults[RANDOM % ${#faults[@]}]}
  seed=$((1 + RANDOM % 1000))
  began=$SECONDS
  AFFORD_LOGGER_FAULTS_BENCH=1 bash "$root/tests/restart/test_logger_faults.sh" "$build" "$out/run-$i" "$fault" \
    "$seed" >"$out/run-$i.txt" 2>&1
  rc=$?
  line=$(grep '^{' "$out/run-$i.txt" | tail -1)
  # Exit 3: the run ended before the fault could be placed (not a run with a fault).
  [[ -n $line ]] || line=$(printf '{"fault": "%s", "seed": %d, "placed": %s, "completed": false, "why": "%s"}' \
    "$fault" "$seed" "$( ((rc == 3)) && echo false || echo true)" \
    "$(grep -v '^---' "$out/run-$i.txt" | grep -m1 -E 'error|failed|ended before|never' | tr -d '"\\')")
  echo "${line%\}}, \"seconds\": $((SECONDS - began))}" | tee -a "$out/runs.jsonl"
done
/usr/bin/python3 - "$out/runs.jsonl" <<'EOF'
import json, sys, collections
runs = [json.loads(l) for l in open(sys.argv[1])]
by = collections.defaultdict(list)
unplaced = collections.Counter()
for r in runs:
    if r.get("placed", True):
        by[r["fault"]].append(r)
    else:
        unplaced[r["fault"]] += 1
for fault, rs in sorted(by.items()):
    ok = [r for r in rs if r.get("completed") and r.get("replays") and r["weights_checksum"] == r["undisturbed"]]
    steps = sorted(r["step"] for r in rs if "step" in r)
    span = f", faults at steps {steps[0]}..{steps[-1]}" if steps else ""
    print(f"{fault}: {len(ok)} of {len(rs)} completed, replayed and equal the undisturbed run{span}, "
          f"{sum(r['seconds'] for r in rs) / len(rs):.1f} s a run on average")
for fault, n in sorted(unplaced.items()):
    print(f"{fault}: {n} more run(s) ended before the fault could be placed (not counted)")
EOF
