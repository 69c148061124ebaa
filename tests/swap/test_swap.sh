#!/usr/bin/env bash
# A process of one's own in place of a shipped one runs as the group's
# motivation, started by scripts/procs.sh with --process, is killed with -9 at
# a random step and started again. The run must end with the weights and the
# summary of the same experiment run uninterrupted by `afford experiment
# --process`, and its log must replay to those weights.
#   tests/swap/test_swap.sh BUILD_DIR WORK_DIR [SEED|any] [random|python-imp]
# random: the example motivation (examples/random-motivation), whose weights
# must differ from the paper's IMP. python-imp: a Python port of the paper's
# IMP motivation (python/tests/motivations.py, `python3 -m afford.process`),
# whose weights must be the C++ IMP's, checksum for checksum.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
seed=${3:-any}
[[ $seed != any ]] || seed=$((1 + RANDOM % 20))
own=${4:-random}
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_LOGS=$out/logs AFFORD_GRACE=3
export AFFORD_URL="udpm://239.255.76.67:7994?ttl=0&recv_buf_size=2097152"
procs=$root/scripts/procs.sh
trap 'rc=$?; "$procs" stop own >/dev/null 2>&1 || true; ((rc == 0)) || tail -n 20 "$out/run.txt" "$out/logs/own/motivation.log" 2>/dev/null' EXIT

case $own in
  random)
    mine=$build/bin/random-motivation
    kind=(--set motivation.kind=random);;
  python-imp)
    export PYTHONPATH=$build/python
    mine="/usr/bin/python3 -m afford.process motivation $root/python/tests/motivations.py:PyPaper"
    # The port needs no memory: without one the checksum is comparable with the paper's.
    kind=(--set motivation.kind=py-paper --set predictors.memory.keep=never);;
  *) echo "unknown own motivation '$own' (random or python-imp)"; exit 2;;
esac
experiment=(base --system IMP --reps 1 --steps 3000 --seed "$seed" --quiet --extrinsic-reps 0 "${kind[@]}")
"$procs" start own --process motivation="$mine" >"$out/start.txt"
"$procs" status own --wait-for environment,eye,predictors,motivation,planner,logger --state waiting --seconds 30 |
  tee "$out/status.txt"
grep -qF "runs: $mine" "$out/status.txt" || { echo "status does not show the swapped motivation"; exit 1; }
"$procs" run own "${experiment[@]}" --out "$out/run" >"$out/run.txt" 2>&1 &
runner=$!
target=$((300 + RANDOM % 1500))
"$procs" status own --wait-for motivation --step "$target" --seconds 60 >/dev/null ||
  { echo "the motivation never reached step $target"; exit 1; }
# Stopped at once (SIGSTOP: it publishes nothing more), then killed only once it is sure the run still needs
# it: the environment, which takes every decision, has not had the last one. (The heartbeat the wait read may
# be half a second old, and a loaded machine delays what follows: a motivation killed after its last decision
# is not needed again, the run ends without it, and nothing would have been tried.)
kill -STOP "$(cat "$out/logs/own/motivation.pid")"
environment_step=$("$procs" status own | awk '$1 == "environment" && NF >= 5 && $3 != "yes" {print $4}' | tail -1)
[[ -n $environment_step && $environment_step -lt 2999 ]] ||
  { kill -CONT "$(cat "$out/logs/own/motivation.pid")"; echo "the motivation decided every step before it was stopped (the environment is at ${environment_step:-?})"; exit 1; }
kill -0 "$runner" 2>/dev/null || { echo "the run ended before the kill"; exit 1; }
"$procs" kill own motivation
"$procs" start own motivation  # the stored --process: the same command again
grep -qF "${mine##*/}" "$out/logs/own/motivation.cmd" || { echo "the restart did not start the swapped command"; exit 1; }
wait "$runner" || { echo "the run with the restarted own motivation failed"; exit 1; }
grep -q "process motivation is free again" "$out/run.txt" || { echo "the motivation did not rejoin"; exit 1; }
echo "seed $seed: killed the own motivation after step $target; $(grep -o "process motivation is free again.* at step [0-9]*" "$out/run.txt" | head -1)"

# Uninterrupted, with the runner's own group and the same swap.
"$build/bin/afford" experiment "${experiment[@]}" --process motivation="$mine" --run-prefix own \
  --out "$out/uninterrupted" --log-root "$out/uninterrupted-logs" >"$out/uninterrupted.txt" 2>&1 ||
  { cat "$out/uninterrupted.txt"; echo "afford experiment --process failed"; exit 1; }
same_results "$out/uninterrupted" "$out/run" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/run/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
grep -q "\"motivation\": \"$mine\"" "$out/uninterrupted/summary.json" || { echo "summary.json does not name the swap"; exit 1; }

# The paper's IMP makes other decisions: the swap was in effect.
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 3000 --seed "$seed" --quiet --extrinsic-reps 0 \
  --transport memq --keep-logs none --out "$out/paper" --log-root "$out/paper-logs" >/dev/null 2>&1
paper=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/paper/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
if [[ $own == random ]]; then
  [[ $paper != "$sum" ]] || { echo "the run with the own motivation gave the paper's IMP weights"; exit 1; }
else
  [[ $paper == "$sum" ]] || { echo "the port of IMP gave $sum, the C++ IMP $paper"; exit 1; }
fi

"$build/bin/afford" replay "$out/logs/own-base-IMP-s$seed" | tee "$out/replay.txt"
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the log replays differently"; exit 1; }
grep -q "decider not replayed: motivation.kind '${kind[1]#motivation.kind=}'" "$out/replay.txt" || { echo "replay does not say why"; exit 1; }
echo "weights_checksum $sum: equal to the uninterrupted run's and to the replay's (the paper's IMP: $paper)"
