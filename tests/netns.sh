# Sourced by the shell tests that put a live run on a bus of their own
# (tests/spy, viewer, attach, procs, restart, hostile, loss, hosts, logger, replay).
#
# enter_mount_namespace "$0" "$@": re-runs the calling script in a mount namespace of its own, where there can
# be one (root); in a chroot, whose root is not a mount point, there cannot, and the script goes on where it is
# (it mounts where it runs and unmounts when it ends).
enter_mount_namespace() {
  if [[ -z ${AFFORD_TEST_MOUNTNS:-} ]] && unshare --mount true 2>/dev/null; then
    exec unshare --mount env AFFORD_TEST_MOUNTNS=1 bash "$@"
  fi
}

# enter_private_netns "$0" "$@": re-runs the calling script in a private
# network namespace (root), with multicast routed over its loopback, so no
# datagram leaves the machine. Background jobs are killed when the script ends.
enter_private_netns() {
  if [[ -z ${AFFORD_TEST_NETNS:-} ]]; then
    exec unshare --net env AFFORD_TEST_NETNS=1 bash "$@"
  fi
  ip link set lo up multicast on
  ip route add 224.0.0.0/4 dev lo
  trap 'kill $(jobs -p) 2>/dev/null || true' EXIT
}

# enter_test "$0" "$@": the start of a test called as SCRIPT BUILD_DIR WORK_DIR
# [...]. Re-runs it in a private network namespace, then sets `build` and
# `out` (WORK_DIR, emptied) to absolute paths.
enter_test() {
  enter_private_netns "$@"
  build=$(cd "$2" && pwd)
  rm -rf "$3" && mkdir -p "$3"
  out=$(cd "$3" && pwd)
}

# process_command PROCESS URL ROOT: the command that starts PROCESS on URL
# with every folder it writes in ROOT (the logger's logs, the predictors'
# checkpoints, everyone's snapshots): the same before and after a kill.
process_command() {
  case $1 in
    logger) echo "$build/bin/afford-logger --lcm-url $2 --log-dir $3 --state-dir $3" ;;
    predictors) echo "$build/bin/afford-predictors --lcm-url $2 --checkpoint-dir $3 --state-dir $3" ;;
    *) echo "$build/bin/afford-$1 --lcm-url $2 --state-dir $3" ;;
  esac
}

# show_why LABEL DETAIL: after a failed run, what the runner said (the last
# lines of $out/attached.txt) and each process of "${processes[@]}" (its
# last warnings and errors in $out/<process>.log), so a CI log shows why.
show_why() {
  local p
  echo "--- diagnostics ($1): $2"
  tail -n 15 "$out/attached.txt" 2>/dev/null || true
  for p in "${processes[@]}"; do
    grep -h -E "\] \[(warning|error|critical)\]" "$out/$p.log" 2>/dev/null | tail -n 6 | sed "s/^/$p: /" || true
  done
}

# wait_until SECONDS COMMAND...: returns as soon as COMMAND succeeds, or 1
# after SECONDS. For conditions no event announces (a line in a file); the
# processes on a bus are waited for with `afford status --wait-for`.
wait_until() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    ((SECONDS < deadline)) || return 1
    read -r -t 0.02 <> <(:) || true  # a short pause between tries
  done
}

# start_xvfb WIDTHxHEIGHT LOGFILE: an X server on a display it finds free (so that tests can run at once); exports
# DISPLAY.
start_xvfb() {
  Xvfb -displayfd 3 -screen 0 "${1}x24" -nolisten tcp 3>"$2.display" >"$2" 2>&1 &
  wait_until 10 grep -q '^[0-9]' "$2.display" || { echo "Xvfb did not start (see $2)" >&2; return 1; }
  export DISPLAY=:$(head -n 1 "$2.display")
}

# summary_results DIR: DIR/summary.json without what the clock, the host or
# the paths decide (wall times, speeds, memory, log sizes and folders, run
# ids, versions): two experiments with the same results print the same.
summary_results() {
  # (how the runs were hosted: the processes' peak memory, the commands swapped in with --process)
  awk '/"(peak_rss_kb|processes)": \{\}/ {next} /"(peak_rss_kb|processes)": \{/ {skip=1; next} skip && /\}/ {skip=0; next} !skip' "$1/summary.json" |
    grep -v -E '"(wall_seconds|run_seconds|steps_per_second|log_bytes|log_bytes_per_step|log_dir|checkpoint|transport|network|afford_version|run_id)"'
}

# same_results A B: the summary and every CSV file of experiment folders A and
# B are equal (an extrinsic test's wall time aside); else says what differs.
same_results() {
  local a=$1 b=$2 f name
  if ! diff <(summary_results "$a") <(summary_results "$b") >"$b.summary.diff"; then
    head -30 "$b.summary.diff"
    echo "the summary in $b differs from the one in $a"
    return 1
  fi
  for f in "$a"/*.csv; do
    name=$(basename "$f")
    if [[ $name == extrinsic_* ]]; then
      cmp -s <(sed 's/,[^,]*$//' "$f") <(sed 's/,[^,]*$//' "$b/$name") || { echo "$name differs"; return 1; }
    else
      cmp -s "$f" "$b/$name" || { echo "$name differs"; return 1; }
    fi
  done
}
