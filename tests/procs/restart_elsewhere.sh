#!/usr/bin/env bash
# A scripts/procs.sh group's process killed and started again from another
# working folder, at random steps of a run: each run's weights must equal an
# undisturbed run's. A stress script (not part of ctest): N runs (default 10),
# one after another on the same group, each with one process (at random among
# those of the intrinsic run) killed at a random step past the run's first
# snapshot and started from a folder of its own; a table of what happened:
# the step it was killed past (the furthest process's, from the heartbeats),
# the step at which the runner saw it again, the snapshot it went on from.
#   tests/procs/restart_elsewhere.sh BUILD_DIR WORK_DIR [N] [SEED]
# Exit 1 if a run fails or its weights differ.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
n=${3:-10}
RANDOM=${4:-$$}
steps=3000 snapshot=500
mkdir -p "$out/checkout/scripts" "$out/w0"
ln -s "$root/scripts/procs.sh" "$out/checkout/scripts/procs.sh"  # a checkout's layout: its logs/, no $AFFORD_LOGS
unset AFFORD_LOGS
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_GRACE=3
procs=$out/checkout/scripts/procs.sh logs=$out/checkout/logs
# The group's processes are procs.sh's: whatever happens, they end with this script.
trap 'kill $(jobs -p) 2>/dev/null || true; "$procs" kill demo environment eye predictors motivation planner logger >/dev/null 2>&1 || true' EXIT
victims=(environment eye predictors motivation logger)
experiment=(base --system IMP --reps 1 --steps "$steps" --seed 4 --set "protocol.recovery.snapshot_steps=$snapshot"
  --no-reuse-agents)
checksum() { grep -o '"weights_checksum": "[0-9a-f]*"' "$1/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}'; }

"$build/bin/afford" experiment "${experiment[@]}" --transport memq --keep-logs none --quiet --out "$out/undisturbed" \
  --log-root "$out/undisturbed-logs" >"$out/undisturbed.txt" 2>&1
want=$(checksum "$out/undisturbed")
(cd "$out/w0" && "$procs" start demo >/dev/null)
"$procs" status demo --wait-for environment,eye,predictors,motivation,planner,logger --state waiting --seconds 30 >/dev/null

printf '%-4s %-12s %6s %8s %10s  %-10s %-16s %s\n' run process killed rejoined snapshot from weights same
bad=0
for k in $(seq "$n"); do
  p=${victims[RANDOM % ${#victims[@]}]}
  aim=$((snapshot + 100 + RANDOM % (steps - snapshot - 400)))
  from=$out/w$k
  mkdir -p "$from"
  (cd "$out/w0" && "$procs" run demo "${experiment[@]}" --quiet --run-prefix "t$k" --out "$out/run$k" \
    >"$out/run$k.txt" 2>&1) &
  runner=$!
  # The run's step: the furthest process's (their heartbeats), once the victim takes part in the run.
  at=
  "$procs" status demo --wait-for "$p" --step "$aim" --seconds 120 >/dev/null && at=$aim
  "$procs" kill demo "$p" >/dev/null
  (cd "$from" && "$procs" start demo "$p" >/dev/null)
  rc=0
  wait "$runner" || rc=$?
  killed=$(grep -o "process $p is free again.* at step [0-9]*" "$out/run$k.txt" | head -1 | grep -o '[0-9]*$' || true)
  went=$(grep -o "goes on from its snapshot of step [0-9]*" "$logs/demo/$p.log" | tail -1 | grep -o '[0-9]*$' || true)
  got=$( ((rc == 0)) && checksum "$out/run$k" || echo "failed")
  same=no
  [[ $got == "$want" ]] && same=yes
  [[ $same == yes && -n $at ]] || bad=$((bad + 1))
  printf '%-4s %-12s %6s %8s %10s  %-10s %-16s %s\n' "$k" "$p" "$aim" "${killed:-?}" "${went:-none}" "w$k" "$got" "$same"
  [[ $same == yes ]] || { tail -5 "$out/run$k.txt"; grep -h "error" "$logs/demo/$p.log" | tail -3; }
done
"$procs" stop demo >/dev/null
left=$(ls -d "$out"/w*/logs 2>/dev/null || true)
[[ -z $left ]] && under=no || { under=yes; echo "written under a working folder: $left"; }
echo "undisturbed weights $want; $((n - bad)) of $n runs with a process restarted from another folder equal to it"
((bad == 0)) && [[ $under == no ]]
