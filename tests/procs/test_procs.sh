#!/usr/bin/env bash
# scripts/procs.sh as a user drives it: start a group, status, a run on it,
# kill -9 and start one process during the run from another working folder
# (the run's weights are an undisturbed run's), afford clean during the run,
# restart one, stop them all.
#   tests/procs/test_procs.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
# The script as in a checkout of its own ($out/checkout/scripts/procs.sh), so that its folders are the checkout's
# logs/ (no $AFFORD_LOGS, which the processes would inherit): a process must be told where they are.
mkdir -p "$out/checkout/scripts" "$out/a" "$out/b"
ln -s "$root/scripts/procs.sh" "$out/checkout/scripts/procs.sh"
unset AFFORD_LOGS
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_GRACE=3
procs=$out/checkout/scripts/procs.sh logs=$out/checkout/logs
cd "$out/a"
# The group's processes are procs.sh's, not this script's jobs: a test that fails midway kills them too.
trap 'kill $(jobs -p) 2>/dev/null || true; "$procs" kill demo environment eye predictors motivation planner logger >/dev/null 2>&1 || true' EXIT

"$procs" start demo | tee "$out/start.txt"
[[ $(grep -c "started (pid" "$out/start.txt") -eq 6 ]] || { echo "expected 6 processes started"; exit 1; }
grep -q "^group folder: $logs/demo " "$out/start.txt" || { echo "start does not say where the group is kept"; exit 1; }
"$procs" status demo --wait-for environment,eye,predictors,motivation,planner,logger --state waiting --seconds 30 |
  tee "$out/status.txt"
[[ $(grep -c " yes$" "$out/status.txt") -eq 6 ]] || { echo "expected 6 live processes"; exit 1; }
[[ $(grep -c "waiting" "$out/status.txt") -eq 6 ]] || { echo "expected 6 processes waiting for a run"; exit 1; }

# A snapshot every 500 steps: the eye is killed past the first, and started again from another working folder;
# it must go on from its snapshot (its peers no longer hold what came before it).
experiment=(base --system FIX --reps 1 --steps 3000 --seed 2 --set protocol.recovery.snapshot_steps=500)
"$procs" run demo "${experiment[@]}" --quiet --out "$out/run" >"$out/run.txt" 2>&1 &
runner=$!
"$procs" status demo --wait-for eye --step 600 --seconds 60 >/dev/null ||
  { cat "$out/run.txt"; echo "the eye never reached step 600"; exit 1; }
# afford clean never offers the group's run going on (its runner holds its experiment's folder).
"$build/bin/afford" clean --log-root "$logs" --all >"$out/clean-run.txt"
grep -q "would remove.*/demo-base-FIX-s2$" "$out/clean-run.txt" && { cat "$out/clean-run.txt"; echo "clean offers the group's run going on"; exit 1; }
grep -q "^left alone .*/demo-base-FIX-s2: its experiment is running (in $out/run)" "$out/clean-run.txt" ||
  { cat "$out/clean-run.txt"; echo "clean does not say the group's run is going on"; exit 1; }
"$procs" kill demo eye
"$procs" status demo | grep "^eye" | head -1 | grep -q " no$" || { echo "status does not show the killed eye as dead"; exit 1; }
(cd "$out/b" && "$procs" start demo eye)
wait "$runner" || { cat "$out/run.txt"; grep -h "error" "$logs/demo/eye.log" | tail -3; echo "the run failed"; exit 1; }
grep -q "process eye is free again" "$out/run.txt" || { cat "$out/run.txt"; echo "the eye did not rejoin"; exit 1; }
grep -q "goes on from its snapshot of step" "$logs/demo/eye.log" || { echo "the eye did not go on from its snapshot"; exit 1; }
[[ $(grep -c "=== .* start:" "$logs/demo/eye.log") -eq 2 ]] || { echo "the eye's log should hold both starts"; exit 1; }
[[ -f $logs/demo-base-FIX-s2/log.00.lcm ]] || { echo "no run log"; exit 1; }
[[ ! -e $out/a/logs && ! -e $out/b/logs ]] || { echo "a process wrote under its working folder's logs/"; exit 1; }
"$build/bin/afford" experiment "${experiment[@]}" --transport memq --keep-logs none --quiet --out "$out/undisturbed" \
  --log-root "$out/undisturbed-logs" >"$out/undisturbed.txt" 2>&1 || { cat "$out/undisturbed.txt"; exit 1; }
checksum() { grep -o '"weights_checksum": "[0-9a-f]*"' "$1/summary.json" | head -1; }
[[ -n $(checksum "$out/run") && $(checksum "$out/run") == "$(checksum "$out/undisturbed")" ]] ||
  { echo "the weights differ from an undisturbed run's: $(checksum "$out/run") vs $(checksum "$out/undisturbed")"; exit 1; }
# afford experiment gives a --process command the log root as its --state-dir too (not the working folder's logs/).
(cd "$out/b" && "$build/bin/afford" experiment base --system FIX --reps 1 --steps 600 --seed 2 --quiet --netns off \
  --base-port 7710 --set protocol.recovery.snapshot_steps=200 --process eye="$build/bin/afford-eye" \
  --out "$out/swapped" --log-root "$out/swapped-logs" >"$out/swapped.txt" 2>&1) || { cat "$out/swapped.txt"; exit 1; }
[[ ! -e $out/b/logs ]] || { echo "afford experiment's --process eye wrote its snapshots under its working folder's logs/"; exit 1; }
# Every column of afford status is labelled: the logger's is where it wrote the run's log.
"$procs" status demo | tee "$out/status-done.txt"
grep -Eq "^process +pid +state +last step +run +detail$" "$out/status-done.txt" &&
  grep -Eq "^logger +[0-9]+  [a-z]+ +-?[0-9]+  [^ ]+ +$logs/demo-base-FIX-s2$" "$out/status-done.txt" ||
  { echo "afford status: the logger's column is unlabelled or misplaced"; exit 1; }

# The same run again: new run ids (demo-2-...), and --run-prefix is the user's to give.
"$procs" run demo base --system FIX --reps 1 --steps 200 --seed 2 --quiet --out "$out/run2" >"$out/run2.txt" 2>&1 ||
  { cat "$out/run2.txt"; echo "a second run with the same seed failed"; exit 1; }
[[ -f $logs/demo-2-base-FIX-s2/log.00.lcm ]] || { cat "$out/run2.txt"; echo "the second run is not demo-2-..."; exit 1; }
"$procs" run demo base --system FIX --reps 1 --steps 200 --seed 2 --quiet --no-reuse-agents --run-prefix mine --out "$out/run3" \
  >"$out/run3.txt" 2>&1 || { cat "$out/run3.txt"; echo "--run-prefix with procs.sh run failed"; exit 1; }
[[ -f $logs/mine-base-FIX-s2/log.00.lcm ]] || { echo "--run-prefix mine was not used"; exit 1; }
# afford clean never offers the live group's folder (its key, its pids).
"$build/bin/afford" clean --log-root "$logs" --all | tee "$out/clean.txt"
grep -q "would remove.*logs/demo$" "$out/clean.txt" && { echo "clean would remove the live group's folder"; exit 1; }
grep -q "^left alone .*logs/demo: a scripts/procs.sh group (running: " "$out/clean.txt" ||
  { echo "clean does not say it leaves the live group alone"; exit 1; }

"$procs" restart demo predictors | tee "$out/restart.txt"
grep -q "predictors (pid [0-9]*) stopped" "$out/restart.txt" || { echo "restart did not stop with SIGINT"; exit 1; }
"$procs" stop demo | tee "$out/stop.txt"
[[ $(grep -c "stopped$" "$out/stop.txt") -eq 6 ]] || { echo "expected 6 processes stopped by SIGINT"; exit 1; }
"$procs" status demo >"$out/status-after.txt" 2>&1 || true
[[ $(grep -c " no$" "$out/status-after.txt") -eq 6 ]] || { cat "$out/status-after.txt"; echo "processes left alive"; exit 1; }
for p in environment eye predictors motivation planner logger; do
  grep -q "stopped" "$logs/demo/$p.log" || { echo "$p's log does not end with its orderly stop"; exit 1; }
done
echo "procs.sh: start, status, run, kill and start, restart, stop: all as documented"
