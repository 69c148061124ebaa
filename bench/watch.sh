#!/usr/bin/env bash
# A run watched by afford watch's page in headless Chromium against the same run
# unwatched, over udpm in a private network namespace: the weights checksum of
# each pair (must be equal) and their steps per second (floor: watched at least
# 0.95 of unwatched, median over the pairs; exit 1 below it). The pairs run in
# alternating order. docs/performance.md reports it.
# --page remote: the page is elsewhere (a browser on another machine, as for a
# cluster node reached over ssh): only a client reading its event stream runs
# here. --page local (the default): headless Chromium on the run's machine.
#   bench/run.sh watch [--steps N] [--reps R] [--floor F] [--page local|remote] [--out DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
steps=6000 reps=10 floor=0.95 page=local out=$root/out/bench-watch
while (($#)); do
  case $1 in
    --steps) steps=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    --floor) floor=$2; shift 2 ;;
    --page) page=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "bench/watch.sh: unknown option '$1' (--steps, --reps, --floor, --page, --out)" >&2; exit 2 ;;
  esac
done
source "$root/tests/netns.sh"
[[ $page == local || $page == remote ]] || { echo "bench/watch.sh: --page is local or remote, not '$page'" >&2; exit 2; }
enter_private_netns "$0" --steps "$steps" --reps "$reps" --floor "$floor" --page "$page" --out "$out"
build=$root/build
[[ -x $build/bin/afford ]] || "$root/scripts/setup.sh"
rm -rf "$out" && mkdir -p "$out"
export PYTHONPATH=$build/python
port=7997
url="udpm://239.255.76.67:$port?ttl=0"

run() {  # NAME: one run of the pair into $out/NAME
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps "$steps" --extrinsic-reps 0 --quiet \
    --netns off --base-port "$port" --keep-logs none --out "$out/$1" --log-root "$out/logs-$1" --run-prefix "$1" \
    >"$out/$1.log" 2>&1 || { cat "$out/$1.log"; exit 1; }
}
watched() {  # NAME: the same, with the page open on it throughout
  "$build/bin/afford" watch --lcm-url "$url" --port 8093 ${AFFORD_WATCH_ARGS:-} >"$out/$1-watch.log" 2>&1 &
  local watch=$!
  wait_until 30 grep -qs "the page:" "$out/$1-watch.log" || { cat "$out/$1-watch.log"; exit 1; }
  /usr/bin/python3 "$root/tests/watch/browser.py" "$([[ $page == local ]] && echo hold || echo stream)" http://127.0.0.1:8093/ "$out/$1/summary.json" \
    "$out/$1-page.ready" >"$out/$1-page.log" 2>&1 &
  local page=$!
  wait_until 60 test -e "$out/$1-page.ready" || { cat "$out/$1-page.log"; exit 1; }  # the page follows the bus
  [[ $page == remote ]] || wait_until 60 browser_settled || echo "(Chromium still busy after 60 s)"
  run "$1"
  wait "$page" || { cat "$out/$1-page.log"; exit 1; }
  kill "$watch"; wait "$watch" 2>/dev/null || true
}

# Until headless Chromium has finished starting (its processes took at most one clock tick, 10 ms, of CPU
# in the last half second), or 60 s: the run then measures what following it costs, not the browser's
# start (a page opened on a run already going pays that once).
browser_ticks() {
  local t=0 f
  for p in $(pgrep -f afford-chromium-); do read -r -a f <"/proc/$p/stat" 2>/dev/null && t=$((t + f[13] + f[14])); done
  echo "$t"
}
browser_settled() {
  local a b
  a=$(browser_ticks); read -r -t 0.5 <> <(:) || true; b=$(browser_ticks)
  ((b - a <= 1))
}

field() { /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['systems']['IMP']['runs'][0]; print(r[sys.argv[2]])" "$1" "$2"; }
printf '%-4s %-18s %-18s %12s %12s %7s\n' rep unwatched watched "steps/s" "watched" ratio | tee "$out/results.txt"
for r in $(seq "$reps"); do
  if ((r % 2)); then run "plain$r"; watched "watched$r"; else watched "watched$r"; run "plain$r"; fi
  a=$(field "$out/plain$r/summary.json" weights_checksum) b=$(field "$out/watched$r/summary.json" weights_checksum)
  sa=$(field "$out/plain$r/summary.json" steps_per_second) sb=$(field "$out/watched$r/summary.json" steps_per_second)
  [[ $a == "$b" ]] || { echo "rep $r: the watched run's checksum $b is not the unwatched $a"; exit 1; }
  printf '%-4s %-18s %-18s %12.0f %12.0f %7.3f   (%s)\n' "$r" "$a" "$b" "$sa" "$sb" "$(awk -v a="$sa" -v b="$sb" 'BEGIN { print b / a }')" \
    "$(cat "$out/watched$r-page.log")" | tee -a "$out/results.txt"
done
/usr/bin/python3 - "$out/results.txt" "$floor" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]).read().splitlines()[1:]]
ratio = statistics.median(float(r[5]) for r in rows)
floor = float(sys.argv[2])
print(f"median watched / unwatched: {ratio:.3f} over {len(rows)} pairs, every checksum equal: "
      f"{'PASS' if ratio >= floor else 'FAIL'} (floor {floor})")
sys.exit(0 if ratio >= floor else 1)
PY
