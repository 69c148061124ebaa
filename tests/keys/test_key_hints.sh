#!/usr/bin/env bash
# What an operator is told when a key, an address or a URL is wrong (issue 55, items 7 and 8), each on a live
# bus in a private network namespace:
#  1. a keyed group heard without its key (by `afford experiment --attach` and `afford status`), with another
#     key, and an unkeyed group heard with one: one line naming the fix, then counts; the runner's wait for
#     free processes names the fix too; no line a message;
#  2. a process killed mid-run and started on another bus (a wrong --lcm-url): the runner says at once that it
#     is not heard, and the progress board waits for it rather than showing a time left;
#  3. a keyed bus's recording (lcm-logger) replayed and explained without the key, and read by the Python
#     package: refused, naming the fix, in one line; with the key it replays;
#  4. a second group (scripts/procs.sh) on the same port with another address: `start` warns of it, and no
#     process of either says anything while both idle (each hears only its own address).
#   tests/keys/test_key_hints.sh BUILD_DIR WORK_DIR
# AFFORD_KEY_HINTS_PARTS: the parts to run (default "1 2 3 4"; 3 needs 2's recording).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
url="udpm://239.255.76.67:7993?ttl=0&recv_buf_size=2097152"
plain_url="udpm://239.255.76.67:7994?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
afford=$build/bin/afford
"$afford" bus-key "$out/bus.key" >/dev/null
"$afford" bus-key "$out/other.key" >/dev/null
tagged="tagged messages heard: this bus is keyed; give --bus-key"
untagged="untagged messages heard: this bus is not keyed (or its publishers lack the key)"
other_key="messages tagged with another key heard"
group_diagnose keyed "key hints" "$out"/attach-*.txt "$out/restart.txt"
parts=" ${AFFORD_KEY_HINTS_PARTS:-1 2 3 4} "
part() { [[ $parts == *" $1 "* ]]; }

# count FILE TEXT: lines of FILE holding TEXT.
count() { grep -c -F -- "$2" "$1" || true; }
# one_line_then_counts FILE HINT: the hint once as a line of its own (the runner's failure may repeat it), no
# line a dropped message, and a handful of lines in all.
one_line_then_counts() {
  local said lines
  said=$(grep -F -- "$2" "$1" | grep -c -F "(first on " || true)
  lines=$(wc -l <"$1")
  if [[ $said != 1 || $(count "$1" "dropped message") != 0 || $(count "$1" "trailing bytes") != 0 || $lines -gt 20 ]]; then
    cat "$1"
    echo "$1: expected the line \"$2\" once, no line a message and a handful of lines ($said, $lines lines)"
    return 1
  fi
}
# attach LABEL URL [ARGS...]: `afford experiment --attach URL` (without $AFFORD_BUS_KEY), which must fail: no
# process is free, by its key.
attach() {
  local label=$1 u=$2
  shift 2
  if env -u AFFORD_BUS_KEY "$afford" experiment base --system IMP --reps 1 --steps 50 --extrinsic-reps 0 --quiet \
    --attach "$u" "$@" --set protocol.ready_timeout_ms=3000 --run-prefix "$label" --out "$out/$label" \
    --log-root "$out/$label-logs" --progress none >"$out/attach-$label.txt" 2>&1; then
    cat "$out/attach-$label.txt"
    echo "$label: the experiment ran on a bus whose key it does not have"
    return 1
  fi
}

export AFFORD_BUS_KEY=$out/bus.key  # (group_start waits for the group with afford status)
if part 1 || part 2; then group_start keyed --bus-key "$out/bus.key"; fi

# ---- 1. keys that do not fit ----------------------------------------------------------------------------------
if part 1; then

attach without-key "$url"
one_line_then_counts "$out/attach-without-key.txt" "$tagged"
grep "no process of this name reported free for a run within" "$out/attach-without-key.txt" | grep -q -F "$tagged" ||
  { cat "$out/attach-without-key.txt"; echo "the runner's wait does not name the key"; exit 1; }

attach other-key "$url" --bus-key "$out/other.key"
one_line_then_counts "$out/attach-other-key.txt" "$other_key"
grep "reported free" "$out/attach-other-key.txt" | grep -q -F "$other_key" ||
  { cat "$out/attach-other-key.txt"; echo "the runner's wait does not name the other key"; exit 1; }

env -u AFFORD_BUS_KEY "$afford" status --lcm-url "$url" --seconds 1.5 >"$out/status-without-key.txt" 2>&1 || true
grep -q -F "($tagged" "$out/status-without-key.txt" && [[ $(count "$out/status-without-key.txt" "dropped message") == 0 ]] ||
  { cat "$out/status-without-key.txt"; echo "afford status without the key does not name it"; exit 1; }

# An unkeyed group heard with a key: the processes first (the group's environment alone is enough).
env -u AFFORD_BUS_KEY "$build/bin/afford-environment" --lcm-url "$plain_url" >"$out/plain-environment.log" 2>&1 &
plain_environment=$!
env -u AFFORD_BUS_KEY "$afford" status --lcm-url "$plain_url" --wait-for environment --seconds 30 >/dev/null
attach with-key "$plain_url" --bus-key "$out/bus.key"
one_line_then_counts "$out/attach-with-key.txt" "$untagged"
grep "reported free" "$out/attach-with-key.txt" | grep -q -F "$untagged" ||
  { cat "$out/attach-with-key.txt"; echo "the runner's wait does not say the bus is not keyed"; exit 1; }
kill -INT "$plain_environment"
fi

# ---- 2. a process restarted on another bus mid-run --------------------------------------------------------------
if part 2; then
lcm-logger --lcm-url="${url%%&*}&recv_buf_size=$(cat /proc/sys/net/core/rmem_max)" -f "$out/recording.lcm" \
  >"$out/lcm-logger.txt" 2>&1 &
recorder=$!
wait_until 30 grep -s -a -q "STATUS" "$out/recording.lcm" || { echo "lcm-logger records nothing"; exit 1; }
"$afford" experiment base --system IMP --reps 1 --steps 6000 --extrinsic-reps 0 --quiet --attach "$url" \
  --bus-key "$out/bus.key" --run-prefix restart --out "$out/restart" --log-root "$out/keyed-logs" \
  --progress lines --progress-every 0.5 >"$out/restart.txt" 2>&1 &
runner=$!
"$afford" status --lcm-url "$url" --wait-for eye --state running --step 300 --seconds 60 >/dev/null ||
  { cat "$out/restart.txt"; echo "the run did not start"; exit 1; }
kill -9 "${pid[eye]}"
killed_at=$SECONDS
"$build/bin/afford-eye" --lcm-url "udpm://239.255.76.67:7995?ttl=0" --bus-key "$out/bus.key" \
  --state-dir "$out/keyed-logs" >"$out/wrong-eye.log" 2>&1 &
wrong_eye=$!
wait_until 10 grep -q "process eye not heard for" "$out/restart.txt" ||
  { cat "$out/restart.txt"; echo "the runner did not say that the eye is not heard"; exit 1; }
said_after=$((SECONDS - killed_at))
grep "process eye not heard for" "$out/restart.txt"
((said_after <= 6)) || { echo "said $said_after s after the kill"; exit 1; }
[[ $(count "$out/restart.txt" "process eye not heard for") == 1 ]] || { cat "$out/restart.txt"; echo "said more than once"; exit 1; }
grep -q -F "check its bus URL" "$out/restart.txt" || { echo "the line does not say where to look"; exit 1; }
wait_until 10 grep -q "waiting for eye" "$out/restart.txt" ||
  { cat "$out/restart.txt"; echo "the progress line does not say that the run waits for the eye"; exit 1; }
waiting_line=$(grep "waiting for eye" "$out/restart.txt" | tail -n 1)
[[ $waiting_line != *" left"* ]] || { echo "a time left while waiting: $waiting_line"; exit 1; }
kill -INT "$runner"
wait "$runner" || true
kill -INT "$wrong_eye"
kill -INT "$recorder"
wait "$recorder" || true
fi
if part 1 || part 2; then group_stop keyed || true; fi

# ---- 3. the keyed bus's recording, without its key --------------------------------------------------------------
if part 3; then
grep -a -q "RUN_CONFIG" "$out/recording.lcm" || { echo "the recording holds no RUN_CONFIG"; exit 1; }
for command in replay explain; do
  if env -u AFFORD_BUS_KEY "$afford" "$command" "$out/recording.lcm" >"$out/$command-without-key.txt" 2>&1; then
    cat "$out/$command-without-key.txt"
    echo "afford $command took a keyed recording without the key"
    exit 1
  fi
  f=$out/$command-without-key.txt
  if [[ $(grep -c -E "\] .*offset [0-9]+: $tagged" "$f" || true) != 1 || $(count "$f" "trailing bytes") != 0 ]] ||
    ! grep -q -F "no RUN_CONFIG that the edge accepts in the log, so nothing says how the run was configured; $tagged" "$f"; then
    cat "$f"
    echo "afford $command of a keyed recording without the key: not one line naming the fix"
    exit 1
  fi
done
PYTHONPATH="$build/python" /usr/bin/python3 - "$out/recording.lcm" "$tagged" <<'PY'
import sys
import afford
try:
    afford.read_log(sys.argv[1])
except Exception as e:
    assert sys.argv[2] in str(e), str(e)
else:
    raise SystemExit("read_log took a keyed recording without the key")
PY
# The recording is of a run interrupted mid-way, by a recorder that may have lost datagrams under load: replay
# says the log is cut (exit 1); with the key, what it holds replays as recorded, and nothing is said of tags.
"$afford" replay "$out/recording.lcm" --bus-key "$out/bus.key" >"$out/replay-with-key.txt" 2>&1 || true
if ! grep -q -E "^decisions: [1-9][0-9]* replayed, [0-9]+ recorded, 0 differing" "$out/replay-with-key.txt" ||
  ! grep -q -F "what it holds replays as recorded" "$out/replay-with-key.txt" ||
  grep -q -E "tagged|without a valid tag of the key: skipped" "$out/replay-with-key.txt"; then
  cat "$out/replay-with-key.txt"
  echo "the recording does not replay with its key"
  exit 1
fi
grep -q "replayed" "$out/replay-with-key.txt" || { cat "$out/replay-with-key.txt"; exit 1; }
fi

# ---- 4. two groups on one port, other addresses -----------------------------------------------------------------
if part 4; then
# The groups' processes are procs.sh's children, not this script's jobs: stopped whatever ends the script, by
# procs.sh, which signals a pid only while it is the process it started (a stopped group's pid files stay, and
# pids are soon reused: 32768 of them on a machine running the suite).
stop_groups() {
  local g
  for g in "$out"/groups/*/; do
    [[ -d $g ]] && "$root/scripts/procs.sh" stop "$(basename "$g")" >/dev/null 2>&1
  done
  return 0
}
trap 'rc=$?; stop_groups; (exit $rc); group_on_exit' EXIT
export AFFORD_NETNS=none AFFORD_LOGS=$out/groups AFFORD_BIN=$build/bin
unset AFFORD_BUS_KEY
AFFORD_URL="udpm://239.255.76.67:7996?ttl=0" "$root/scripts/procs.sh" start ga >"$out/start-ga.txt" 2>&1
AFFORD_URL="udpm://239.255.76.68:7996?ttl=0" "$root/scripts/procs.sh" start gb >"$out/start-gb.txt" 2>&1
grep -q "procs.sh: warning: group 'ga' (running) uses port 7996 too, with address 239.255.76.67" "$out/start-gb.txt" ||
  { cat "$out/start-gb.txt"; echo "procs.sh start did not warn of the group on the same port"; exit 1; }
! grep -q "warning" "$out/start-ga.txt" || { cat "$out/start-ga.txt"; echo "a warning with no other group"; exit 1; }
# Both idle while their processes beat a few times: 60 messages heard on gb's port by Debian's lcm-logger
# (whose liblcm hears both addresses).
lcm-logger --lcm-url="udpm://239.255.76.68:7996?ttl=0" -f "$out/gb.lcm" >"$out/gb-logger.txt" 2>&1 &
gb_logger=$!
beats() { (($(/usr/bin/python3 -c 'import sys; print(open(sys.argv[1], "rb").read().count(b"\xed\xa1\xda\x01"))' "$out/gb.lcm" 2>/dev/null || echo 0) >= 60)); }
wait_until 30 beats || { echo "group gb is not heard on its bus"; exit 1; }
kill -INT "$gb_logger"
for g in ga gb; do
  if grep -h -E "\[(warning|error)\]" "$out/groups/$g"/*.log; then
    echo "a process of group $g said something while both groups idled"
    exit 1
  fi
done
# A third group on ga's very bus: the same warning, saying so.
AFFORD_URL="udpm://239.255.76.67:7996?ttl=0" "$root/scripts/procs.sh" start gc environment >"$out/start-gc.txt" 2>&1
grep -q "procs.sh: warning: group 'ga' (running) is on this same bus (239.255.76.67:7996)" "$out/start-gc.txt" ||
  { cat "$out/start-gc.txt"; echo "procs.sh start did not warn of the group on the same bus"; exit 1; }
for g in ga gb gc; do "$root/scripts/procs.sh" stop "$g" >/dev/null; done
# A pid the groups had, reused by another program once they stopped, is left alone at the script's end.
# (It blocks until a signal ends it; a background job of a script ignores SIGINT, this one does not once it has
# said so in a file.)
perl -e '$SIG{INT} = "DEFAULT"; open(my $f, ">", $ARGV[0]) && close($f); select(undef, undef, undef, undef)' \
  "$out/decoy-ready" &
decoy=$!
wait_until 10 test -e "$out/decoy-ready" || { echo "the stand-in program did not start"; exit 1; }
echo "$decoy" >"$out/groups/ga/eye.pid"
stop_groups
# (Alive, not a zombie: this script has not waited for it.)
[[ $(ps -o stat= -p "$decoy" 2>/dev/null) == [^Z]* ]] ||
  { echo "stopping the stopped groups signalled a program their pid file names"; exit 1; }
kill "$decoy"
fi
echo "every hint said once, at once"
