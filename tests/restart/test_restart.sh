#!/usr/bin/env bash
# Live restart: during a run on hand-started processes, `kill -9` one of them
# at a random moment and start it again with the same command. The run must
# complete with the same final weights and the same summary as an
# uninterrupted run, and its log (the segments together) must replay to them.
#   tests/restart/test_restart.sh BUILD_DIR WORK_DIR PROCESS [SEED]
# PROCESS: environment, eye, predictors, motivation, logger (killed during the
# intrinsic run) or planner (killed during the extrinsic tests).
set -euo pipefail
build=$(cd "$1" && pwd)
rm -rf "$2" && mkdir -p "$2"
out=$(cd "$2" && pwd)
victim=$3
seed=${4:-$((1 + RANDOM % 20))}
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_private_netns "$0" "$@"

url="udpm://239.255.76.67:7993?ttl=0&recv_buf_size=2097152"
steps=3000
processes=(environment eye predictors motivation planner logger)
command_of() {  # the command that starts process $1, the same before and after the kill
  case $1 in
    logger) echo "$build/bin/afford-logger --lcm-url $url --log-dir $out/logs" ;;
    *) echo "$build/bin/afford-$1 --lcm-url $url" ;;
  esac
}
declare -A pid
start() { $(command_of "$1") >>"$out/$1.log" 2>&1 & pid[$1]=$!; }
for p in "${processes[@]}"; do start "$p"; done
sleep 1

experiment=(experiment base --system IMP --reps 1 --steps "$steps" --seed "$seed" --quiet --scenarios scenario1 --scenarios scenario2)
extrinsic=(--extrinsic-reps 3)
# The planner's tests run their whole budget (no scene is close enough to end
# one early), so there is time to kill it in the middle of one.
[[ $victim == planner ]] && extrinsic+=(--set planner.success_distance=0 --set planner.budget=1500 --set planner.max_attempts=1500)
echo "seed $seed, killing $victim"
"$build/bin/afford" "${experiment[@]}" "${extrinsic[@]}" --attach "$url" --run-prefix restart \
  --out "$out/attached" --log-root "$out/logs" >"$out/attached.txt" 2>&1 &
runner=$!

# The moment: a random time into the phase the process serves.
if [[ $victim == planner ]]; then  # a random moment of the second test
  for _ in $(seq 6000); do grep -q "configured for run '.*-e1'" "$out/planner.log" && break; sleep 0.01; done
  delay=$((20 + RANDOM % 200))
else
  for _ in $(seq 600); do grep -q "configured for run" "$out/$victim.log" && break; sleep 0.1; done
  delay=$((300 + RANDOM % 1700))  # ms into the intrinsic run (it lasts 4-7 s)
fi
sleep "$(printf '%d.%03d' $((delay / 1000)) $((delay % 1000)))"
kill -0 "$runner" 2>/dev/null || { cat "$out/attached.txt"; echo "the run ended before the kill"; exit 1; }
kill -9 "${pid[$victim]}"
wait "${pid[$victim]}" 2>/dev/null || true
echo "killed $victim ${delay} ms into its phase" | tee "$out/kill.txt"
sleep 0.5
start "$victim"
wait "$runner" || { cat "$out/attached.txt"; echo "the run with a restarted $victim failed"; exit 1; }
grep -q "free again" "$out/attached.txt" || { cat "$out/attached.txt"; echo "the runner never re-sent the run"; exit 1; }
grep -o "process $victim is free again.* at step [0-9]*" "$out/attached.txt" | head -1

# The same experiment uninterrupted, hosted by the runner in one process.
"$build/bin/afford" "${experiment[@]}" "${extrinsic[@]}" --transport memq --keep-logs none --run-prefix restart \
  --out "$out/uninterrupted" >"$out/uninterrupted.txt" 2>&1

# Summaries equal, but for what the wall clock, the host or the paths decide.
results() {
  awk '/"peak_rss_kb": \{\}/ {next} /"peak_rss_kb": \{/ {skip=1; next} skip && /\}/ {skip=0; next} !skip' "$1/summary.json" |
    grep -v -E '"(wall_seconds|run_seconds|steps_per_second|log_bytes|log_bytes_per_step|log_dir|checkpoint|transport|network|afford_version|run_id)"'
}
if ! diff <(results "$out/attached") <(results "$out/uninterrupted") >"$out/summary.diff"; then
  head -40 "$out/summary.diff"; echo "the summary differs from the uninterrupted run's"; exit 1
fi
for f in "$out"/uninterrupted/*.csv; do
  cmp -s "$f" "$out/attached/$(basename "$f")" || { echo "$(basename "$f") differs"; exit 1; }
done
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/attached/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum, equal to the uninterrupted run's; summary and CSV files equal"

# The intrinsic run's log, all its segments, replays to the same weights.
log=$(ls -d "$out"/logs/restart-base-IMP-s"$seed")
"$build/bin/afford" replay "$log" | tee "$out/replay.txt"
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the log replays differently"; exit 1; }
if [[ $victim == logger ]]; then
  [[ -f $log/log.01.lcm ]] || { echo "the restarted logger wrote no second segment"; exit 1; }
  echo "the restarted logger continued the log in $(ls "$log" | grep -c 'log\..*\.lcm') segments"
fi
