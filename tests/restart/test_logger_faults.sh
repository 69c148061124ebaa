#!/usr/bin/env bash
# The logger's faults around a run's end, on hand-started processes: the run
# must complete, its log replay to its weights, its extrinsic test run, and
# the logger be free afterwards.
#   tests/restart/test_logger_faults.sh BUILD_DIR WORK_DIR FAULT [SEED]
# FAULT (at a random step past the first third of the intrinsic run):
#   kill-late   kill -9, started again only once the other processes have
#               handled the run's last step
#   pause       SIGSTOP, continued (SIGCONT) once the others have handled the
#               last step and the run's close_timeout_ms (2 s here) has passed
#   kill-6s     kill -9, started again 6 s later (the shipped timeouts)
#   pause-20s   SIGSTOP for 20 s (the shipped timeouts)
# AFFORD_LOGGER_FAULTS_BENCH=1 adds the run of the same seed on an undisturbed
# group (memq) and prints one JSON line (bench/logger_faults.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
fault=$3
seed=${4:-$((1 + RANDOM % 20))}
diagnose() {
  local rc=$?
  kill -CONT "${pid[logger]:-0}" 2>/dev/null || true
  kill $(jobs -p) 2>/dev/null || true
  ((rc == 0)) || show_why "seed $seed, $fault" "$(cat "$out/fault.txt" 2>/dev/null)"
}
declare -A pid
trap diagnose EXIT

url="udpm://239.255.76.67:7995?ttl=0&recv_buf_size=2097152"
steps=3000
mapfile -t processes < <("$build/bin/afford" processes)
others=$(printf '%s\n' "${processes[@]}" | grep -v -x -e logger -e planner | paste -sd,)
start() { $(process_command "$1" "$url" "$out/logs") >>"$out/$1.log" 2>&1 & pid[$1]=$!; }
for p in "${processes[@]}"; do start "$p"; done
"$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" --state waiting \
  --seconds 30 >/dev/null || { echo "the processes did not all come up"; exit 1; }

experiment=(experiment base --system IMP --reps 1 --steps "$steps" --seed "$seed" --quiet --scenarios scenario1
  --extrinsic-reps 1)
# A close_timeout_ms of 2 s (stop_grace_ms below it): the pause passes it.
[[ $fault == kill-late || $fault == pause ]] &&
  experiment+=(--set protocol.close_timeout_ms=2000 --set protocol.stop_grace_ms=1000)
run="faults-base-IMP-s$seed"
echo "seed $seed, logger: $fault"
"$build/bin/afford" "${experiment[@]}" --attach "$url" --run-prefix faults --out "$out/attached" \
  --log-root "$out/logs" >"$out/attached.txt" 2>&1 &
runner=$!

# The fault's step: a random one of the run, read from the size of the logger's log as it grows (about 3.4 KB
# a step): the heartbeats, 0.5 s apart, would miss most of a run that takes 2 s. kill-late and pause last past
# the run's last step whatever the step.
target=${AFFORD_KILL_STEP:-$((100 + RANDOM % (steps * 2 / 3)))}
log=$out/logs/$run
bytes() { stat -c %s "$log/log.00.lcm" 2>/dev/null || echo 0; }
ended() { grep -qs '"complete": true' "$log/manifest.json" || ! kill -0 "$runner" 2>/dev/null; }
reached() { (($(bytes) >= target * 3400)) || ended; }
wait_until 120 reached || { cat "$out/attached.txt"; echo "the logger's log never grew"; exit 1; }
# (Exit 3: no fault was placed, which bench/logger_faults.sh counts apart.)
ended && { cat "$out/attached.txt"; echo "the run ended before the fault"; exit 3; }
at=$(($(bytes) / 3400))
case $fault in
  kill-late | kill-6s) kill -9 "${pid[logger]}"; wait "${pid[logger]}" 2>/dev/null || true ;;
  pause | pause-20s) kill -STOP "${pid[logger]}" ;;
  *) echo "unknown fault '$fault'"; exit 2 ;;
esac
# The others have handled the run's last step (or, the run stopped without the logger, are free again).
past_the_end() {
  "$build/bin/afford" status --lcm-url "$url" --seconds 0.55 |
    awk -v r="$run" -v last=$((steps - 1)) -v want="$others" 'BEGIN {n = split(want, w, ",")}
      ($5 == r && $4 >= last) || $3 == "waiting" {done[$1] = 1}
      END {for (i = 1; i <= n; i++) if (!done[w[i]]) exit 1}'
}
case $fault in
  kill-late) wait_until 60 past_the_end || { cat "$out/attached.txt"; echo "the run never ended"; exit 1; }; start logger ;;
  pause) wait_until 60 past_the_end || { cat "$out/attached.txt"; echo "the run never ended"; exit 1; }
    read -r -t 3 <> <(:) || true  # the pause itself: past close_timeout_ms
    kill -CONT "${pid[logger]}" ;;
  kill-6s) read -r -t 6 <> <(:) || true; start logger ;;
  pause-20s) read -r -t 20 <> <(:) || true; kill -CONT "${pid[logger]}" ;;
esac
echo "logger: $fault at about step $at of the intrinsic run (its log then $((at * 34 / 10)) KB; aimed at $target)" |
  tee "$out/fault.txt"
wait "$runner" || { cat "$out/attached.txt"; echo "the run failed"; exit 1; }

# Its test ran: the summary holds the intrinsic run's weights, and the extrinsic test of its agent is in.
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/attached/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}' || true)
[[ -n $sum ]] || { cat "$out/attached.txt"; echo "no intrinsic run in the summary"; exit 1; }
grep -q "^IMP,$run,[0-9]*,scenario1," "$out/attached/extrinsic_IMP.csv" || { echo "the extrinsic test did not run"; exit 1; }
# The log, all its segments, replays to the run's weights.
"$build/bin/afford" replay "$log" >"$out/replay.txt" 2>&1 || { cat "$out/replay.txt"; echo "replay failed"; exit 1; }
grep -q "replay equals the record" "$out/replay.txt" && grep -q "weights_checksum: $sum" "$out/replay.txt" ||
  { cat "$out/replay.txt"; echo "the log does not replay to the run's weights $sum"; exit 1; }
segments=$(ls "$log" | grep -c 'log\..*\.lcm')
[[ $fault == pause* ]] || ((segments >= 2)) || { echo "the restarted logger wrote no second segment"; exit 1; }
# The logger is free again, not left in the run.
"$build/bin/afford" status --lcm-url "$url" --wait-for logger --state waiting --seconds 10 >/dev/null ||
  { "$build/bin/afford" status --lcm-url "$url" --seconds 1; echo "the logger is not free after the runs"; exit 1; }
echo "the run completed; its log ($segments segment(s)) replays to weights_checksum $sum; the extrinsic test ran"
if [[ -n ${AFFORD_LOGGER_FAULTS_BENCH:-} ]]; then
  "$build/bin/afford" "${experiment[@]}" --transport memq --keep-logs none --run-prefix faults \
    --out "$out/undisturbed" --log-root "$out/undisturbed-logs" >"$out/undisturbed.txt" 2>&1
  undisturbed=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/undisturbed/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
  printf '{"fault": "%s", "seed": %d, "step": %d, "completed": true, "replays": true, "weights_checksum": "%s", "undisturbed": "%s"}\n' \
    "$fault" "$seed" "$at" "$sum" "$undisturbed"
fi
