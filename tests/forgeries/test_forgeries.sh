#!/usr/bin/env bash
# Forged names, paths and floods on an unauthenticated bus: afford-hostile
# sends the run's own RUN_CONFIG with run ids that climb out of a folder
# (../../.., absolute, ".."), with fresh run ids whose checkpoint lies outside
# the predictors' folder, the logger's DONE naming a folder outside as the
# run's log; a flood of distinct RUN_CONTROL messages of the run; and a flood
# of STATUS messages from made-up processes and pids, while `afford status`
# listens. All of them point into one folder, $out/outside, which must never
# come to exist; nothing may be written anywhere but the configured roots;
# every process must be alive and none 64 MB above its peak in the same
# experiment undisturbed; the logger must have recorded at most
# protocol.limits.control_messages control messages (the manifest counts the
# rest), `afford status` at most protocol.limits.peers processes, and the
# runner must take no folder a message names. The results must be the
# undisturbed ones.
#   tests/forgeries/test_forgeries.sh BUILD_DIR WORK_DIR
# AFFORD_FORGE_MESSAGES (default 12000), AFFORD_FORGE_SEED (default random).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
messages=${AFFORD_FORGE_MESSAGES:-12000}
seed=${AFFORD_FORGE_SEED:-$((1 + RANDOM % 100000))}
url="udpm://239.255.76.67:7986?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
outside=$out/outside
echo "forgeries: $messages messages, seed $seed; every forged path points into $outside"

experiment() {  # $1: label
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 4000 --seed 9 --extrinsic-reps 1 \
    --scenarios scenario1 --quiet --attach "$url" --run-prefix forge --out "$out/$1" --log-root "$out/$1-logs" \
    >"$out/$1.txt" 2>&1
}
group_diagnose forged "seed $seed" "$out/forged.txt" "$out/hostile.txt"

group_undisturbed
touch "$out/.start"

group_start forged
experiment forged &
runner=$!
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null ||
  { cat "$out/forged.txt"; echo "the run never started"; exit 1; }
# afford status listens through the flood: what it keeps is bounded.
/usr/bin/time -f "%M" -o "$out/status.rss" "$build/bin/afford" status --lcm-url "$url" --seconds 4 >"$out/status.txt" 2>&1 &
status=$!
"$build/bin/afford-hostile" --lcm-url "$url" --messages "$messages" --seed "$seed" --outside "$outside" \
  --kinds paths control statusflood >"$out/hostile.txt" 2>&1
cat "$out/hostile.txt"
wait "$runner" || { cat "$out/forged.txt"; echo "the experiment under the forgeries failed"; exit 1; }
wait "$status" || true
group_stop forged

# Nothing was written outside the roots: the folder every forged path points into does not exist, and
# every file written since the start is in the group's roots, the experiment's output or this test's own.
[[ ! -e $outside ]] || { find "$outside" | head; echo "a forged path was written to"; exit 1; }
stray=$(find "$out" -newer "$out/.start" -not -path "$out/forged-logs*" -not -path "$out/forged/*" -not -path "$out/forged" \
  -not -name 'forged*.log' -not -name '*.txt' -not -name '*.rss' -not -name '*.diff' -not -path "$out" -print)
[[ -z $stray ]] || { echo "$stray"; echo "files were written outside the configured roots"; exit 1; }
find / -xdev -newer "$out/.start" \( -name 'climb-*' -o -name 'abs-*' -o -name 'forged-*.ckpt' \) -print 2>/dev/null |
  grep . && { echo "a forged name was written somewhere"; exit 1; }
echo "nothing written outside the roots"

same_results "$out/clean" "$out/forged" || exit 1
echo "the results equal the undisturbed experiment's"

# The runner took no folder a forged STATUS named: the run's log folder is its own, or none (a forged
# DONE of the logger, which no receiver on an unauthenticated bus can tell from the real one, may end the
# runner's wait for the real one).
if grep '"log_dir"' "$out/forged/summary.json" | grep -v -e null -e "\"$out/forged-logs/forge-base-IMP-s9\""; then
  echo "the runner took a log folder a forged message named"; exit 1
fi
# The logger recorded a bounded number of control messages and counted the rest.
limit=$(awk '/control_messages:/ {print $2; exit}' "$root/config/defaults.yaml")
manifest=$out/forged-logs/forge-base-IMP-s9/manifest.json
dropped=$(grep -o '"control_dropped": [0-9]*' "$manifest" | grep -o '[0-9]*$' || echo 0)
# (each event names its channel in plain text, and no message's data holds these names)
recorded=$(cat "$out"/forged-logs/forge-base-IMP-s9/log.*.lcm | grep -a -o -E 'RUN_CONFIG|RUN_CONTROL' | wc -l)
echo "the logger recorded $recorded control messages of the run (at most $limit) and counted $dropped more"
((recorded <= limit)) || { echo "the logger recorded more than protocol.limits.control_messages"; exit 1; }
((dropped > 0)) || { echo "no forged RUN_CONTROL reached the logger during the run"; exit 1; }
# afford status listed at most protocol.limits.peers processes and said how many more it heard.
peers=$(awk '/peers:/ {print $2; exit}' "$root/config/defaults.yaml")
listed=$(($(wc -l <"$out/status.txt") - 1))
grep -q "more process ids heard, beyond protocol.limits.peers" "$out/status.txt" ||
  { tail -3 "$out/status.txt"; echo "afford status did not say it forgot some of the flood"; exit 1; }
((listed <= peers + 2)) || { echo "afford status listed $listed lines for at most $peers processes"; exit 1; }
echo "afford status: $(tail -1 "$out/status.txt"); peak memory $(cat "$out/status.rss") kB"

worst=0
for p in "${processes[@]}"; do
  c=${peak[clean-$p]} f=${peak[forged-$p]}
  grown=$(((f - c) / 1024))
  printf "peak memory %-11s undisturbed %7d kB, forged %7d kB (%+d MB)\n" "$p" "$c" "$f" "$grown"
  ((grown > worst)) && worst=$grown
done
((worst <= 64)) || { echo "a process grew more than 64 MB above its undisturbed peak"; exit 1; }
