#!/usr/bin/env bash
# A finished run's log played onto a live group's bus (lcm-logplayer): the
# processes that write refuse the run (the logger: its folder holds the
# complete log; the predictors: its checkpoint exists), nothing in the run's
# folder changes by a byte, and the group then serves a new run as usual.
#   tests/replay/test_played_log.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
url="udpm://239.255.76.67:7999?ttl=0&recv_buf_size=2097152"
logs="$out/logs"  # the logger's folder and the runner's --log-root: log and checkpoint side by side
mapfile -t processes < <("$build/bin/afford" processes --phase intrinsic)  # the registry's
declare -A pid
for p in "${processes[@]}"; do
  extra=()
  [[ $p == logger ]] && extra=(--log-dir "$logs")
  [[ $p == predictors ]] && extra=(--checkpoint-dir "$logs")
  "$build/bin/afford-$p" --lcm-url "$url" "${extra[@]}" >"$out/$p.log" 2>&1 &
  pid[$p]=$!
done
for _ in $(seq 100); do
  (($("$build/bin/afford" status --lcm-url "$url" --seconds 0.6 | grep -c -E "^(environment|eye|predictors|motivation|logger) ") >= 5)) && break
done

run() {  # $1: run prefix
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 400 --quiet --attach "$url" --run-prefix "$1" --no-reuse-agents \
    --out "$out/$1" --log-root "$logs" >"$out/$1.txt" 2>&1 || { cat "$out/$1.txt"; echo "run $1 failed"; exit 1; }
}
run first
folder="$logs/first-base-IMP-s1"
[[ -f $folder/predictors.ckpt ]] || { ls -l "$folder"; echo "no checkpoint beside the log"; exit 1; }
before=$(cd "$folder" && sha256sum *)

lcm-logplayer --lcm-url "$url" --speed 2 "$folder/log.00.lcm" >"$out/logplayer.txt" 2>&1
after=$(cd "$folder" && sha256sum *)
[[ $before == "$after" ]] || { diff <(echo "$before") <(echo "$after"); echo "the played log changed the run's folder"; exit 1; }
echo "the run's folder is unchanged, byte for byte:"
echo "$after" | sed 's/^/  /'
grep -q "already holds the complete log of run 'first-base-IMP-s1'" "$out/logger.log" ||
  { tail "$out/logger.log"; echo "the logger did not refuse the played run"; exit 1; }
grep -q "checkpoint .*predictors.ckpt exists already: run 'first-base-IMP-s1' has been run before" "$out/predictors.log" ||
  { tail "$out/predictors.log"; echo "the predictors did not refuse the played run"; exit 1; }
echo "the logger and the predictors refused the played run"
for p in "${processes[@]}"; do kill -0 "${pid[$p]}" || { echo "process $p is gone"; exit 1; }; done

# The group, told the played run is over by the log's own STOP, serves a new run.
run second
grep -q '"complete": true' "$logs/second-base-IMP-s1/manifest.json" || { echo "the new run's log is not complete"; exit 1; }
echo "the same group then ran and recorded a new run"
