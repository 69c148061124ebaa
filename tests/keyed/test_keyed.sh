#!/usr/bin/env bash
# An authenticated bus: a group that shares a key (afford bus-key) runs an
# experiment, first undisturbed, then while afford-hostile sends at least
# 20,000 perfect forgeries (the next serial of a run channel with the digest
# chain right, a STOP of the run, FAILED STATUS of its processes), tagged with
# another key. Without the group's key, none may change anything: the results
# must be the undisturbed ones (weights checksum included), every process
# alive, and the processes must have dropped the forgeries at the tag. Also:
# `afford status` hears the group only with the key; the run's log, which holds
# the messages without their tags, replays to the same weights. And a
# recording of the undisturbed run (lcm-logger, stamps and tags kept) played
# back onto the group during a later run of the same ids changes nothing:
# every process drops what it is played, counted (freshness).
#   tests/keyed/test_keyed.sh BUILD_DIR WORK_DIR
# AFFORD_KEYED_MESSAGES (default 20000), AFFORD_KEYED_SEED (default random).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
messages=${AFFORD_KEYED_MESSAGES:-20000}
seed=${AFFORD_KEYED_SEED:-$((1 + RANDOM % 100000))}
url="udpm://239.255.76.67:7987?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
key=$out/bus.key
"$build/bin/afford" bus-key "$key" >/dev/null
"$build/bin/afford" bus-key "$out/forger.key" >/dev/null
export AFFORD_BUS_KEY=$key  # afford status and the runner take it from here; the processes get --bus-key
echo "forgeries: $messages, seed $seed"

experiment() {  # $1: label
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 4000 --seed 13 --extrinsic-reps 2 \
    --scenarios scenario3 --quiet --attach "$url" --bus-key "$key" --run-prefix keyed --out "$out/$1" \
    --log-root "$out/$1-logs" >"$out/$1.txt" 2>&1
}
group_diagnose forged "seed $seed" "$out/forged.txt" "$out/hostile.txt"

group_start clean --bus-key "$key"
# Without the key, nothing of the group is heard.
env -u AFFORD_BUS_KEY "$build/bin/afford" status --lcm-url "$url" --seconds 1.2 >"$out/status-without-key.txt" 2>&1 || true
grep -q "no process heard" "$out/status-without-key.txt" ||
  { cat "$out/status-without-key.txt"; echo "afford status heard the keyed group without its key"; exit 1; }
# The undisturbed experiment, recorded as it goes by Debian's lcm-logger (every datagram, stamps and tags kept).
lcm-logger --lcm-url="$url" "$out/recording.lcm" >"$out/lcm-logger.txt" 2>&1 &
recorder=$!
experiment clean || { cat "$out/clean.txt"; echo "the undisturbed experiment failed"; exit 1; }
kill -INT "$recorder"
wait "$recorder" || true

# Freshness: the same experiment again on the same group, the same run ids (the first one's folders moved
# aside), while the recording plays back onto the bus. Every message of it is said again: each process drops
# it at its stamp (its own sessions' counters are behind their windows; the first runner's session is known to
# them, or else its messages are older than protocol.freshness_ms), and the results are the undisturbed ones.
mkdir -p "$out/clean-kept"
mv "$out"/clean-logs/keyed-* "$out/clean-kept/"
played() {
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 4000 --seed 13 --extrinsic-reps 2 \
    --scenarios scenario3 --quiet --attach "$url" --bus-key "$key" --run-prefix keyed --no-reuse-agents \
    --out "$out/played" --log-root "$out/clean-logs" >"$out/played.txt" 2>&1
}
played &
runner=$!
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null ||
  { cat "$out/played.txt"; echo "the run of the same ids never started"; exit 1; }
lcm-logplayer --lcm-url="$url" "$out/recording.lcm" >"$out/logplayer.txt" 2>&1 || { cat "$out/logplayer.txt"; exit 1; }
wait "$runner" || { cat "$out/played.txt"; echo "the experiment under the played-back recording failed"; exit 1; }
group_stop clean
same_results "$out/clean" "$out/played" || { echo "the played-back recording changed the results"; exit 1; }
# What each process was played of the recording: the channels it takes (every process takes STATUS, RUN_CONFIG
# and RUN_CONTROL; the logger every channel), counted from the recording itself.
PYTHONPATH="$build/python" /usr/bin/python3 - "$out/recording.lcm" "$key" >"$out/recorded.txt" <<'PY'
import collections, sys
import afford
log = afford.read_log(sys.argv[1], bus_key=sys.argv[2])
counts = collections.Counter(m.channel for m in log.messages)
print("all", sum(counts.values()))
print("control", counts["STATUS"] + counts["RUN_CONFIG"] + counts["RUN_CONTROL"])
PY
cat "$out/recorded.txt"
recorded_all=$(sed -n 's/^all //p' "$out/recorded.txt")
recorded_control=$(sed -n 's/^control //p' "$out/recorded.txt")
for p in "${processes[@]}"; do
  n=$(sed -n 's/.*stopped; [0-9]* messages dropped at the edge ([0-9]* without a valid tag, \([0-9]*\) said again).*/\1/p' \
    "$out/clean-$p.log" | tail -1)
  want=$recorded_control
  [[ $p == logger ]] && want=$recorded_all
  echo "$p: ${n:-none} messages said again dropped, of $want played to it"
  ((${n:-0} * 10 >= want * 9)) || { echo "process $p did not drop the played-back messages at their stamps"; exit 1; }
done

group_start forged --bus-key "$key"
experiment forged &
runner=$!
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null || { cat "$out/forged.txt"; echo "the run never started"; exit 1; }
"$build/bin/afford-hostile" --lcm-url "$url" --messages "$messages" --seed "$seed" --kinds forge --tagged \
  --forge-key "$out/forger.key" >"$out/hostile.txt" 2>&1
cat "$out/hostile.txt"
sent=$(sed -n 's/^sent \([0-9]*\) .*/\1/p' "$out/hostile.txt")
((sent >= messages)) || { echo "only $sent forgeries were sent"; exit 1; }
kill -0 "$runner" 2>/dev/null && echo "the forgeries ended while the experiment still ran" ||
  echo "NOTE: the experiment ended before the forgeries did"
wait "$runner" || { cat "$out/forged.txt"; echo "the experiment under the forgeries failed"; exit 1; }
group_stop forged

same_results "$out/clean" "$out/forged" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/forged/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum, equal to the undisturbed experiment's; summary and CSV files equal"

# Every process dropped what it heard of them at the tag (each says so when it stops): the forged RUN_CONTROL
# and STATUS messages, which every process takes; the logger, which takes every channel, all of them. (Nine
# in ten: a full socket buffer may lose a datagram here or there, forged or not.)
everyone=$(($(sed -n 's/.* RUN_CONTROL \([0-9]*\).*/\1/p' "$out/hostile.txt") + $(sed -n 's/.* STATUS \([0-9]*\).*/\1/p' "$out/hostile.txt")))
for p in "${processes[@]}"; do
  n=$(sed -n 's/.*stopped; [0-9]* messages dropped at the edge (\([0-9]*\) without a valid tag.*/\1/p' "$out/forged-$p.log" | tail -1)
  want=$everyone
  [[ $p == logger ]] && want=$sent
  echo "$p: ${n:-none} messages without a valid tag dropped, of $want sent to it"
  ((${n:-0} * 10 >= want * 9)) || { echo "process $p did not drop the forgeries it heard at the tag"; exit 1; }
done

# The log holds the messages without their tags (its manifest says the bus was keyed): it replays, with no
# key, to the run's weights.
grep -q '"bus_keyed": true' "$out/forged-logs/keyed-base-IMP-s13/manifest.json" ||
  { echo "the manifest does not say the bus was keyed"; exit 1; }
"$build/bin/afford" replay "$out/forged-logs/keyed-base-IMP-s13" | tee "$out/replay.txt"
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the keyed run's log replays differently"; exit 1; }
