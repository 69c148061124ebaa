# Sourced, after tests/netns.sh and enter_test, by the tests of a scripts/procs.sh group (tests/procs).
#
# procs_group PORT: the group's commands in this namespace (AFFORD_NETNS=none) on PORT, its folders in
#   $out/logs; sets `procs` (the script), `logs` and `host`. Every process of the group (paused ones
#   continued first) and the test's own background jobs are killed when the test ends.
# start_beside_reference STEPS: `undisturbed STEPS` in the background (its pid in `reference`), and meanwhile
#   the group's six processes started.
# checksum DIR: the first weights checksum of an experiment's summary.json.
# undisturbed STEPS: the weights checksum of the FIX run of seed 2 and STEPS steps in one process (into
#   $out/undisturbed.sum too: a test may run it in the background while its group starts).
procs_group() {
  export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_GRACE=3 AFFORD_LOGS=$out/logs
  export AFFORD_URL="udpm://239.255.76.67:$1?ttl=0&recv_buf_size=2097152"
  procs=$root/scripts/procs.sh logs=$out/logs host=$(hostname)
  trap 'kill -CONT $(cat "$logs"/demo/*.pid 2>/dev/null) 2>/dev/null; kill $(jobs -p) 2>/dev/null || true
        "$procs" kill demo $("$build/bin/afford" processes) >/dev/null 2>&1 || true' EXIT
}

checksum() { grep -o '"weights_checksum": "[0-9a-f]*"' "$1/summary.json" | head -1; }

undisturbed() {
  "$build/bin/afford" experiment base --system FIX --reps 1 --steps "$1" --seed 2 --transport memq --keep-logs none \
    --quiet --out "$out/undisturbed" --log-root "$out/undisturbed-logs" >"$out/undisturbed.txt" 2>&1 ||
    { cat "$out/undisturbed.txt"; return 1; }
  checksum "$out/undisturbed" | tee "$out/undisturbed.sum"
}

start_beside_reference() {
  undisturbed "$1" >/dev/null &
  reference=$!
  "$procs" start demo >"$out/start.txt" || { cat "$out/start.txt"; return 1; }
}
