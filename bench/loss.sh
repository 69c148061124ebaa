#!/usr/bin/env bash
# Packet loss, speed: how much longer a run takes when the loopback drops
# datagrams at random (docs/performance.md#packet-loss). For each of R seeds,
# the experiment of tests/loss/lossy.sh without loss and at each rate; the time
# of the run from START to RESULT against the lossless one's. Floor: at 5%,
# the median over seeds at most 3 times as long (PASS/FAIL, exit 1 on FAIL).
# Run it on an otherwise idle machine.
#   bench/run.sh loss [--reps R] [--seed S] [--rates "0.01 0.05 0.20"] [--out DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/tests/netns.sh"
reps=3 first_seed=1 rates="0.01 0.05 0.20" dir=out/bench/loss
while (($#)); do
  case $1 in
    --reps) reps=$2 ;;
    --seed) first_seed=$2 ;;
    --rates) rates=$2 ;;
    --out) dir=$2 ;;
    *) echo "bench/run.sh loss: unknown argument '$1' (--reps R, --seed S, --rates \"R1 R2\", --out DIR)" >&2; exit 2 ;;
  esac
  shift 2 || { echo "bench/run.sh loss: $1 needs a value" >&2; exit 2; }
done
[[ $reps =~ ^[1-9][0-9]*$ ]] || { echo "bench/run.sh loss: --reps must be a positive integer, not '$reps'" >&2; exit 2; }
[[ $first_seed =~ ^[0-9]+$ ]] || { echo "bench/run.sh loss: --seed must be a non-negative integer, not '$first_seed'" >&2; exit 2; }
read -r -a rates <<<"$rates"
for p in "${rates[@]}"; do
  awk -v p="$p" 'BEGIN {exit !(p > 0 && p < 1)}' || { echo "bench/run.sh loss: a rate must be in (0, 1), not '$p'" >&2; exit 2; }
done
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
[[ -x $root/build/bin/afford ]] || "$root/scripts/setup.sh"
# A private network namespace of its own; then `out` is emptied per seed.
enter_private_netns "$0" --reps "$reps" --seed "$first_seed" --rates "${rates[*]}" --out "$dir"
build=$root/build
source "$root/tests/loss/lossy.sh"

table=$dir/loss.csv
echo "seed,rate,datagrams_dropped,steps_per_second,times_as_long" >"$table"
for ((i = 0; i < reps; i++)); do
  seed=$((first_seed + i))
  out=$dir/s$seed
  rm -rf "$out" && mkdir -p "$out"
  lossy_experiment 0
  base=$(summary_field "$out/p0" steps_per_second)
  echo "$seed,0,0,$base,1" >>"$table"
  for p in "${rates[@]}"; do
    lossy_experiment "$p"
    sps=$(summary_field "$out/p$p" steps_per_second)
    slowdown=$(awk -v a="$base" -v b="$sps" 'BEGIN {printf "%.2f", a / b}')
    echo "$seed,$p,$dropped,$sps,$slowdown" >>"$table"
    printf "seed %s, loss %s: %.0f steps/s (%.0f without), %s times as long, %s datagrams dropped\n" \
      "$seed" "$p" "$sps" "$base" "$slowdown" "$dropped"
  done
  rm -rf "$out"/p*-logs  # the logs are large; the summaries stay
done

echo
echo "| loss | datagrams dropped | times as long as without loss (median, min to max over $reps seeds) |"
echo "|---|---|---|"
status=0
for p in "${rates[@]}"; do
  mapfile -t t < <(awk -F, -v p="$p" 'NR > 1 && $2 == p {print $5}' "$table" | sort -g)
  mapfile -t d < <(awk -F, -v p="$p" 'NR > 1 && $2 == p {print $3}' "$table" | sort -g)
  n=${#t[@]}
  med=$(awk -v a="${t[$(((n - 1) / 2))]}" -v b="${t[$((n / 2))]}" 'BEGIN {printf "%.2f", (a + b) / 2}')
  verdict=""
  if awk -v p="$p" 'BEGIN {exit !(p == 0.05)}'; then
    if awk -v m="$med" 'BEGIN {exit !(m <= 3)}'; then verdict=" PASS (floor: at most 3)"; else verdict=" FAIL (floor: at most 3)"; status=1; fi
  fi
  printf "| %s%% | %s to %s | %s (%s to %s)%s |\n" "$(awk -v p="$p" 'BEGIN {print p * 100}')" "${d[0]}" "${d[n - 1]}" "$med" "${t[0]}" "${t[n - 1]}" "$verdict"
done
echo "per seed: $table"
exit $status
