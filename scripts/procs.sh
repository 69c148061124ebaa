#!/usr/bin/env bash
# Start, stop, restart and watch the processes of a run by hand.
#
#   scripts/procs.sh start   RUN [--process NAME='CMD ARGS']... [PROCESS...]
#                                               start processes (default: all six) on RUN's bus; with
#                                               --process, CMD runs in place of afford-NAME, its standard
#                                               arguments (--lcm-url URL ...) appended, in this start and
#                                               every later one (--process NAME= goes back to the shipped one).
#                                               A process running already is not started again (exit 1); a
#                                               program that is not there is refused before anything; each is
#                                               said started once its first STATUS is heard, or said to have
#                                               exited, with its last lines (exit 1)
#   scripts/procs.sh stop    RUN [PROCESS...]   SIGINT, then SIGTERM after $AFFORD_GRACE s (default 5), then
#                                               SIGKILL
#   scripts/procs.sh restart RUN [--process NAME='CMD ARGS']... PROCESS...
#                                               stop, then start again (with the same command, or CMD)
#   scripts/procs.sh kill    RUN PROCESS...     kill -9 (to try a live restart)
#   scripts/procs.sh status  RUN [OPTIONS]      pid and liveness (yes, no, paused), then what the bus says:
#                                               each process's state, run id and last step handled (its
#                                               STATUS), the runner driving a run and what it waits for, and
#                                               each live process not heard (silent)
#   scripts/procs.sh run     RUN EXPERIMENT [afford experiment options...]
#                                               drive runs on the group (run ids RUN-<exp>-<sys>-s<seed>;
#                                               RUN-2-..., RUN-3-... once those exist; or --run-prefix P);
#                                               refused if none of the group's processes runs
#   scripts/procs.sh run     RUN --resume --out DIR
#                                               continue an interrupted one on the group (its run ids), as
#                                               the runner's "to resume" line says
#   scripts/procs.sh exec    RUN COMMAND...     run a command on RUN's bus (spy, viewer, lcm-logger)
#
# PROCESS: environment eye predictors motivation planner logger.
# Where: a group's folder is LOGS/RUN and its runs' logs and checkpoints are
# LOGS/<run-id>, LOGS being $AFFORD_LOGS, else the checkout's logs/ (an
# installed copy: ./logs). Every process gets LOGS, whatever the current folder:
# the logger as its --log-dir, the predictors as their --checkpoint-dir, and
# each as its --state-dir (its snapshots, which a restart goes on from). Each
# process's output goes to LOGS/RUN/<process>.log
# (appended), its pid to LOGS/RUN/<process>.pid, its command line to
# LOGS/RUN/<process>.cmd (and a --process command to LOGS/RUN/<process>.process);
# the bus to LOGS/RUN/lcm-url. The bus is $AFFORD_URL (default below) at `start`.
# start, stop, restart and kill of a group take turns (a lock, LOGS/RUN/procs.lock): two starts of one process
# at once cannot both start it. A start waits at most $AFFORD_START_SECONDS s (default 30) for the first STATUS.
# A stopped group's folder stays (its key, its processes' output): remove it
# yourself; `afford clean` leaves it alone.
#
# The group's bus is keyed (docs/security.md): `start` makes LOGS/RUN/bus.key
# (a new random key) if there is none, and every process, `status`, `run` and
# `exec` use it, so a process must carry the key's tags to be heard. lcm-spy
# still decodes every channel. AFFORD_PROCS_KEY=off starts a group without a key.
#
# Multicast needs a route. By default the group lives in the named network
# namespace "afford" (created at the first start: loopback only, multicast
# routed over lo), which every terminal can enter, so no datagram leaves the
# machine. AFFORD_NETNS=none uses the current namespace instead (it must
# route 224.0.0.0/4, e.g. inside `unshare --net`). The namespace stays after
# `stop` (other groups may use it); once no group runs, `ip netns delete
# afford` removes it (the next `start` makes it again).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if [[ -f $root/config/defaults.yaml && -x $root/../../bin/afford && ! -d $root/build ]]; then
  # an installed copy (cmake --install): <prefix>/share/afford/scripts; the binaries in <prefix>/bin, logs here
  bin=${AFFORD_BIN:-$(cd "$root/../../bin" && pwd)}
  logs=${AFFORD_LOGS:-$PWD/logs}
else
  bin=${AFFORD_BIN:-$root/build/bin}
  logs=${AFFORD_LOGS:-$root/logs}
fi
# One folder whatever the current one: every process gets it (its logs, checkpoints and snapshots), so a
# process started or restarted from anywhere finds its snapshot of the run.
[[ $logs == /* ]] || logs=$PWD/$logs
netns=${AFFORD_NETNS:-afford}
grace=${AFFORD_GRACE:-5}
start_seconds=${AFFORD_START_SECONDS:-30}
mapfile -t all < <("$bin/afford" processes)  # the registry of processes

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 2; }
die() { echo "procs.sh: $*" >&2; exit 1; }
[[ $# -ge 2 ]] || usage
cmd=$1 run=$2
shift 2
[[ $run =~ ^[A-Za-z0-9_-][A-Za-z0-9._-]*$ ]] || die "run id '$run': use letters, digits, '.', '_' or '-' (not first '.')"
dir=$logs/$run
key=$dir/bus.key
# The group's key, for every command that speaks on its bus (processes read $AFFORD_BUS_KEY).
[[ -f $key && ${AFFORD_PROCS_KEY:-on} != off ]] && export AFFORD_BUS_KEY=$key

in_ns() {  # run "$@" in the group's namespace
  if [[ $netns == none ]]; then "$@"; else ip netns exec "$netns" "$@"; fi
}
ensure_ns() {
  [[ $netns == none ]] && return 0
  if ! ip netns list | grep -qw "^$netns"; then
    ip netns add "$netns" || die "cannot create network namespace '$netns' (root needed; or AFFORD_NETNS=none)"
  fi
  ip netns exec "$netns" ip link set lo up multicast on
  ip netns exec "$netns" ip route replace 224.0.0.0/4 dev lo
}
check_process() {
  local p
  for p in "${all[@]}"; do [[ $1 == "$p" ]] && return 0; done
  die "unknown process '$1' (one of: ${all[*]})"
}
url() { [[ -f $dir/lcm-url ]] || die "no group '$run' (scripts/procs.sh start $run first)"; cat "$dir/lcm-url"; }
# stat PID: the fields of /proc/PID/stat after the command's name (which may hold spaces): state first,
# then the 20th, the start time since boot.
stat_of() { local s; s=$(cat "/proc/$1/stat" 2>/dev/null) || return 1; echo "${s##*) }"; }
# running PID PROCESS: PID is the process started as PROCESS (its start time is the one recorded then) and
# not a zombie (a killed process nobody has reaped yet). The start time matters: pids are reused (pid_max can
# be 32768), and a busy machine may give a dead process's pid to another one within seconds. (Not its name:
# a --process command may be any program.)
running() {
  local f
  f=($(stat_of "$1")) || return 1
  [[ ${f[0]} != Z && ${f[19]} == "$(cat "$dir/$2.started" 2>/dev/null)" ]]
}
alive() { [[ -f $dir/$1.pid ]] && running "$(cat "$dir/$1.pid")" "$1"; }
# paused PID: stopped by SIGSTOP (or Ctrl-Z): alive, but it handles nothing until SIGCONT.
paused() { local f; f=($(stat_of "$1")) && [[ ${f[0]} == [Tt] ]]; }

# The group's lock, held by this script from here to its end (the kernel frees it however the script ends):
# start, stop, restart and kill take turns, so two starts of a process at once cannot both pass its checks.
# Not inherited by what the script starts ({lock}>&- on each command line).
lock_group() {
  exec {lock}>>"$dir/procs.lock"
  if ! flock -n "$lock"; then
    echo "procs.sh: another procs.sh is starting or stopping processes of '$run': waiting for it" >&2
    flock "$lock"
  fi
}

# The --process options of start and restart, into swaps[NAME] (the command, "" for the shipped one), each
# checked before anything is done: its program must be there and executable.
declare -A swaps
args=()
parse_swaps() {
  local swap name
  while [[ $# -gt 0 ]]; do
    case $1 in
      --process | --process=*)
        if [[ $1 == --process ]]; then
          [[ $# -ge 2 ]] || die "--process needs NAME='CMD ARGS'"
          swap=$2
          shift
        else
          swap=${1#--process=}
        fi
        [[ $swap == *=* ]] || die "--process '$swap': give NAME='CMD ARGS'"
        name=${swap%%=*}
        check_process "$name"
        swaps[$name]=$(printf '%s\n' "${swap#*=}" | sed '/^[[:space:]]*$/d')
        [[ -z ${swaps[$name]} ]] || check_program "--process $name='${swaps[$name]}'" "${swaps[$name]}"
        ;;
      *) args+=("$1") ;;
    esac
    shift
  done
}
# check_program WHAT COMMAND: the program COMMAND runs (its first word, as the shell splits it) is there and
# executable, from this folder and $PATH as the process will be started.
check_program() {
  local first
  first=$(xargs -n 1 printf '%s\n' <<<"$2" 2>/dev/null | head -n 1) || true
  [[ -n $first ]] || die "$1: no program named"
  if [[ $first == */* ]]; then
    [[ -e $first ]] || die "$1: $first: not found (from $PWD)"
    [[ -f $first && -x $first ]] || die "$1: $first: not an executable file"
  else
    command -v -- "$first" >/dev/null 2>&1 || die "$1: $first: not found in \$PATH"
  fi
}
# The program that starts PROCESS: the --process command given now, else the one it has, else the shipped
# afford-PROCESS.
check_start() {
  if [[ -v swaps[$1] ]]; then
    [[ -z ${swaps[$1]} ]] || return 0  # checked as given
    [[ -x $bin/afford-$1 ]] || die "$bin/afford-$1: not found or not executable (is the build done?)"
  elif [[ -s $dir/$1.process ]]; then
    check_program "$1's --process command ($dir/$1.process)" "$(cat "$dir/$1.process")"
  else
    [[ -x $bin/afford-$1 ]] || die "$bin/afford-$1: not found or not executable (is the build done?)"
  fi
}
# A process's --process command as given (swaps), for this start and the later ones.
apply_swap() {
  [[ -v swaps[$1] ]] || return 0
  if [[ -n ${swaps[$1]} ]]; then printf '%s\n' "${swaps[$1]}" >"$dir/$1.process"; else rm -f "$dir/$1.process"; fi
}

# The lines of PROCESS's output since its last start.
last_lines() {
  awk '/^=== .* start: / {n = 0; delete l; next} {l[++n] = $0} END {for (i = (n > 8 ? n - 7 : 1); i <= n; i++) print l[i]}' \
    "$dir/$1.log"
}

# launch PROCESS URL: start it in the background (`launched` gets PROCESS:PID). Not said started yet: heard()
# says so once its first STATUS is heard.
launch() {
  local p=$1 u=$2
  local line=("$bin/afford-$p" --lcm-url "$u")
  # A swapped process: the shell runs the command with the standard arguments as "$@", and becomes it (exec).
  [[ -s $dir/$p.process ]] && line=(/bin/sh -c "exec $(cat "$dir/$p.process") \"\$@\"" "afford-$p" --lcm-url "$u")
  [[ -n ${AFFORD_BUS_KEY:-} ]] && line+=(--bus-key "$AFFORD_BUS_KEY")
  [[ $p == logger ]] && line+=(--log-dir "$logs")
  [[ $p == predictors ]] && line+=(--checkpoint-dir "$logs")
  line+=(--state-dir "$logs")
  printf '%q ' "${line[@]}" >"$dir/$p.cmd"
  echo "=== $(date -Is) start: $(cat "$dir/$p.cmd")" >>"$dir/$p.log"
  # A simple command in the background, so that $! is the process itself
  # (`ip netns exec` execs it), and signals reach it.
  if [[ $netns == none ]]; then
    "${line[@]}" >>"$dir/$p.log" 2>&1 </dev/null {lock}>&- &
  else
    ip netns exec "$netns" "${line[@]}" >>"$dir/$p.log" 2>&1 </dev/null {lock}>&- &
  fi
  local pid=$! f
  # The pid and its start time (`running`): the same through every exec from here to the process itself.
  f=($(stat_of "$pid")) && echo "${f[19]}" >"$dir/$p.started"
  echo "$pid" >"$dir/$p.pid"
  launched+=("$p:$pid")
}

# heard URL: each launched process said started once its first STATUS is heard on the bus, or said to have
# exited (with its last lines) if it exits first; at most $start_seconds each. Returns 1 if one did not start.
heard() {
  local u=$1 e p pid rc=0 code
  local -A waiter
  local listen=("$bin/afford" status --lcm-url "$u" --wait-for "" --seconds "$start_seconds")
  [[ $netns == none ]] || listen=(ip netns exec "$netns" "${listen[@]}")
  for e in "${launched[@]}"; do
    listen[${#listen[@]} - 3]=$e  # (a simple command in the background: $! is the listener itself)
    "${listen[@]}" >/dev/null 2>&1 {lock}>&- &
    waiter[$e]=$!
  done
  local pending=("${launched[@]}") next
  while [[ ${#pending[@]} -gt 0 ]]; do
    next=()
    for e in "${pending[@]}"; do
      p=${e%%:*} pid=${e#*:}
      if ! running "$pid" "$p"; then
        kill "${waiter[$e]}" 2>/dev/null || true
        wait "${waiter[$e]}" 2>/dev/null || true
        code=0
        wait "$pid" 2>/dev/null || code=$?
        echo "procs.sh: $p (pid $pid) exited at once (exit status $code); the last lines of its output" \
          "($dir/$p.log):" >&2
        last_lines "$p" | sed 's/^/  /' >&2
        rc=1
      elif ! kill -0 "${waiter[$e]}" 2>/dev/null; then
        if wait "${waiter[$e]}"; then
          echo "$p started (pid $pid, heard on the bus; output in $dir/$p.log)"
        else
          echo "procs.sh: $p (pid $pid) runs, but was not heard on the bus within $start_seconds s (its output:" \
            "$dir/$p.log)" >&2
          rc=1
        fi
      else
        next+=("$e")
      fi
    done
    pending=("${next[@]}")
    [[ ${#pending[@]} -eq 0 ]] || sleep 0.05
  done
  launched=()
  return $rc
}

# start_one PROCESS URL: launched, unless it runs already (then refused: returns 1).
start_one() {
  local p=$1 u=$2
  if alive "$p"; then
    echo "procs.sh: $p is running already (pid $(cat "$dir/$p.pid")): not started again" \
      "(\`scripts/procs.sh restart $run $p\` starts it anew)" >&2
    return 1
  fi
  apply_swap "$p"
  launch "$p" "$u"
}

# warn_port_shared URL: a warning for each other group of LOGS with a process running whose bus is on URL's
# port: on the same address it is the same bus (each group hears the other's messages and drops them); on
# another address, afford's processes hear only their own (third_party/lcm, patch 0012), but other LCM
# programs (Debian's lcm-spy, lcm-logger) hear both.
warn_port_shared() {
  local mine=${1#*://} f g other oport pidf f19 live
  local addr=${mine%%:*} port=${mine#*:}
  port=${port%%[?/]*}
  for f in "$logs"/*/lcm-url; do
    g=${f%/lcm-url}
    [[ -f $f && $g != "$dir" ]] || continue
    other=$(cat "$f")
    other=${other#*://}
    oport=${other#*:}
    oport=${oport%%[?/]*}
    [[ $oport == "$port" ]] || continue
    live=
    for pidf in "$g"/*.pid; do
      f19=($(stat_of "$(cat "$pidf" 2>/dev/null)" 2>/dev/null)) || continue
      [[ ${f19[0]} != Z && ${f19[19]} == "$(cat "${pidf%.pid}.started" 2>/dev/null)" ]] && live=1
    done
    [[ -n $live ]] || continue
    if [[ ${other%%:*} == "$addr" ]]; then
      echo "procs.sh: warning: group '${g##*/}' (running) is on this same bus ($addr:$port): each group's" \
        "processes hear the other's messages (dropped: another key, or another run); give this group its own" \
        "port (AFFORD_URL at its first start, or edit $dir/lcm-url)" >&2
    else
      echo "procs.sh: warning: group '${g##*/}' (running) uses port $port too, with address ${other%%:*} (this" \
        "group: $addr): afford's processes hear only their own address, but other LCM programs (lcm-spy," \
        "lcm-logger) on either bus hear both; another port keeps them apart (AFFORD_URL at a group's first" \
        "start, or edit $dir/lcm-url)" >&2
    fi
  done
}

stop_one() {
  local p=$1
  check_process "$p"
  alive "$p" || { echo "$p is not running"; return 0; }
  local pid
  pid=$(cat "$dir/$p.pid")
  kill -INT "$pid"
  paused "$pid" && kill -CONT "$pid"  # a paused process takes its SIGINT once it goes on
  for _ in $(seq $((grace * 10))); do running "$pid" "$p" || break; sleep 0.1; done
  if running "$pid" "$p"; then  # (a program started in the background may ignore SIGINT: SIGTERM then)
    kill -TERM "$pid"
    for _ in $(seq 20); do running "$pid" "$p" || break; sleep 0.1; done
  fi
  if running "$pid" "$p"; then
    kill -KILL "$pid"
    echo "$p (pid $pid) did not stop within ${grace} s: killed"
  else
    echo "$p (pid $pid) stopped"
  fi
}

case $cmd in
  start)
    mkdir -p "$dir"
    ensure_ns
    [[ -f $dir/lcm-url ]] || echo "${AFFORD_URL:-udpm://239.255.76.67:7700?ttl=0&recv_buf_size=2097152}" >"$dir/lcm-url"
    if [[ ${AFFORD_PROCS_KEY:-on} != off ]]; then
      [[ -f $key ]] || "$bin/afford" bus-key "$key" >/dev/null
      export AFFORD_BUS_KEY=$key
    fi
    u=$(url)
    warn_port_shared "$u"
    parse_swaps "$@"
    procs=("${args[@]}")
    [[ ${#procs[@]} -gt 0 ]] || procs=("${all[@]}")
    for p in "${procs[@]}"; do check_process "$p"; check_start "$p"; done  # every program is there, first
    lock_group
    launched=()
    rc=0
    for p in "${procs[@]}"; do start_one "$p" "$u" || rc=1; done
    # A --process for a process not started here (it runs already) is not kept: its command stays what runs.
    heard "$u" || rc=1
    echo "group folder: $dir (each process's output, pid and command; runs' logs in $logs)"
    if [[ $netns == none ]]; then echo "bus: $u"; else echo "bus: $u (network namespace '$netns')"; fi
    [[ -n ${AFFORD_BUS_KEY:-} ]] && echo "key: $AFFORD_BUS_KEY (every process of the group needs it: --bus-key)"
    exit $rc
    ;;
  stop)
    url >/dev/null
    procs=("$@")
    [[ ${#procs[@]} -gt 0 ]] || procs=("${all[@]}")
    lock_group
    for p in "${procs[@]}"; do stop_one "$p"; done
    if [[ $netns != none ]] && ip netns list | grep -qw "^$netns" && ! ip netns pids "$netns" | grep -q .; then
      echo "no process runs in the network namespace '$netns' now: \`ip netns delete $netns\` removes it" \
        "(the next start makes it again)"
    fi
    ;;
  restart)
    u=$(url)
    parse_swaps "$@"
    [[ ${#args[@]} -ge 1 ]] || usage
    for p in "${args[@]}"; do check_process "$p"; check_start "$p"; done  # before any is stopped
    ensure_ns
    lock_group
    launched=()
    rc=0
    for p in "${args[@]}"; do stop_one "$p"; start_one "$p" "$u" || rc=1; done
    heard "$u" || rc=1
    exit $rc
    ;;
  kill)
    [[ $# -ge 1 ]] || usage
    url >/dev/null
    lock_group
    for p in "$@"; do
      check_process "$p"
      alive "$p" || { echo "$p is not running"; continue; }
      pid=$(cat "$dir/$p.pid")
      kill -KILL "$pid"
      for _ in $(seq 50); do running "$pid" "$p" || break; sleep 0.1; done
      echo "$p (pid $pid) killed with SIGKILL"
    done
    ;;
  status)
    u=$(url)
    printf '%-12s %8s  %s\n' process pid alive
    expect=()  # the live ones: each must be heard on the bus, else it is listed as silent
    for p in "${all[@]}"; do
      [[ -f $dir/$p.pid ]] || continue
      pid=$(cat "$dir/$p.pid")
      if ! alive "$p"; then
        a=no
      elif paused "$pid"; then
        a="paused (SIGSTOP: it handles nothing until \`kill -CONT $pid\`)"
        expect+=("$p:$pid")
      else
        a=yes
        expect+=("$p:$pid")
      fi
      printf '%-12s %8s  %s\n' "$p" "$pid" "$a"
      [[ -s $dir/$p.process ]] && printf '%-12s %8s  runs: %s\n' "" "" "$(cat "$dir/$p.process")"
    done
    echo
    # e.g. --wait-for eye --state running
    in_ns "$bin/afford" status --lcm-url "$u" --expect "$(IFS=,; echo "${expect[*]}")" "$@"
    ;;
  run)
    [[ $# -ge 1 ]] || usage
    u=$(url)
    # The group must be up: a run on a bus nobody serves waits for processes that never come.
    up=() down=()
    for p in "${all[@]}"; do
      [[ -f $dir/$p.pid ]] || continue
      if alive "$p"; then up+=("$p"); else down+=("$p"); fi
    done
    [[ ${#up[@]} -gt 0 ]] || die "group '$run' is not up: none of its processes runs (scripts/procs.sh start $run;" \
      "scripts/procs.sh status $run shows them)"
    [[ ${#down[@]} -eq 0 ]] || echo "procs.sh: not running in group '$run': ${down[*]} (a run that needs one waits" \
      "for it: scripts/procs.sh start $run ${down[*]})" >&2
    # How the runner says to resume what it runs: this script's run of the group, with the settings that find it.
    with=
    for v in AFFORD_NETNS AFFORD_BIN AFFORD_PROCS_KEY; do [[ -n ${!v:-} ]] && with+="$v=$(printf '%q' "${!v}") "; done
    [[ -n ${AFFORD_LOGS:-} ]] && with+="AFFORD_LOGS=$(printf '%q' "$logs") "
    export AFFORD_RESUME_WITH="$with$(printf '%q' "$0") run $(printf '%q' "$run")"
    # The run ids' prefix: --run-prefix if given, else RUN, or RUN-2, RUN-3, ... once runs of RUN exist; a resumed
    # experiment keeps its own (stored).
    prefix=()
    for a in "$@"; do [[ $a == --run-prefix || $a == --run-prefix=* || $a == --resume ]] && prefix=(none); done
    if [[ ${#prefix[@]} -eq 0 ]]; then
      p=$run k=1
      while compgen -G "$logs/$p-*" >/dev/null; do k=$((k + 1)); p=$run-$k; done
      prefix=(--run-prefix "$p")
      echo "run ids: $p-<experiment>-<system>-s<seed> (logs in $logs)"
    else
      prefix=()
    fi
    in_ns "$bin/afford" experiment "$@" --attach "$u" "${prefix[@]}" --log-root "$logs"
    ;;
  exec)
    [[ $# -ge 1 ]] || usage
    u=$(url)
    export AFFORD_URL=$u LCM_DEFAULT_URL=$u
    in_ns "$@"
    ;;
  *) usage ;;
esac
