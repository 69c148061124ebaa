#!/usr/bin/env bash
# lcm-spy on a live run, under Xvfb: every message on every channel decodes
# with the project's types (as lcm-spy decodes them), and a screenshot of the
# spy window is kept as a test artefact. The bus is keyed (docs/security.md),
# as the groups of scripts/procs.sh are: the tags that trail every message do
# not keep lcm-spy from decoding them.
#   tests/spy/test_spy.sh BUILD_DIR ARTEFACT_DIR
# Runs in a private network namespace of its own (root), so its multicast
# stays on this machine's loopback.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
# Without a display, spy.sh says so and how to get one (no Java stack trace).
set +e
DISPLAY= "$root/scripts/spy.sh" "udpm://239.255.76.67:7990?ttl=0" >"$out/no-display.log" 2>&1
code=$?
set -e
cat "$out/no-display.log"
[[ $code -eq 2 ]] && grep -q "no display (DISPLAY is not set)" "$out/no-display.log" &&
  grep -q "xvfb-run" "$out/no-display.log" && ! grep -q "Exception" "$out/no-display.log" ||
  { echo "spy.sh without a display: exit $code"; exit 1; }
start_xvfb 1280x900 "$out/xvfb.log"

port=7990
url="udpm://239.255.76.67:$port?ttl=0"
"$build/bin/afford" bus-key "$out/bus.key" >/dev/null
export AFFORD_BUS_KEY=$out/bus.key  # the runner, the processes it starts, afford status

"$root/scripts/spy.sh" "$url" >"$out/spy.log" 2>&1 &
# SpyCheck listens until the runs below are over (this script closes its standard input then), or 120 s.
mkfifo "$out/spycheck.in"
java -cp "$build/share/afford-lcmtypes.jar:$build/share/afford-spycheck.jar:/usr/share/java/lcm.jar" \
  SpyCheck "$url" 120 \
  RUN_CONFIG,RUN_CONTROL,STATUS,SCENE,FOCUS,PREDICTION,DECISION,EFFECT,AFFORDANCE_TABLE,RESULT,LOOK,FORWARD_QUERY,FORWARD_PREDICTION,EXTRINSIC_RESULT,GOAL,GOAL_RESULT \
  <"$out/spycheck.in" >"$out/decoded.txt" 2>&1 &
check=$!
exec 3>"$out/spycheck.in"
# The listeners are up before the run's first message: SpyCheck says so, and lcm-spy's window is mapped.
wait_until 60 grep -q "^listening on" "$out/decoded.txt" || { cat "$out/decoded.txt"; echo "SpyCheck never listened"; exit 1; }
wait_until 60 bash -c 'xwininfo -root -tree | grep -qi "spy"' || { cat "$out/spy.log"; echo "lcm-spy never showed its window"; exit 1; }
# An intrinsic run and one extrinsic test on that bus, in this namespace.
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 3000 --extrinsic-reps 1 --scenarios scenario3 \
  --netns off --base-port "$port" --keep-logs none --quiet --out "$out/run" --log-root "$out/logs" \
  --run-prefix spy >"$out/run.log" 2>&1 &
run=$!
# Mid-run: once the environment runs the run.
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null ||
  { cat "$out/run.log"; echo "the run never started"; exit 1; }
import -window root "$out/spy-during-run.png"
wait "$run" || { echo "the run failed:"; cat "$out/run.log"; exit 1; }
# A short run of the agent that sets its own goals: GOAL and GOAL_RESULT on the bus too.
"$build/bin/afford" experiment base --system GOALS --reps 1 --steps 300 --netns off --base-port "$port" \
  --keep-logs none --quiet --out "$out/goals" --log-root "$out/logs" --run-prefix spy >"$out/goals.log" 2>&1 ||
  { echo "the goals run failed:"; cat "$out/goals.log"; exit 1; }
exec 3>&-
status=0
wait "$check" || status=$?
import -window root "$out/spy.png"
cat "$out/decoded.txt"
[[ $status -eq 0 ]] || { echo "some channel was not decoded or not heard"; exit 1; }
# The screenshot shows a window, not a blank screen.
sd=$(convert "$out/spy.png" -colorspace Gray -format '%[fx:standard_deviation]' info:)
echo "screenshot: $out/spy.png (grey standard deviation $sd)"
awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "the screenshot is blank"; exit 1; }
