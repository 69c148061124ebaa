#!/usr/bin/env bash
# Packet loss: the same experiment (an IMP run of 2000 steps and extrinsic
# tests of its agent, with logs) over udpm in a private network namespace
# whose loopback drops datagrams at random, at 0%, 1%, 5% and 20%, the four
# at once, each on a port of its own (tests/loss/lossy.sh). Every lossy
# experiment must give the lossless one's summary and CSV files (weights
# checksum included), and the most lossy run's log must replay to the same
# weights. How much longer a lossy run takes is a speed goal: `bench/run.sh
# loss` measures it, one experiment at a time (docs/performance.md).
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
source "$root/tests/loss/lossy.sh"
echo "seed $seed"

# All at once, each on its own port at its own rate (most of a lossy run's time is spent waiting for what was lost).
lossy_experiment 0 7996 &
lossless_run=$!
declare -A runner
port=7996
for p in "${rates[@]}"; do
  port=$((port + 1))
  lossy_experiment "$p" "$port" &
  runner[$p]=$!
done
wait "$lossless_run" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/p0/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "loss 0%: weights $sum"
for p in "${rates[@]}"; do
  wait "${runner[$p]}" || exit 1
  echo "loss $p: $(cat "$out/p$p.dropped") datagrams dropped"
  same_results "$out/p0" "$out/p$p" || { echo "at loss $p"; exit 1; }
done
echo "every lossy experiment gave the lossless one's summary and CSV files (weights $sum)"

# The most lossy run's log is whole: it replays to the same weights.
last=${rates[-1]}
"$build/bin/afford" replay "$out/p$last-logs/loss-base-IMP-s$seed" | tee "$out/replay.txt"
grep -q "replay equals the record" "$out/replay.txt" || { echo "the log at loss $last does not replay to the record"; exit 1; }
