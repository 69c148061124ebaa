#!/usr/bin/env bash
# Hostile input: the same experiment (an intrinsic run and extrinsic tests of
# its agent) on two fresh groups of hand-started processes, the second time
# with afford-hostile publishing at least 10,000 bad messages over the run's
# channels (random bytes; truncated, bit-flipped and re-sealed copies of the
# run's own messages with a wrong run id, step, serial, size field, NaN or
# infinity; duplicates; RESEND storms; STATUS that lie about counts;
# RUN_CONFIG junk). The disturbed experiment must give the undisturbed one's
# summary and CSV files (weights checksum included), every process must be
# alive, and each process's peak memory (VmHWM) must stay within 20% of its
# peak in the undisturbed experiment.
#   tests/hostile/test_hostile.sh BUILD_DIR WORK_DIR
# AFFORD_HOSTILE_MESSAGES (default 10000), AFFORD_HOSTILE_SEED (default random),
# AFFORD_HOSTILE_KINDS (default all) vary the flood.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
messages=${AFFORD_HOSTILE_MESSAGES:-10000}
seed=${AFFORD_HOSTILE_SEED:-$((1 + RANDOM % 100000))}
kinds=()
[[ -n ${AFFORD_HOSTILE_KINDS:-} ]] && kinds=(--kinds $AFFORD_HOSTILE_KINDS)
url="udpm://239.255.76.67:7995?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
echo "flood: $messages messages, seed $seed"

experiment() {  # $1: label
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 3000 --seed 7 --extrinsic-reps 2 \
    --scenarios scenario2 --scenarios scenario4 --quiet --attach "$url" --run-prefix flood \
    --out "$out/$1" --log-root "$out/$1-logs" >"$out/$1.txt" 2>&1
}
group_diagnose hostile "seed $seed" "$out/hostile.txt" "$out/flood.txt"

group_undisturbed

group_start hostile
experiment hostile &
runner=$!
"$build/bin/afford-hostile" --lcm-url "$url" --messages "$messages" --seed "$seed" "${kinds[@]}" >"$out/flood.txt" 2>&1
cat "$out/flood.txt"
kill -0 "$runner" 2>/dev/null && echo "the flood ended while the experiment still ran" || echo "NOTE: the experiment ended before the flood did"
wait "$runner" || { cat "$out/hostile.txt"; echo "the experiment under the flood failed"; exit 1; }
group_stop hostile

# The same results, but for what the clock, the host or the paths decide.
same_results "$out/clean" "$out/hostile" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/hostile/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum, equal to the undisturbed experiment's; summary and CSV files equal"

# The edge dropped them, naming channel and field; nothing crashed.
dropped=$(cat "$out"/hostile-*.log | grep -c "dropped message" || true)
echo "lines 'dropped message' in the processes' output: $dropped"
((dropped > 0)) || { echo "no message was dropped: the flood did not reach the processes"; exit 1; }

worst=0
for p in "${processes[@]}"; do
  c=${peak[clean-$p]} h=${peak[hostile-$p]}
  pct=$(((h - c) * 100 / c))
  printf "peak memory %-11s undisturbed %6d kB, flooded %6d kB (%+d%%); resident at the end %d / %d kB\n" "$p" "$c" "$h" "$pct" "${resident[clean-$p]}" "${resident[hostile-$p]}"
  ((pct > worst)) && worst=$pct
done
((worst <= 20)) || { echo "a process's peak memory grew by more than 20% under the flood"; exit 1; }

# The flooded run's log replays to its weights.
"$build/bin/afford" replay "$out/hostile-logs/flood-base-IMP-s7" | tee "$out/replay.txt"
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the flooded run's log replays differently"; exit 1; }
