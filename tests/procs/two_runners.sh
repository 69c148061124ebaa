#!/usr/bin/env bash
# Two runners on one scripts/procs.sh group (two terminals): the second is
# refused at once, naming the first (its pid, host and run), and the first
# goes on undisturbed: its weights are an undisturbed run's. Once one after
# the other (the first mid-run), once both started together (then the one
# started later is refused, whichever it is).
#   tests/procs/two_runners.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
source "$root/tests/procs/group.sh"
procs_group 7751
steps=1500
start_beside_reference "$steps" || exit 1
run() {  # PREFIX: a run on the group, its output in $out/PREFIX.txt
  "$procs" run demo base --system FIX --reps 1 --steps "$steps" --seed 2 --quiet --no-reuse-agents --run-prefix "$1" \
    --out "$out/$1" >"$out/$1.txt" 2>&1
}
# refused FILE PREFIX [alive]: FILE says the runner was refused because of the runner of PREFIX (alive: that
# runner, still running, is the pid named).
refused() {
  local said pid
  said=$(grep -Eo "another runner \(pid [0-9]+ on host $host, run $2-base-FIX-s2\) is driving this bus; wait for it to \
finish or use another group" "$1" | head -1)
  [[ -n $said ]] || { cat "$1"; echo "the refusal does not name the runner of $2"; return 1; }
  pid=$(grep -Eo "pid [0-9]+" <<<"$said" | grep -Eo "[0-9]+")
  [[ ${3:-} != alive ]] || tr '\0' ' ' <"/proc/$pid/cmdline" | grep -q -- "--run-prefix $2" ||
    { echo "pid $pid is not the runner of $2"; return 1; }
}

# One after the other: the second comes while the first is mid-run.
run ra &
first=$!
"$procs" status demo --wait-for eye --step 100 --seconds 60 >/dev/null || { cat "$out/ra.txt"; echo "the first run did not start"; exit 1; }
if run rb; then cat "$out/rb.txt"; echo "the second runner drove the group the first drives"; exit 1; fi
kill -0 "$first" 2>/dev/null || { cat "$out/rb.txt"; echo "the first run ended before the second was refused: nothing tried"; exit 1; }
refused "$out/rb.txt" ra alive
wait "$first" || { cat "$out/ra.txt"; echo "the first run failed"; exit 1; }
! grep -q "free again" "$out/ra.txt" || { cat "$out/ra.txt"; echo "the first runner's processes were disturbed"; exit 1; }
wait "$reference" || exit 1
want=$(cat "$out/undisturbed.sum")
[[ $(checksum "$out/ra") == "$want" ]] || { echo "the first run's weights differ from an undisturbed run's"; exit 1; }
[[ ! -e $out/logs/rb-base-FIX-s2/log.00.lcm ]] || { echo "the refused runner's run was recorded"; exit 1; }

# Together: the later one is refused, naming the other; the other's run is undisturbed.
run rc &
c=$!
run rd &
d=$!
rc_c=0 rc_d=0
wait "$c" || rc_c=$?
wait "$d" || rc_d=$?
if ((rc_c == 0 && rc_d != 0)); then
  winner=rc
  refused "$out/rd.txt" rc || { cat "$out/rd.txt"; echo "rd failed without naming the runner of rc"; exit 1; }
elif ((rc_d == 0 && rc_c != 0)); then
  winner=rd
  refused "$out/rc.txt" rd || { cat "$out/rc.txt"; echo "rc failed without naming the runner of rd"; exit 1; }
else
  cat "$out/rc.txt" "$out/rd.txt"
  echo "two runners started together: exit statuses $rc_c and $rc_d (one must be refused, the other complete)"
  exit 1
fi
[[ $(checksum "$out/$winner") == "$want" ]] || { echo "the run of $winner has weights other than an undisturbed run's"; exit 1; }
echo "a second runner on the group is refused, naming the first; the first is undisturbed ($winner won the start together)"
