#!/usr/bin/env bash
# Live restart: during a run on hand-started processes, `kill -9` one of them
# at a random moment and start it again with the same command. The run must
# complete with the same final weights and the same summary as an
# uninterrupted run, and its log (the segments together) must replay to them.
#   tests/restart/test_restart.sh BUILD_DIR WORK_DIR PROCESS[,PROCESS...] [SEED]
# AFFORD_KILL_STEP=N kills at step N (at least) instead of a random step; for the
# planner AFFORD_KILL_DELAY_MS=N kills at N ms into its second test.
# PROCESS: environment, eye, predictors, motivation, logger (killed during the
# intrinsic run) or planner (killed during the extrinsic tests). Several, comma-separated, are killed one after
# another in a random order during one longer intrinsic run (the planner among them with GOALS only), each once
# the one before has rejoined the run and caught up: one run checks them all.
# AFFORD_RESTART_SYSTEM=GOALS runs the goals agent instead of IMP: every process,
# the planner too, is killed during its intrinsic run, in the middle of a goal
# (the step is random; a goal lasts up to goals.budget steps).
# AFFORD_RESTART_EXPERIMENT=table runs the physical table (world.kind: table) instead of the paper's world, IMP, no
# extrinsic test: the environment spends most of a step in a motor primitive's physics, so it is killed mid-primitive.
# AFFORD_RESTART_PREDICTORS="python3 -m afford.process predictors FILE:CLASS" with
# AFFORD_RESTART_KIND=KIND: the predictors are that affordance predictor written in
# Python (intrinsic run only); the uninterrupted run starts the same command over
# udpm, and the log is replayed in Python (afford.replay with the class).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
IFS=, read -r -a victims <<<"$3"
seed=${4:-$((1 + RANDOM % 20))}
# On failure, what the runner and the processes said, so a CI log shows why.
diagnose() {
  local rc=$?
  kill $(jobs -p) 2>/dev/null || true
  ((rc == 0)) || show_why "seed $seed, ${victims[*]}" "$(cat "$out/kill.txt" 2>/dev/null)"
}
trap diagnose EXIT

url="udpm://239.255.76.67:7993?ttl=0&recv_buf_size=2097152"
system=${AFFORD_RESTART_SYSTEM:-IMP}
steps=3000
snapshot=500
# The goals agent steps four to five times slower, and so does an affordance predictor in Python: a shorter run,
# snapshots as often in steps.
[[ $system == GOALS || -n ${AFFORD_RESTART_PREDICTORS:-} ]] && { steps=1500; snapshot=300; }
# Several in turn: a run long enough for each to be killed, come back and catch up before the next (the STATUS
# read every 0.55 s overshoots; catching up takes a second or two): IMP goes about 1000 steps a second here,
# the goals agent about 200.
cycle=1500
[[ $system == GOALS ]] && cycle=300
world=${AFFORD_RESTART_EXPERIMENT:-base}
# The table world steps about 40 times a second: a short run, snapshots every 50 steps, the first kill after
# the first snapshot.
from=200  # the first kill's earliest step; each later one's is after the one before has caught up
[[ $world == table ]] && { steps=150; snapshot=50; cycle=100; from=60; }
((${#victims[@]} > 1)) && steps=$((steps + cycle * ${#victims[@]}))
victim=${victims[0]}
if ((${#victims[@]} > 1)); then
  for v in "${victims[@]}"; do
    [[ $v != planner || $system == GOALS ]] || { echo "the planner is killed alone (in an extrinsic test)"; exit 1; }
  done
  mapfile -t victims < <(printf '%s\n' "${victims[@]}" | shuf --random-source=<(yes "$seed"))
fi
mapfile -t processes < <("$build/bin/afford" processes)  # the registry's
declare -A pid
own=${AFFORD_RESTART_PREDICTORS:-}
command_of() {  # PROCESS URL ROOT
  if [[ $1 == predictors && -n $own ]]; then echo "$own --lcm-url $2 --checkpoint-dir $3 --state-dir $3"
  else process_command "$@"; fi
}
start() { $(command_of "$1" "$url" "$out/logs") >>"$out/$1.log" 2>&1 & pid[$1]=$!; }
for p in "${processes[@]}"; do start "$p"; done
"$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" --state waiting \
  --seconds 30 >/dev/null || { echo "the processes did not all come up"; exit 1; }

# A snapshot every $snapshot steps: a kill before the first restarts from the run's start, a later one from a snapshot.
experiment=(experiment "$world" --system "$system" --reps 1 --steps "$steps" --seed "$seed" --quiet
  --set protocol.recovery.snapshot_steps="$snapshot")
extrinsic=(--extrinsic-reps 3 --scenarios scenario1 --scenarios scenario2)
# The table's truth from 4 trials a cell (its runs are measured against it; estimated in each log root).
[[ $world == table ]] && { experiment+=(--set table.truth.trials=4); extrinsic=(); }
[[ -n $own ]] && { experiment+=(--set "predictors.affordance.kind=$AFFORD_RESTART_KIND"); extrinsic=(--extrinsic-reps 0); }
# The planner's tests run their whole budget (no scene is close enough to end
# one early), so there is time to kill it in the middle of one.
[[ $victim == planner && $system == IMP ]] &&
  extrinsic+=(--set planner.success_distance=0 --set planner.budget=1500 --set planner.max_attempts=1500)
echo "seed $seed, $system, killing $victim"
"$build/bin/afford" "${experiment[@]}" "${extrinsic[@]}" --attach "$url" --run-prefix restart \
  --out "$out/attached" --log-root "$out/logs" >"$out/attached.txt" 2>&1 &
runner=$!

# The moment: in the middle of the victim's work. The planner: a random time
# into the second test. The others: a random step of the intrinsic run, read
# from the STATUS heartbeats (a time would land after the run on a fast
# machine, or between runs on a slow one).
run_id="restart-$world-$system-s$seed"
# step_of PROCESS: the run's step (the furthest process's), printed once PROCESS is in the run ("" before).
step_of() {
  "$build/bin/afford" status --lcm-url "$url" --seconds 0.55 |
    awk -v p="$1" -v r="$run_id" '$5 == r && $4 > max {max = $4}
      $1 == p && ($3 == "running" || $3 == "done") && $5 == r {in_run = 1; mine = $4} END {if (in_run) print max + 0, mine + 0}'
}
: >"$out/kill.txt"
for victim in "${victims[@]}"; do
  if [[ $victim == planner && $system == IMP ]]; then
    wait_until 60 grep -q "configured for run '.*-e1'" "$out/planner.log" ||
      { cat "$out/attached.txt"; echo "the planner never took the second test"; exit 1; }
    delay=${AFFORD_KILL_DELAY_MS:-$((20 + RANDOM % 200))}
    sleep "$(printf '%d.%03d' $((delay / 1000)) $((delay % 1000)))"
    moment="${delay} ms into its second test"
  else
    # heartbeats come every 0.5 s, so it overshoots
    spread=$((steps / 3))
    ((${#victims[@]} == 1)) || spread=$((cycle / 4))
    target=${AFFORD_KILL_STEP:-$((from + RANDOM % spread))}
    at=-1
    for _ in $(seq 200); do
      read -r at _ < <(step_of "$victim") || at=
      [[ -n $at ]] && ((at >= target)) && break
      kill -0 "$runner" 2>/dev/null || break
    done
    moment="at step ${at:-?} of the intrinsic run (aimed at $target)"
  fi
  kill -0 "$runner" 2>/dev/null || { cat "$out/attached.txt"; echo "the run ended before the kill of $victim"; exit 1; }
  kill -9 "${pid[$victim]}"
  wait "${pid[$victim]}" 2>/dev/null || true
  echo "killed $victim $moment" | tee -a "$out/kill.txt"
  start "$victim"  # at once: the process is gone (waited for above), and its peers must cope with a quick return
  ((${#victims[@]} > 1)) || break
  # Back in the run and caught up (its own step where the run was at the kill) before the next is killed.
  mine=-1
  for _ in $(seq 120); do
    read -r now mine < <(step_of "$victim") || mine=
    [[ -n $mine ]] && ((mine >= at)) && break
    kill -0 "$runner" 2>/dev/null || break
  done
  kill -0 "$runner" 2>/dev/null || { cat "$out/attached.txt"; echo "the run ended before $victim caught up"; exit 1; }
  [[ -n $mine ]] && ((mine >= at)) || { cat "$out/attached.txt"; echo "$victim did not catch up with the run"; exit 1; }
  echo "  $victim caught up at step $mine (the run at step $now)"
  from=$((now + 50))
done
wait "$runner" || { cat "$out/attached.txt"; echo "the run with a restarted ${victims[*]} failed"; exit 1; }
grep -q "free again" "$out/attached.txt" || { cat "$out/attached.txt"; echo "the runner never re-sent the run"; exit 1; }
for victim in "${victims[@]}"; do
  ((${#victims[@]} == 1)) || grep -q "process $victim is free again" "$out/attached.txt" ||
    { cat "$out/attached.txt"; echo "the runner never re-sent the run to $victim"; exit 1; }
  grep -o "process $victim is free again.* at step [0-9]*" "$out/attached.txt" | head -1
  grep -o "goes on from its snapshot of step [0-9]*" "$out/$victim.log" | tail -1 || echo "($victim took the run from its start)"
done

# The same experiment uninterrupted, hosted by the runner in one process.
# Its own log root: the checkpoint goes there, and the same seed may be run by
# another test case at the same time.
if [[ -n $own ]]; then  # a component in Python: its own process over udpm (the runner starts them all)
  "$build/bin/afford" "${experiment[@]}" "${extrinsic[@]}" --netns off --base-port 7300 --process "predictors=$own" \
    --keep-logs none --run-prefix restart --out "$out/uninterrupted" --log-root "$out/uninterrupted-logs" \
    >"$out/uninterrupted.txt" 2>&1
else
  "$build/bin/afford" "${experiment[@]}" "${extrinsic[@]}" --transport memq --keep-logs none --run-prefix restart \
    --out "$out/uninterrupted" --log-root "$out/uninterrupted-logs" >"$out/uninterrupted.txt" 2>&1
fi

# The runs over, no snapshot stays (each process removes its own on STOP; the runner what a process left).
left=$(find "$out/logs" "$out/uninterrupted-logs" -name '*.snapshot*' | head -3)
[[ -z $left ]] || { echo "snapshots left after the runs: $left"; exit 1; }

# Summaries and CSV files equal, but for what the wall clock, the host or the paths decide.
same_results "$out/uninterrupted" "$out/attached" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/attached/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum, equal to the uninterrupted run's; summary and CSV files equal"

# The intrinsic run's log, all its segments, replays to the same weights.
log=$(ls -d "$out"/logs/restart-"$world"-"$system"-s"$seed")
if [[ -n $own ]]; then  # replayed in Python, with the class (afford replay cannot rebuild it)
  target=${own##* }
  /usr/bin/python3 -c "import sys, afford; from afford.process import load_class
r = afford.replay(sys.argv[1], affordance=load_class(sys.argv[2]))
print('weights_checksum:', r['weights_checksum']); sys.exit(0 if r['ok'] else 1)" "$log" "$target" | tee "$out/replay.txt"
else
  "$build/bin/afford" replay "$log" | tee "$out/replay.txt"
fi
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the log replays differently"; exit 1; }
if [[ " ${victims[*]} " == *" logger "* ]]; then
  [[ -f $log/log.01.lcm ]] || { echo "the restarted logger wrote no second segment"; exit 1; }
  echo "the restarted logger continued the log in $(ls "$log" | grep -c 'log\..*\.lcm') segments"
fi
