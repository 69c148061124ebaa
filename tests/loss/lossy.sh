# Sourced by tests/loss/test_loss.sh and bench/loss.sh, inside a private
# network namespace (tests/netns.sh). Needs `build`, `out` and `seed` set.
#
# lossy_experiment RATE [PORT]: the same experiment (an IMP run of 2000 steps
# and two extrinsic tests of its agent, with logs) over udpm on PORT (default
# 7996) while the loopback drops the datagrams to PORT at random (iptables'
# statistic match on INPUT) at RATE (0 = none): experiments on other ports, at
# other rates, can run at the same time. Results in $out/pRATE, logs in
# $out/pRATE-logs, the command's output in $out/pRATE.txt; sets `dropped` to
# the datagrams dropped, and writes it to $out/pRATE.dropped.
command -v iptables >/dev/null || { echo "iptables is missing (scripts/setup.sh installs it)"; exit 1; }

lossy_experiment() {
  local rate=$1 port=${2:-7996} status=0
  local rule=(INPUT -p udp --dport "$port" -m statistic --mode random --probability "$rate" -j DROP)
  [[ $rate == 0 ]] || iptables -w -A "${rule[@]}"
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 2000 --seed "$seed" --extrinsic-reps 2 \
    --scenarios scenario2 --quiet --netns off --base-port "$port" --run-prefix loss \
    --out "$out/p$rate" --log-root "$out/p$rate-logs" >"$out/p$rate.txt" 2>&1 || status=$?
  dropped=$(iptables -w -L INPUT -v -n -x | awk -v port="dpt:$port" '/DROP/ && $0 ~ port {print $1}')
  echo "${dropped:=0}" >"$out/p$rate.dropped"
  [[ $rate == 0 ]] || iptables -w -D "${rule[@]}"
  ((status == 0)) || { tail -n 20 "$out/p$rate.txt"; echo "the experiment at loss $rate failed"; return 1; }
}

# summary_field DIR FIELD: a number of DIR/summary.json.
summary_field() { grep -o "\"$2\": [0-9.e+-]*" "$1/summary.json" | head -1 | awk '{print $2}'; }
