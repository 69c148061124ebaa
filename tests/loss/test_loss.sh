#!/usr/bin/env bash
# Packet loss: the same experiment (an IMP run of 2000 steps and extrinsic
# tests of its agent, with logs) over udpm in a private network namespace
# whose loopback drops datagrams at random (iptables' statistic match on
# INPUT), at 0%, 1%, 5% and 20%. Every lossy experiment must give the lossless
# one's summary and CSV files (weights checksum included); the run at 5% loss
# must take at most 3 times as long as without loss (START to RESULT); the run
# at 20% must complete, and its log replay to the same weights.
#   tests/loss/test_loss.sh BUILD_DIR WORK_DIR [RATE...]
# AFFORD_LOSS_SEED fixes the run's seed (default random).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
shift 2
rates=("${@:-0.01 0.05 0.20}")
read -r -a rates <<<"${rates[*]}"
seed=${AFFORD_LOSS_SEED:-$((1 + RANDOM % 50))}
command -v iptables >/dev/null || { echo "iptables is missing (scripts/setup.sh installs it)"; exit 1; }
echo "seed $seed"

experiment() {  # $1: loss rate (0 = none); the results in $out/p$1
  iptables -F INPUT
  [[ $1 != 0 ]] && iptables -A INPUT -m statistic --mode random --probability "$1" -j DROP
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 2000 --seed "$seed" --extrinsic-reps 2 \
    --scenarios scenario2 --quiet --netns off --base-port 7996 --run-prefix loss \
    --out "$out/p$1" --log-root "$out/p$1-logs" >"$out/p$1.txt" 2>&1 ||
    { tail -n 20 "$out/p$1.txt"; echo "the experiment at loss $1 failed"; return 1; }
  dropped=$(iptables -L INPUT -v -n -x | awk '/DROP/ {print $1}')
  iptables -F INPUT
}
field() { grep -o "\"$2\": [0-9.e+-]*" "$1/summary.json" | head -1 | awk '{print $2}'; }

experiment 0
base=$(field "$out/p0" steps_per_second)
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/p0/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
printf "loss 0%%: %.0f steps/s, weights %s\n" "$base" "$sum"
for p in "${rates[@]}"; do
  experiment "$p"
  sps=$(field "$out/p$p" steps_per_second)
  slowdown=$(awk -v a="$base" -v b="$sps" 'BEGIN {printf "%.2f", a / b}')
  printf "loss %s: %.0f steps/s, %.2f times as long as without loss (%s datagrams dropped)\n" "$p" "$sps" "$slowdown" "$dropped"
  same_results "$out/p0" "$out/p$p" || { echo "at loss $p"; exit 1; }
  if [[ $p == 0.05 ]]; then
    awk -v s="$slowdown" 'BEGIN {exit !(s <= 3)}' || { echo "at 5% loss the run took more than 3 times as long"; exit 1; }
  fi
done
echo "every lossy experiment gave the lossless one's summary and CSV files (weights $sum)"

# The most lossy run's log is whole: it replays to the same weights.
last=${rates[-1]}
"$build/bin/afford" replay "$out/p$last-logs/loss-base-IMP-s$seed" | tee "$out/replay.txt"
grep -q "replay equals the record" "$out/replay.txt" || { echo "the log at loss $last does not replay to the record"; exit 1; }
