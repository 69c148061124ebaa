# Sourced by tests/loss/test_loss.sh and bench/loss.sh, inside a private
# network namespace (tests/netns.sh). Needs `build`, `out` and `seed` set.
#
# lossy_experiment RATE: the same experiment (an IMP run of 2000 steps and
# two extrinsic tests of its agent, with logs) over udpm while the loopback
# drops datagrams at random (iptables' statistic match on INPUT) at RATE
# (0 = none). Results in $out/pRATE, logs in $out/pRATE-logs, the command's
# output in $out/pRATE.txt; sets `dropped` to the datagrams dropped.
command -v iptables >/dev/null || { echo "iptables is missing (scripts/setup.sh installs it)"; exit 1; }

lossy_experiment() {
  iptables -F INPUT
  [[ $1 != 0 ]] && iptables -A INPUT -m statistic --mode random --probability "$1" -j DROP
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 2000 --seed "$seed" --extrinsic-reps 2 \
    --scenarios scenario2 --quiet --netns off --base-port 7996 --run-prefix loss \
    --out "$out/p$1" --log-root "$out/p$1-logs" >"$out/p$1.txt" 2>&1 ||
    { tail -n 20 "$out/p$1.txt"; echo "the experiment at loss $1 failed"; iptables -F INPUT; return 1; }
  dropped=$(iptables -L INPUT -v -n -x | awk '/DROP/ {print $1}')
  dropped=${dropped:-0}
  iptables -F INPUT
}

# summary_field DIR FIELD: a number of DIR/summary.json.
summary_field() { grep -o "\"$2\": [0-9.e+-]*" "$1/summary.json" | head -1 | awk '{print $2}'; }
