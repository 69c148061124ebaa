#!/usr/bin/env bash
# scripts/procs.sh start and restart check what they start: a --process
# program that is not there is refused before anything changes (the running
# eye and its command stay); a process running already is not started again;
# one that dies at once is said to have died, with its last lines, and the
# command fails; one is said started once its first STATUS is heard.
#   tests/procs/start_checks.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
source "$root/tests/procs/group.sh"
procs_group 7754
cd "$out"

"$procs" start demo eye >"$out/start.txt" || { cat "$out/start.txt"; exit 1; }
eye=$(cat "$logs/demo/eye.pid")
grep -q "^eye started (pid $eye, heard on the bus" "$out/start.txt" || { cat "$out/start.txt"; echo "start does not say the eye was heard"; exit 1; }

# A typo in --process while the eye runs: refused, and nothing changes.
if "$procs" start demo --process eye=build/bin/afford-eyes eye >"$out/typo.txt" 2>&1; then
  cat "$out/typo.txt"; echo "start took a --process program that is not there"; exit 1
fi
grep -q "build/bin/afford-eyes: not found" "$out/typo.txt" || { cat "$out/typo.txt"; echo "the refusal does not name the program"; exit 1; }
[[ ! -e $logs/demo/eye.process ]] || { echo "the typo'd command was kept for the eye"; exit 1; }
"$procs" status demo >"$out/status.txt"
! grep -q "runs:" "$out/status.txt" || { cat "$out/status.txt"; echo "status shows a command the eye does not run"; exit 1; }
if "$procs" restart demo --process eye=build/bin/afford-eyes eye >"$out/restart-typo.txt" 2>&1; then
  cat "$out/restart-typo.txt"; echo "restart took a --process program that is not there"; exit 1
fi
kill -0 "$eye" 2>/dev/null || { echo "restart stopped the eye before finding its program missing"; exit 1; }

# The eye again while it runs: refused by procs.sh, naming it.
if "$procs" start demo eye >"$out/again.txt" 2>&1; then cat "$out/again.txt"; echo "a second start of a live eye passed"; exit 1; fi
grep -q "eye is running already (pid $eye)" "$out/again.txt" || { cat "$out/again.txt"; echo "the refusal does not name the eye"; exit 1; }

# A program that dies at once: said, with its last lines, and the restart fails.
printf '#!/bin/sh\necho "dies.sh: cannot serve with $*" >&2\nexit 3\n' >"$out/dies.sh"
chmod +x "$out/dies.sh"
if "$procs" restart demo --process eye="$out/dies.sh" eye >"$out/dies.txt" 2>&1; then
  cat "$out/dies.txt"; echo "restart said a process that died at once started"; exit 1
fi
grep -q "eye (pid [0-9]*) exited at once (exit status 3)" "$out/dies.txt" &&
  grep -q "dies.sh: cannot serve with --lcm-url" "$out/dies.txt" ||
  { cat "$out/dies.txt"; echo "the death is not said with its last lines"; exit 1; }
! grep -q "^eye started" "$out/dies.txt" || { cat "$out/dies.txt"; echo "a dead eye was said started"; exit 1; }

# Back to the shipped eye: started once heard.
"$procs" start demo --process eye= eye >"$out/back.txt" || { cat "$out/back.txt"; exit 1; }
grep -q "^eye started (pid $(cat "$logs/demo/eye.pid"), heard on the bus" "$out/back.txt" ||
  { cat "$out/back.txt"; echo "the shipped eye was not said started"; exit 1; }
[[ ! -e $logs/demo/eye.process ]] || { echo "--process eye= kept a command"; exit 1; }
echo "procs.sh start and restart check the program, refuse a live process, and say a death at once"
