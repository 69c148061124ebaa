#!/usr/bin/env bash
# Two copies of one process on a scripts/procs.sh group: a second eye started
# by hand is refused at once (it exits 1 naming the first's pid and host) and
# the first names it in its output; two `procs.sh start demo eye` at once
# start one eye, and the other is refused naming it (the pid file names the
# live one); a copy started during a run is refused and the run's weights are
# an undisturbed run's.
#   tests/procs/copies.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
source "$root/tests/procs/group.sh"
procs_group 7752
steps=1500
start_beside_reference "$steps" || exit 1
url=$(cat "$logs/demo/lcm-url")
# copy LABEL: a second eye by hand on the group's bus (its key from procs.sh exec); must exit 1 within 15 s.
copy() {
  local rc=0
  timeout 15 "$procs" exec demo "$build/bin/afford-eye" --lcm-url "$url" --state-dir "$logs" >"$out/$1.txt" 2>&1 || rc=$?
  ((rc == 1)) || { tail -n 5 "$out/$1.txt"; echo "$1: a second eye on the group's bus: exit status $rc, not 1 (refused)"; return 1; }
}

# By hand: refused at once, naming the first; the first names it.
eye=$(cat "$logs/demo/eye.pid")
copy copy1
grep -q "another copy of eye serves this bus: pid $eye on host $host, started earlier; this one (pid [0-9]* on host $host) refuses to serve" \
  "$out/copy1.txt" || { cat "$out/copy1.txt"; echo "the copy does not name the eye it found"; exit 1; }
second=$(grep -Eo "this one \(pid [0-9]+" "$out/copy1.txt" | head -1 | grep -Eo "[0-9]+$")
wait_until 5 grep -q "another copy of eye on this bus: pid $second on host $host, started later (it refuses to serve)" \
  "$logs/demo/eye.log" || { tail -n 5 "$logs/demo/eye.log"; echo "the first eye does not name its copy"; exit 1; }
kill -0 "$eye" || { echo "the first eye did not survive its copy"; exit 1; }

# procs.sh start twice at once: they take turns (the group's lock, held here first as another procs.sh would
# hold it, so that both are surely at it together); one eye starts, the other start is refused naming it.
"$procs" stop demo eye >/dev/null
stopped=$(cat "$logs/demo/eye.pid")
exec {held}>>"$logs/demo/procs.lock"
flock "$held"
twice=()
for k in 1 2; do
  (exec {held}>&- && rc=0 && "$procs" start demo eye >"$out/twice$k.txt" 2>&1 || rc=$?; echo $rc >"$out/twice$k.rc") &
  twice+=($!)
done
both_wait() { grep -qs "waiting for it" "$out/twice1.txt" && grep -qs "waiting for it" "$out/twice2.txt"; }
waited=0 still=0
wait_until 10 both_wait && waited=1
[[ $(cat "$logs/demo/eye.pid") == "$stopped" ]] && still=1
exec {held}>&-  # (released before anything fails: the test's end stops the group through procs.sh)
((waited)) || { cat "$out"/twice*.txt; echo "two starts at once do not wait for the group's lock"; exit 1; }
((still)) || { echo "an eye was started while the group's lock was held"; exit 1; }
wait "${twice[@]}"
started=$(cat "$out"/twice*.txt | grep -c "^eye started (pid ") || true
eye=$(cat "$logs/demo/eye.pid")
[[ $started -eq 1 ]] || { cat "$out"/twice*.txt; echo "two procs.sh start demo eye at once: $started eyes said started"; exit 1; }
grep -q "eye is running already (pid $eye)" "$out"/twice*.txt ||
  { cat "$out"/twice*.txt; echo "the second start does not name the eye the first started"; exit 1; }
[[ $(cat "$out"/twice*.rc | sort | tr '\n' ' ') == "0 1 " ]] || { echo "exit statuses: $(cat "$out"/twice*.rc)"; exit 1; }
"$procs" status demo >"$out/status.txt"
grep -Eq "^eye +$eye  yes$" "$out/status.txt" || { cat "$out/status.txt"; echo "the pid file does not name the live eye"; exit 1; }
[[ $(grep -Ec "^eye +[0-9]+  (waiting|ready|running)" "$out/status.txt") -eq 1 ]] ||
  { cat "$out/status.txt"; echo "not one eye on the bus"; exit 1; }

# During a run: the copy is refused, the run goes on as an undisturbed one.
wait "$reference" || exit 1
"$procs" run demo base --system FIX --reps 1 --steps "$steps" --seed 2 --quiet --run-prefix cp --out "$out/run" \
  >"$out/run.txt" 2>&1 &
runner=$!
"$procs" status demo --wait-for eye --step 100 --seconds 60 >/dev/null || { cat "$out/run.txt"; echo "the run did not start"; exit 1; }
copy copy2
grep -q "another copy of eye serves this bus: pid $eye on host $host" "$out/copy2.txt" ||
  { cat "$out/copy2.txt"; echo "the copy during the run does not name the eye"; exit 1; }
wait "$runner" || { cat "$out/run.txt"; echo "the run with a copy of the eye started during it failed"; exit 1; }
[[ $(checksum "$out/run") == "$(cat "$out/undisturbed.sum")" ]] || { echo "the weights differ from an undisturbed run's"; exit 1; }
echo "a second copy of a process is refused at once, named by both; two starts at once start one"
