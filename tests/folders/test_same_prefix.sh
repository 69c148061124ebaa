#!/usr/bin/env bash
# Two experiments given one --run-prefix and one log root never share a run's folder: whichever comes second
# is refused at once, naming the folder and the experiment that has it, and leaves nothing behind.
#  * The second starts while the first runs its first run, and plans only the first's third run: it may not
#    take that run's folder before the first gets to it.
#  * Two started together, four times: either one first, with the same configuration and with another.
#   tests/folders/test_same_prefix.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
fail() { echo "$*"; exit 1; }
start() {  # TRY NAME ARGS...: an experiment in the background; its exit status goes to $out/TRY-NAME.code
  local try=$1 name=$2
  shift 2
  (code=0
   "$build/bin/afford" experiment base --system FIX --no-reuse-agents "$@" --transport memq --run-prefix "p$try" \
     --log-root "$out/logs" --quiet --progress none --out "$out/$try-$name" >"$out/$try-$name.txt" 2>&1 || code=$?
   echo $code >"$out/$try-$name.code") &
}
# TRY WINNER LOSER FOLDER...: WINNER ran every run of FOLDER... whole; LOSER was refused naming the first of them.
judge() {
  local try=$1 won=$2 lost=$3 first=$4 dir
  shift 4
  [[ $(cat "$out/$try-$won.code") == 0 && $(cat "$out/$try-$lost.code") == 2 ]] ||
    { cat "$out/$try-$won.txt" "$out/$try-$lost.txt"; fail "try $try: $won exited $(cat "$out/$try-$won.code"), $lost $(cat "$out/$try-$lost.code"); not 0 and 2"; }
  grep -q "the log folder $out/logs/$first exists already.* of experiment base, writing to $out/$try-$won" \
    "$out/$try-$lost.txt" || { cat "$out/$try-$lost.txt"; fail "try $try: the refusal does not name the folder and whose it is"; }
  [[ ! -e $out/$try-$lost ]] || fail "try $try: the refused experiment left $out/$try-$lost"
  for dir in "$@"; do
    dir=$out/logs/$dir
    [[ $(ls "$dir" | grep -c '\.lcm$') -eq 1 ]] && grep -q '"complete": *true' "$dir/manifest.json" &&
      grep -q "\"out_dir\":\"$out/$try-$won\"" "$dir/run.json" || { ls -l "$dir"; fail "try $try: $dir is not one whole run of $won"; }
  done
}

start 0 a --seed 1 --reps 3 --steps 200
wait_until 60 test -e "$out/logs/p0-base-FIX-s1" || fail "the first experiment's first run never began"
start 0 b --seed 3 --reps 1 --steps 200
wait
judge 0 a b p0-base-FIX-s3 p0-base-FIX-s1 p0-base-FIX-s2 p0-base-FIX-s3

for try in 1 2 3 4; do
  same=(--seed 1 --reps 1 --steps 100)
  other=("${same[@]}")
  ((try <= 2)) || other+=(--set motivation.leak=0.2)
  if ((try % 2)); then start $try a "${same[@]}"; start $try b "${other[@]}"; else start $try b "${other[@]}"; start $try a "${same[@]}"; fi
  wait
  if [[ $(cat "$out/$try-a.code") == 0 ]]; then won=a lost=b; else won=b lost=a; fi
  judge $try $won $lost p$try-base-FIX-s1 p$try-base-FIX-s1
done
echo "of two experiments with one run prefix, one runs and the other is refused at once"
