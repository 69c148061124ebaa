# Sourced, after tests/netns.sh and enter_test, by the shell tests that run a
# group of hand-started processes on one bus and compare an undisturbed
# experiment with a disturbed one (tests/hostile, fragments, forgeries, keyed).
# Uses `build`, `out` and `url`; `processes` is the registry's.
#
# group_start LABEL [ARGS...]: every process on $url, with ARGS; the group's
#   roots are $out/LABEL-logs (the logger's --log-dir, the predictors'
#   --checkpoint-dir, everyone's --state-dir: an experiment's --log-root); each one's output in
#   $out/LABEL-<process>.log, its pid in pid[<process>].
#   With GROUP_LIMIT_KB, each runs with its address space capped (ulimit -v).
#   Returns once every process has said it is free (afford status --wait-for;
#   on a keyed bus, $AFFORD_BUS_KEY names the key).
# GROUP_EXTRA: names of the test's own processes beside the group (e.g. the
#   viewer): a function group_extra_start LABEL, if the test defines one,
#   starts them (setting pid[NAME]) before group_start waits; group_stop and
#   group_errors treat them as the group's.
# group_stop LABEL: each process (and each of GROUP_EXTRA) must be
#   alive: its peak memory (VmHWM, kB) goes to peak[LABEL-<process>], what is
#   resident (VmRSS) to resident[...], then it gets SIGINT; returns 1, naming
#   them, if some were not alive.
# group_errors LABEL: the last error lines of each one's output.
# group_diagnose LABEL NOTE FILE...: on a failing exit, NOTE, the tail of each
#   FILE and LABEL's error lines (and background jobs are killed either way).
# group_undisturbed [ARGS...]: the group `clean` (ARGS as group_start's) runs
#   the caller's `experiment clean`, then stops.
mapfile -t processes < <("$build/bin/afford" processes)
declare -A pid peak resident
GROUP_EXTRA=()  # processes of the tests' own beside the group (e.g. the viewer)

group_start() {
  local label=$1 p
  shift
  for p in "${processes[@]}"; do
    local extra=()
    [[ $p == logger ]] && extra=(--log-dir "$out/$label-logs")
    [[ $p == predictors ]] && extra=(--checkpoint-dir "$out/$label-logs")
    extra+=(--state-dir "$out/$label-logs")
    if [[ -n ${GROUP_LIMIT_KB:-} ]]; then
      (ulimit -v "$GROUP_LIMIT_KB" && exec "$build/bin/afford-$p" --lcm-url "$url" "$@" "${extra[@]}") \
        >>"$out/$label-$p.log" 2>&1 &
    else
      "$build/bin/afford-$p" --lcm-url "$url" "$@" "${extra[@]}" >>"$out/$label-$p.log" 2>&1 &
    fi
    pid[$p]=$!
  done
  if declare -F group_extra_start >/dev/null; then group_extra_start "$label"; fi
  "$build/bin/afford" status --lcm-url "$url" --wait-for "$(IFS=,; echo "${processes[*]}")" \
    --state waiting --seconds 30 >/dev/null || { echo "the processes did not come up"; return 1; }
}

group_stop() {
  local label=$1 dead=0 p
  for p in "${processes[@]}" "${GROUP_EXTRA[@]}"; do
    if ! kill -0 "${pid[$p]}" 2>/dev/null; then
      echo "process $p is not alive after the $label experiment (exit status $(wait "${pid[$p]}" 2>/dev/null; echo $?))"
      tail -n 3 "$out/$label-$p.log"
      dead=1
      continue
    fi
    peak[$label-$p]=$(awk '/VmHWM/ {print $2}' "/proc/${pid[$p]}/status")
    resident[$label-$p]=$(awk '/VmRSS/ {print $2}' "/proc/${pid[$p]}/status")
    kill -INT "${pid[$p]}"
  done
  wait 2>/dev/null || true
  return $dead
}

group_errors() {
  local label=$1 p
  for p in "${processes[@]}" "${GROUP_EXTRA[@]}"; do
    grep -h -E "\] \[(error|critical)\]" "$out/$label-$p.log" 2>/dev/null | tail -n 4 | sed "s/^/$p: /" || true
  done
}

group_diagnose() {
  GROUP_DIAGNOSE=("$@")
  trap group_on_exit EXIT
}
group_on_exit() {
  local rc=$?
  kill $(jobs -p) 2>/dev/null || true
  ((rc == 0)) && return
  echo "--- diagnostics (${GROUP_DIAGNOSE[1]})"
  tail -n 8 "${GROUP_DIAGNOSE[@]:2}" 2>/dev/null || true
  group_errors "${GROUP_DIAGNOSE[0]}"
}

group_undisturbed() {
  group_start clean "$@" || exit 1
  experiment clean || { cat "$out/clean.txt"; echo "the undisturbed experiment failed"; exit 1; }
  group_stop clean || exit 1
}

