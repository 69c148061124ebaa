#!/usr/bin/env bash
# scripts/procs.sh status says what is wrong: during a run it shows the
# runner (its pid, its run, what it waits for) and the planner idle in an
# intrinsic run; a paused (SIGSTOP) eye is shown paused and silent on the bus,
# and the runner names it; a paused logger at the run's end is what the
# runner waits for. Each continued, the run ends well.
#   tests/procs/status_silent.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
source "$root/tests/procs/group.sh"
procs_group 7753

"$procs" start demo >"$out/start.txt" || { cat "$out/start.txt"; exit 1; }
"$procs" run demo base --system FIX --reps 1 --steps 2000 --seed 2 --quiet --run-prefix st --out "$out/run" \
  >"$out/run.txt" 2>&1 &
runner=$!
"$procs" status demo --wait-for eye --step 100 --seconds 60 >/dev/null || { cat "$out/run.txt"; echo "the run did not start"; exit 1; }

# The eye paused: the run waits for it.
eye=$(cat "$logs/demo/eye.pid")
kill -STOP "$eye"
# says NAME WHAT REGEX: a status says it, within a few listens (the runner's beat comes every 0.5 s).
says() {
  local file=$out/status-$1.txt re=$3
  wait_until 15 eval '"$procs" status demo >"$file" 2>&1 && grep -Eq "$re" "$file"' ||
    { cat "$file"; echo "procs.sh status does not show $2"; exit 1; }
}
says paused "the eye paused" "^eye +$eye  paused \(SIGSTOP"
grep -Eq "^eye +$eye  silent +- +- +not heard in [0-9.]+ s" "$out/status-paused.txt" ||
  { cat "$out/status-paused.txt"; echo "procs.sh status does not mark the paused eye silent"; exit 1; }
grep -Eq "^planner +[0-9]+  running +-1  st-base-FIX-s2 +idle in this run: its intrinsic phase needs no planner$" \
  "$out/status-paused.txt" || { cat "$out/status-paused.txt"; echo "the planner is not said idle in the run"; exit 1; }
grep -Eq "^runner +[0-9]+  running +[0-9]+  st-base-FIX-s2 +runs" "$out/status-paused.txt" ||
  { cat "$out/status-paused.txt"; echo "the runner is not shown with its run"; exit 1; }
says runner-eye "the runner naming the silent eye" "^runner .*silent: eye \(not heard for [0-9.]+ s\)"
kill -CONT "$eye"

# The logger paused before the run's end: the runner waits for it (its log to hold the run, then to close it).
logger=$(cat "$logs/demo/logger.pid")
kill -STOP "$logger"
says logger "the runner waiting for the logger" "^runner .*waits for the logger"
kill -CONT "$logger"
wait "$runner" || { cat "$out/run.txt"; echo "the run failed"; exit 1; }
[[ -f $logs/st-base-FIX-s2/log.00.lcm ]] || { echo "no log of the run"; exit 1; }
echo "procs.sh status shows the runner and what it waits for, a paused process, and an idle one"
