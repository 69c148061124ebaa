#!/usr/bin/env bash
# Crafted datagrams below the edge: LCM's datagram layer itself is fuzzed
# (afford-fragfuzz: fragments shorter than their header, wrapped offsets,
# overlapping and repeated fragments, sparse claims of huge messages from 64
# senders, oversized messages, channel names that do not end, junk, whole
# messages of random bytes) while a run and its extrinsic tests go on, against
# every process of the group, the viewer and an attached runner, all sharing
# a key. The same experiment runs first undisturbed, on a group started the
# same way. Every process must be alive after the flood, the results must be the undisturbed
# ones (weights checksum included), and no process (nor the runner) may have
# grown more than 64 MB above its undisturbed peak (VmHWM). Each process runs
# with its address space capped (ulimit -v), so a runaway allocation fails
# rather than taking the machine.
#   tests/fragments/test_fragments.sh BUILD_DIR WORK_DIR
# AFFORD_FRAG_DATAGRAMS (default 120000), AFFORD_FRAG_SEED (default random),
# AFFORD_FRAG_KINDS (default all) vary the flood.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
datagrams=${AFFORD_FRAG_DATAGRAMS:-120000}
seed=${AFFORD_FRAG_SEED:-$((1 + RANDOM % 100000))}
kinds=()
[[ -n ${AFFORD_FRAG_KINDS:-} ]] && kinds=(--kinds "$AFFORD_FRAG_KINDS")
port=7985
url="udpm://239.255.76.67:$port?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
# A keyed group, as scripts/procs.sh starts them: a whole message of the flood then costs each subscriber
# a hash of its bytes before it is dropped, and waits in LCM's queue meanwhile (protocol.bus.queue_bytes).
"$build/bin/afford" bus-key "$out/bus.key" >/dev/null
export AFFORD_BUS_KEY=$out/bus.key  # every process, the viewer, the runner and afford status
export GROUP_LIMIT_KB=$((3 * 1024 * 1024))  # address space of each process: far above its need, far below the machine's
echo "flood: $datagrams datagrams, seed $seed"

GROUP_EXTRA=(viewer)
group_extra_start() {  # the viewer too, writing a frame now and then
  (ulimit -v "$GROUP_LIMIT_KB" && exec "$build/bin/afford-viewer" --lcm-url "$url" --png "$out/$1-frames" --every 1000000) \
    >>"$out/$1-viewer.log" 2>&1 &
  pid[viewer]=$!
}
experiment() {  # $1: label; the runner's own peak memory in $out/$1.rss (GNU time)
  (ulimit -v "$GROUP_LIMIT_KB" && exec /usr/bin/time -f "%M" -o "$out/$1.rss" "$build/bin/afford" experiment base --system IMP \
    --reps 1 --steps 6000 --seed 5 --extrinsic-reps 2 --scenarios scenario2 --scenarios scenario4 --quiet \
    --attach "$url" --run-prefix frag --out "$out/$1" --log-root "$out/$1-logs") >"$out/$1.txt" 2>&1
}
group_diagnose flooded "seed $seed" "$out/flooded.txt" "$out/fuzz.txt"

group_undisturbed

group_start flooded
experiment flooded &
runner=$!
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null ||
  { cat "$out/flooded.txt"; echo "the run never started"; exit 1; }
"$build/bin/afford-fragfuzz" --group 239.255.76.67 --port "$port" --datagrams "$datagrams" --seed "$seed" --rate 30000 "${kinds[@]}" \
  >"$out/fuzz.txt" 2>&1
cat "$out/fuzz.txt"
kill -0 "$runner" 2>/dev/null && echo "the flood ended while the experiment still ran" ||
  echo "NOTE: the experiment ended before the flood did (the processes, still listening, took the rest)"
wait "$runner" || { cat "$out/flooded.txt"; echo "the experiment under the flood failed"; exit 1; }
# Every process (and the viewer) still answers on the bus once the flood is over.
"$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" --state waiting \
  --seconds 30 >"$out/after.txt" || { cat "$out/after.txt"; echo "not every process answers after the flood"; exit 1; }
group_stop flooded

same_results "$out/clean" "$out/flooded" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/flooded/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum, equal to the undisturbed experiment's; summary and CSV files equal"

worst=0
report() {  # name clean_kb flooded_kb
  local grown=$((($3 - $2) / 1024))
  printf "peak memory %-11s undisturbed %7d kB, flooded %7d kB (%+d MB)\n" "$1" "$2" "$3" "$grown"
  ((grown > worst)) && worst=$grown
  return 0
}
for p in "${processes[@]}" viewer; do report "$p" "${peak[clean-$p]}" "${peak[flooded-$p]}"; done
report runner "$(cat "$out/clean.rss")" "$(cat "$out/flooded.rss")"
((worst <= 64)) || { echo "a process grew more than 64 MB above its undisturbed peak under the flood"; exit 1; }
echo "every process alive; none grew more than 64 MB above its undisturbed peak"
