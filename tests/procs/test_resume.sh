#!/usr/bin/env bash
# An experiment on a scripts/procs.sh group, stopped as Ctrl-C stops it (SIGINT to the runner's process group),
# goes on with the command its runner printed, run as printed, and ends with an uninterrupted experiment's
# results. Before that, a resume that cannot reach the group (the runner alone, without the group's key) stops
# at once: no run is marked done, the experiment stays resumable, and the line names the command that works.
# Then `procs.sh run` on a group that is down is refused, and a run attached by hand to a bus nobody serves
# names the bus options it was given (URL, key file, named network namespace; never the key).
#   tests/procs/test_resume.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
mkdir -p "$out/checkout/scripts"
ln -s "$root/scripts/procs.sh" "$out/checkout/scripts/procs.sh"
unset AFFORD_LOGS AFFORD_BUS_KEY AFFORD_RESUME_WITH
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_GRACE=3
procs=$out/checkout/scripts/procs.sh
cd "$out"
trap 'kill $(jobs -p) 2>/dev/null || true; "$procs" kill demo environment eye predictors motivation logger >/dev/null 2>&1 || true' EXIT
fail() { echo "$*"; exit 1; }
state() { grep -o '"state": "[a-z]*"' "$1/experiment.json"; }
kept() { find "$1/runs" -name '*.json' 2>/dev/null | wc -l; }
# The last "to resume (in DIR): COMMAND" line of a file, as DIR<tab>COMMAND.
resume_line() { sed -n 's/.*to resume (in \(.*\)): \(.*\)$/\1\t\2/p' "$1" | tail -1; }
# OUT COMMAND...: runs the experiment of folder OUT (its output in OUT.txt) and stops it as Ctrl-C does (SIGINT
# to its process group) once its first run's outcome is kept (the second has begun, or is about to); it must
# exit 130. Sets `where` and `command` from its resume line.
interrupt_after_first() {
  local dir=$1 code=0 runner
  shift
  setsid "$@" --quiet --progress lines --out "$dir" >"$dir.txt" 2>&1 &
  runner=$!
  wait_until 60 compgen -G "$dir/runs/*.json" >/dev/null || { cat "$dir.txt"; fail "no run of $dir finished"; }
  kill -INT -- "-$runner"
  wait "$runner" || code=$?
  [[ $code -eq 130 ]] || { cat "$dir.txt"; fail "the runner of $dir exited $code after SIGINT, not 130"; }
  IFS=$'\t' read -r where command <<<"$(resume_line "$dir.txt")"
}

# The runs' own setting (in every experiment below): 3 s for the processes to say they are free, not 15.
experiment=(base --system FIX --reps 2 --steps 600 --seed 5 --set protocol.ready_timeout_ms=3000)
"$procs" start demo environment eye predictors motivation logger >/dev/null
"$procs" status demo --wait-for environment,eye,predictors,motivation,logger --state waiting --seconds 30 >/dev/null

interrupt_after_first "$out/run" "$procs" run demo "${experiment[@]}"
expected="AFFORD_NETNS=none AFFORD_BIN=$build/bin $procs run demo --resume --out $out/run"
[[ $where == "$out" && $command == "$expected" ]] ||
  { cat "$out/run.txt"; fail "the resume line says '$command' (in $where), not '$expected' (in $out)"; }
done_before=$(kept "$out/run")
[[ $done_before -eq 1 ]] || fail "$done_before run(s) kept at the interruption, not 1"

# The trap of issue 55: the runner alone, without the group's key. It cannot reach the processes: no run is
# marked done, the experiment stays resumable, and it says so with the command that works.
code=0
"$build/bin/afford" experiment --resume --out "$out/run" --quiet --progress lines >"$out/alone.txt" 2>&1 || code=$?
[[ $code -eq 1 ]] || { cat "$out/alone.txt"; fail "a resume that reaches no process exited $code, not 1"; }
grep -q "no process of this name reported free for a run within 3.00 s.*the run did not begin" "$out/alone.txt" &&
  grep -q "stopped during the intrinsic phase: processes not reached" "$out/alone.txt" ||
  { cat "$out/alone.txt"; fail "the resume does not say that the processes were not reached"; }
[[ $(resume_line "$out/alone.txt") == "$out"$'\t'"$expected" ]] ||
  { cat "$out/alone.txt"; fail "the resume that reached nothing does not name the group's resume command"; }
[[ $(state "$out/run") == '"state": "interrupted"' && $(kept "$out/run") -eq $done_before ]] ||
  fail "the resume that reached nothing marked runs or the experiment done: $(state "$out/run"), $(kept "$out/run") kept"

# The command as printed, from where it says, with nothing of this script's environment it does not give.
(cd "$where" && env -u AFFORD_NETNS -u AFFORD_BIN -u AFFORD_GRACE bash -c "$command") >"$out/resume.txt" 2>&1 ||
  { cat "$out/resume.txt"; fail "the printed resume command failed"; }
[[ $(state "$out/run") == '"state": "finished"' && $(kept "$out/run") -eq 2 ]] || fail "the resumed experiment did not finish"
"$build/bin/afford" experiment "${experiment[@]}" --transport memq --jobs 2 --keep-logs none --quiet --run-prefix demo \
  --out "$out/whole" --log-root "$out/whole-logs" >"$out/whole.txt" 2>&1 || { cat "$out/whole.txt"; fail "the uninterrupted experiment failed"; }
same_results "$out/whole" "$out/run" || fail "the resumed experiment's results are not the uninterrupted one's"
grep -q '"weights_checksum": "[0-9a-f]\{16\}"' "$out/run/summary.json" || fail "no checksum in the summary"

# The same group driven by the runner alone, given its bus and key: interrupted, its printed command (the bus
# options it was given) goes on to the end.
group=$out/checkout/logs/demo
interrupt_after_first "$out/hand" "$build/bin/afford" experiment "${experiment[@]}" --attach "$(cat "$group/lcm-url")" \
  --bus-key "$group/bus.key" --run-prefix hand --no-reuse-agents --log-root "$out/checkout/logs"
[[ $command == *" --attach '$(cat "$group/lcm-url")' --bus-key $group/bus.key --resume --out $out/hand" ]] ||
  { cat "$out/hand.txt"; fail "the attached run's resume line lacks its bus options: $command"; }
(cd "$where" && bash -c "$command") >"$out/hand-resume.txt" 2>&1 || { cat "$out/hand-resume.txt"; fail "its printed command failed"; }
[[ $(state "$out/hand") == '"state": "finished"' && $(kept "$out/hand") -eq 2 ]] || fail "the attached experiment did not finish"

# A group that is down: refused before anything runs.
"$procs" stop demo >/dev/null
code=0
"$procs" run demo "${experiment[@]}" --out "$out/down" >"$out/down.txt" 2>&1 || code=$?
[[ $code -ne 0 ]] && grep -q "group 'demo' is not up: none of its processes runs" "$out/down.txt" &&
  [[ ! -e $out/down ]] || { cat "$out/down.txt"; fail "procs.sh run on a stopped group was not refused"; }

# Attached by hand, in a named network namespace, to a bus nobody serves: the experiment stops at once,
# resumable, and its resume line carries the namespace, the URL and the key file. The namespace is made in a
# mount namespace of its own, so that the machine's /run/netns does not see it; in a chroot (whose root is not
# a mount point) there is none, and it is one of the machine's, removed at once.
"$build/bin/afford" bus-key "$out/hand.key" >/dev/null
bare="udpm://239.255.76.67:7993?ttl=0"
cat >"$out/bare.sh" <<SH
ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo &&
  exec $build/bin/afford experiment base --system FIX --reps 1 --steps 100 --set protocol.ready_timeout_ms=1000 \
    --attach "$bare" --bus-key $out/hand.key --keep-logs none --run-prefix bare --log-root $out/bare-logs \
    --out $out/bare --quiet --progress lines
SH
code=0
if unshare -m true 2>/dev/null; then
  ns=t
  unshare -m bash -c "mount -t tmpfs tmpfs /run && ip netns add $ns && ip netns exec $ns bash $out/bare.sh" \
    >"$out/bare.txt" 2>&1 || code=$?
else  # (entered with nsenter: `ip netns exec` remounts /, which a chroot cannot)
  ns=afford-resume-test-$$
  ip netns add "$ns"
  nsenter --net="/run/netns/$ns" bash "$out/bare.sh" >"$out/bare.txt" 2>&1 || code=$?
  ip netns delete "$ns"
fi
[[ $code -eq 1 ]] || { cat "$out/bare.txt"; fail "an attached run that reaches no process exited $code, not 1"; }
expected="ip netns exec $ns $build/bin/afford experiment --attach '$bare' --bus-key $out/hand.key --resume --out $out/bare"
[[ $(resume_line "$out/bare.txt") == "$out"$'\t'"$expected" ]] ||
  { cat "$out/bare.txt"; fail "the attached run's resume line is not '$expected'"; }
grep -q "$(cat "$out/hand.key")" "$out/bare.txt" "$out/bare/experiment.json" && fail "the key itself was printed or stored"
[[ $(state "$out/bare") == '"state": "interrupted"' && $(kept "$out/bare") -eq 0 ]] ||
  fail "the attached run that reached nothing was marked done: $(state "$out/bare")"
echo "an experiment on a group resumes with the command it printed, and a resume that reaches nothing marks nothing done"
