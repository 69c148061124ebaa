#!/usr/bin/env bash
# On a terminal, the progress board never erases a line the runner printed:
# `afford experiment` with its progress on, on a pseudo-terminal
# (tests/terminal/pty_screen.py), and the final screen read through a VT100
# emulator must hold every log line printed, in order, and the board's last
# drawing below them.
#   1. in this process (memq), Ctrl-C typed in the middle of the first of two
#      runs: the signal's line and the stop's ("not started: ...", "to resume
#      ...") printed while the board is up;
#   2. on hand-started processes (--attach, udpm in a private network
#      namespace): the eye killed with -9 in the middle of the run and started
#      again, so the runner warns that it "is free again (restarted?)" while
#      the board is up, then Ctrl-C.
#   tests/terminal/test_terminal.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
screen=(/usr/bin/python3 "$root/tests/terminal/pty_screen.py")
common=(--system IMP --steps 4000 --seed 3 --no-reuse-agents --scenarios scenario1 --log-root "$out/logs")

failed=()  # each case runs, whatever the one before showed
echo "1. memq, interrupted during its first run"
"${screen[@]}" "$out/memq.raw" --interrupt-on 'step [1-9][0-9]*/' --expect "afford: stopping the runs under way" \
  --expect "not started: 1 intrinsic run(s)" --expect "to resume" -- \
  "$build/bin/afford" experiment base "${common[@]}" --reps 2 --jobs 1 --extrinsic-reps 1 --transport memq \
  --run-prefix memq --out "$out/memq" || failed+=(memq)

echo "2. attached, the eye killed and started again, then interrupted"
url="udpm://239.255.76.67:7994?ttl=0&recv_buf_size=2097152"
mapfile -t processes < <("$build/bin/afford" processes --phase intrinsic)
declare -A pid
start() { $(process_command "$1" "$url" "$out/logs") >>"$out/$1.log" 2>&1 & pid[$1]=$!; }
for p in "${processes[@]}"; do start "$p"; done
"$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" --state waiting \
  --seconds 30 >/dev/null || { echo "the processes did not all come up"; exit 1; }
# Ctrl-C once the board has been drawn again after the warning (drawn over it, it would be gone).
"${screen[@]}" "$out/attached.raw" --interrupt-on 'free again[\s\S]*step [0-9]+/' --expect "process eye is free again (restarted?)" \
  --expect "afford: stopping the runs under way" --expect "to resume" -- \
  "$build/bin/afford" experiment base "${common[@]}" --reps 1 --extrinsic-reps 0 --attach "$url" \
  --run-prefix attached --out "$out/attached" >"$out/attached.txt" 2>&1 &
checker=$!
# The eye killed once the run is under way (its step on the board), and started again at once.
under_way() { grep -a -o -E "step [0-9]+/" "$out/attached.raw" 2>/dev/null | awk -F'[ /]' '$2 >= 300 {f = 1} END {exit !f}'; }
wait_until 60 under_way || { cat "$out/attached.txt"; echo "the attached run never got under way"; exit 1; }
kill -9 "${pid[eye]}"
wait "${pid[eye]}" 2>/dev/null || true
start eye
wait "$checker" || failed+=(attached)
cat "$out/attached.txt"
((${#failed[@]} == 0)) || { echo "lines erased from the screen in: ${failed[*]}"; exit 1; }
