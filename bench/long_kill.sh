#!/usr/bin/env bash
# A long run on hand-started processes, one of them killed with SIGKILL past a
# step and started again with the same command (bench/long_run.py --kill).
#   bench/long_kill.sh BUILD_DIR WORK_DIR PROCESS SEED STEPS AT [SYSTEM]
# SYSTEM: IMP (the default) or GOALS (the goals agent, issue 41).
# Prints one JSON line: the step the run was at when the process was killed,
# the snapshot's step it went on from, how long it took to catch up (until
# its STATUS says a step within one of the others'), and the run's weights
# checksum.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
victim=$3 seed=$4 steps=$5 target=$6 system=${7:-IMP}
url="udpm://239.255.76.67:7994?ttl=0&recv_buf_size=2097152"
mapfile -t processes < <("$build/bin/afford" processes)
declare -A pid
start() { $(process_command "$1" "$url" "$out/logs") >>"$out/$1.log" 2>&1 & pid[$1]=$!; }
for p in "${processes[@]}"; do start "$p"; done
"$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" --state waiting \
  --seconds 30 >/dev/null || { echo "the processes did not all come up"; exit 1; }
"$build/bin/afford" experiment base --system "$system" --reps 1 --steps "$steps" --seed "$seed" --quiet \
  --extrinsic-reps 1 --scenarios scenario1 --attach "$url" --run-prefix long --stall-seconds 120 \
  --out "$out/attached" --log-root "$out/logs" >"$out/attached.txt" 2>&1 &
runner=$!
run="long-base-$system-s$seed"
# From the STATUS heartbeats: the victim's step and the furthest step of the others ("VICTIM OTHERS").
steps() {
  "$build/bin/afford" status --lcm-url "$url" --seconds 0.55 |
    awk -v p="$victim" -v r="$run" '$5 == r && $1 == p {mine = $4} $5 == r && $1 != p && $4 > max {max = $4}
      END {print mine + 0, max + 0}'
}
at=0
while ((at < target)); do
  kill -0 "$runner" 2>/dev/null || { cat "$out/attached.txt"; echo "the run ended before step $target"; exit 1; }
  read -r _ at < <(steps)
done
kill -9 "${pid[$victim]}"
wait "${pid[$victim]}" 2>/dev/null || true
start "$victim"
began=$(date +%s.%N)
# Caught up: within a step of the others (in a step's choreography a process is at most one ahead or behind).
caught=""
while kill -0 "$runner" 2>/dev/null; do
  read -r mine others < <(steps)
  if ((mine > 0 && mine + 1 >= others)); then caught=$(date +%s.%N); break; fi
done
[[ -n $caught ]] || caught=$(date +%s.%N)  # the run ended first: it caught up by then
wait "$runner" || { tail -n 20 "$out/attached.txt"; tail -n 20 "$out/$victim.log"; echo "the run with $victim killed failed"; exit 1; }
restored=$(grep -o "goes on from its snapshot of step [0-9]*" "$out/$victim.log" | tail -1 | grep -o '[0-9]*$' || echo -1)
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/attached/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
printf '{"killed_at": %d, "restored_step": %d, "catch_up_seconds": %.2f, "weights_checksum": "%s"}\n' \
  "$at" "${restored:--1}" "$(awk -v a="$began" -v b="$caught" 'BEGIN {print b - a}')" "$sum"
