#!/usr/bin/env bash
# A one-node Slurm cluster on localhost, for tests (Debian's slurm-wlm 22.05).
#
#   tests/cluster/slurm-local.sh start DIR   # prints the lines to eval
#   tests/cluster/slurm-local.sh stop DIR
#
# Needs root and the packages: apt-get install --no-install-recommends
#   slurmctld slurmd slurm-client munge
#
# `start` builds everything under DIR (munge key and socket; slurm.conf;
# controller state and slurmd spool; pid files in DIR/run; logs in DIR/log),
# leaving /etc/munge and /etc/slurm alone, starts munged, slurmctld and slurmd
# as root on free TCP ports of loopback (no cgroups, no accounting), waits
# until the node is idle and prints on stdout, for the caller to eval (the
# same lines are in DIR/env.sh, to source):
#   export SLURM_CONF=DIR/etc/slurm.conf
#   export SLURM_LOCAL_MUNGE_SOCKET=DIR/munge/munge.socket   (for `munge -S`;
#     Slurm's own clients find it through AuthInfo in slurm.conf)
# Everything else (progress, errors, daemon log tails) goes to stderr. As
# `eval "$(... start DIR)"` would hide a failed start, a caller writes
#   env=$(tests/cluster/slurm-local.sh start "$dir") && eval "$env"
#
# `stop` cancels the cluster's jobs, ends the daemons started by `start` (pid
# files in DIR) and any slurmstepd or job process they left, and waits until
# none is left. It leaves DIR's files (logs, slurm.conf) for a post-mortem.
# Call it from the network namespace `start` ran in (the daemons live there),
# e.g. from the test's EXIT trap: the daemons outlive the caller otherwise.
#
# Both exit non-zero naming what failed. Several clusters can run at once in
# different DIRs (each has its own ports, munge socket and ClusterName).
#
# Note for callers: `sbatch --wait` polls the controller after 2 s, 8 s, then
# every 32 s, so it returns up to ~30 s after a job ended. On this idle node
# `salloc --dependency=afterany:ID true` returns within about a second of job
# ID's end, when the controller grants it (the state is then in
# `scontrol show job ID`).
set -Eeuo pipefail
# Any command failing where it is not checked still names itself.
trap 'echo "slurm-local: error: \"$BASH_COMMAND\" failed (line $LINENO, status $?)" >&2' ERR

usage() {
  echo "usage: $0 start DIR | stop DIR" >&2
  exit 2
}
[[ $# -eq 2 && ( $1 == start || $1 == stop ) ]] || usage
action=$1

# ---------------------------------------------------------------- helpers --

say() { echo "slurm-local: $*" >&2; }

# fail MESSAGE [LOG...]: says what failed, shows the tail of each log, exits 1.
fail() {
  say "error: $1"
  shift
  local log
  for log in "$@"; do
    if [[ -s $log ]]; then
      echo "----- last lines of $log -----" >&2
      tail -n 25 "$log" >&2
      echo "-----" >&2
    fi
  done
  exit 1
}

# running PID: true if PID exists and is not a zombie. (The daemons fork
# away from us, so PID 1 reaps them, and here it does so a second or two late.)
running() {
  local state
  state=$(awk '/^State:/ { print $2 }' "/proc/$1/status" 2>/dev/null) || return 1
  [[ -n $state && $state != Z && $state != X ]]
}

# alive PIDFILE NAME: true if PIDFILE names a running process whose command is
# NAME (guards against a recycled pid). Prints the pid.
alive() {
  local pid
  [[ -s $1 ]] || return 1
  pid=$(<"$1")
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$2" ]] && running "$pid" || return 1
  echo "$pid"
}

# await_exit SECONDS PID...: true once none of the pids runs (a zombie counts
# as gone), false after SECONDS. The processes are not this shell's children,
# so it waits on a pidfd of each (Linux 5.3; perl-base is in every Debian).
await_exit() {
  perl -e '
    my $left = shift; my %open; my $all = "";
    for my $pid (@ARGV) {
      my $fd = syscall(434, $pid + 0, 0);  # pidfd_open; fails once the pid is gone
      next if $fd < 0;
      $open{$fd} = 1; vec($all, $fd, 1) = 1;
    }
    my $end = time + $left;
    while (%open) {
      $left = $end - time;
      exit 1 if $left <= 0;
      my $ready = $all;
      next if select($ready, undef, undef, $left) <= 0;  # EINTR or the timeout: look again
      for my $fd (keys %open) {
        next unless vec($ready, $fd, 1);
        delete $open{$fd}; vec($all, $fd, 1) = 0;  # readable: that process has exited
      }
    }
    exit 0' "$@"
}

# await_line LOG REGEX PID SECONDS WHAT: returns once LOG has a line matching
# REGEX (read as it is written); fails naming WHAT if the process PID exits
# first or SECONDS pass.
await_line() {
  local fd tail_pid found=0
  exec {fd}< <(exec timeout "$4" tail -n +1 -F --pid="$3" "$1" 2>/dev/null)
  tail_pid=$!
  grep -m1 -qE "$2" <&"$fd" && found=1
  exec {fd}<&-
  kill "$tail_pid" 2>/dev/null || true
  ((found)) && return 0
  running "$3" || fail "$5: the process exited" "$1"
  fail "$5: not seen within $4 s" "$1"
}

# cluster_pids: processes of this DIR's cluster, found by what they hold:
# the daemons and each slurmstepd keep a log file in DIR/log open and work in
# DIR/log or DIR/spool (slurmstepd rewrites its environment for its process
# title, so an environment mark would not survive). The caller and this
# script are left out.
cluster_pids() {
  local self=" $$ $BASHPID " pid
  # This script's ancestors, so that a caller sitting in DIR/log is spared.
  pid=$$
  while [[ $pid =~ ^[0-9]+$ ]] && ((pid > 1)); do
    self+="$pid "
    pid=$(awk '/^PPid:/ { print $2 }' "/proc/$pid/status" 2>/dev/null) || break
  done
  # find fails on what it may not read (/proc/1 here) and on processes that
  # end while it looks; what it did print is what counts.
  { find /proc/[0-9]*/cwd /proc/[0-9]*/fd -maxdepth 1 \
    \( -lname "$dir/log" -o -lname "$dir/log/*" -o -lname "$dir/spool" \
    -o -lname "$dir/spool/*" -o -lname "$dir/state/*" -o -lname "$munge_dir/*" \) \
    -printf '%p\n' 2>/dev/null | cut -d/ -f3 | sort -un || true; } |
    while read -r pid; do [[ $self == *" $pid "* ]] || echo "$pid"; done
}

# with_descendants PID...: the pids and all their descendants (a job script
# under a slurmstepd works in the submitter's directory and holds nothing of
# DIR's).
with_descendants() {
  ps -eo pid=,ppid= | awk -v roots="$*" '
    { parent[$1] = $2 }
    END {
      n = split(roots, queue, " ")
      for (i = 1; i <= n; i++) keep[queue[i]] = 1
      do {
        grown = 0
        for (p in parent) if (!(p in keep) && (parent[p] in keep)) { keep[p] = 1; grown = 1 }
      } while (grown)
      for (p in keep) print p
    }'
}

# listening_ports: TCP ports something listens on (any address), one a line.
listening_ports() {
  if command -v ss >/dev/null; then
    ss -Htln | awk '{ n = split($4, a, ":"); print a[n] }'
  else # /proc/net/tcp{,6}: state 0A is LISTEN, the port is hex
    awk '$4 == "0A" { split($2, a, ":"); print strtonum("0x" a[2]) }' \
      /proc/net/tcp /proc/net/tcp6 2>/dev/null
  fi
}

# free_ports N: N distinct free ports in 20000-32767 (below the kernel's
# ephemeral range, clear of Slurm's defaults 6817-6819), starting at a random
# place so that clusters started at the same time seldom pick the same.
free_ports() {
  local used port n=0 tries=0
  used=" $(listening_ports | sort -un | tr '\n' ' ') "
  port=$((20000 + RANDOM % 12000))
  while ((n < $1)); do
    ((++tries < 12768)) || fail "no free TCP port in 20000-32767"
    port=$((port + 1))
    ((port <= 32767)) || port=20000
    [[ $used == *" $port "* ]] && continue
    echo "$port"
    used+="$port "
    n=$((n + 1))
  done
}

# ------------------------------------------------------------------ paths --

if [[ $action == start ]]; then mkdir -p "$2"; fi
if [[ ! -d $2 ]]; then
  say "nothing was running in $2 (no such directory)"
  exit 0
fi
dir=$(cd "$2" && pwd -P)
conf=$dir/etc/slurm.conf
munge_dir=$dir/munge # 0755: the socket must be reachable by any user
socket=$munge_dir/munge.socket
munged_pid=$munge_dir/munged.pid
munged_log=$dir/log/munged.log
run=$dir/run
ctld_pid=$run/slurmctld.pid
slurmd_pid=$run/slurmd.pid
ctld_log=$dir/log/slurmctld.log
slurmd_log=$dir/log/slurmd.log

# ------------------------------------------------------------------- stop --

stop() {
  local pids=() jobs=() strays=() stepds=() pid name file
  # Jobs first, while the controller can still end them cleanly (a stepd
  # killed under a running job would leave the job's processes behind): each
  # job's slurmstepd exits once its job has ended.
  if alive "$ctld_pid" slurmctld >/dev/null && [[ -f $conf ]]; then
    mapfile -t jobs < <(SLURM_CONF=$conf squeue -h -o %A 2>/dev/null || true)
    if ((${#jobs[@]})); then
      for pid in $(cluster_pids); do
        [[ $(cat "/proc/$pid/comm" 2>/dev/null) == slurmstepd ]] && stepds+=("$pid")
      done
      say "cancelling jobs ${jobs[*]}"
      SLURM_CONF=$conf scancel --quiet "${jobs[@]}" 2>/dev/null || true
      ((${#stepds[@]} == 0)) || await_exit 20 "${stepds[@]}" ||
        say "the jobs' slurmstepd processes ${stepds[*]} did not end within 20 s of scancel"
    fi
  fi

  # Then the daemons: slurmd, slurmctld, munged last (the others use it).
  for file in "$slurmd_pid:slurmd" "$ctld_pid:slurmctld" "$munged_pid:munged"; do
    name=${file##*:}
    file=${file%:*}
    if pid=$(alive "$file" "$name"); then
      say "stopping $name (pid $pid)"
      kill -TERM "$pid" 2>/dev/null || true
      pids+=("$pid")
      if ! await_exit 20 "$pid"; then
        say "$name (pid $pid) ignored SIGTERM for 20 s; killing it"
        kill -KILL "$pid" 2>/dev/null || true
        await_exit 5 "$pid" || fail "$name (pid $pid) does not exit" \
          "$ctld_log" "$slurmd_log" "$munged_log"
      fi
    fi
    rm -f "$file"
  done

  # Anything the daemons forked (slurmstepd) and left.
  mapfile -t strays < <(cluster_pids)
  if ((${#strays[@]})); then
    mapfile -t strays < <(with_descendants "${strays[@]}")
    say "killing leftover processes of this cluster: ${strays[*]}"
    kill -KILL "${strays[@]}" 2>/dev/null || true
    await_exit 5 "${strays[@]}" || fail "processes ${strays[*]} of this cluster do not exit"
  fi
  rm -f "$socket" "$socket.lock"
  if ((${#pids[@]} + ${#strays[@]} == 0)); then
    say "nothing was running in $dir"
  else
    say "stopped"
  fi
}

if [[ $action == stop ]]; then
  stop
  exit 0
fi

# ------------------------------------------------------------------ start --

((EUID == 0)) || fail "must run as root (the daemons run as root, SlurmUser=root)"
for tool in munged munge unmunge slurmctld slurmd sinfo scontrol sbatch squeue scancel; do
  command -v "$tool" >/dev/null || fail "'$tool' not found; apt-get install --no-install-recommends slurmctld slurmd slurm-client munge"
done
for file in "$munged_pid:munged" "$ctld_pid:slurmctld" "$slurmd_pid:slurmd"; do
  if pid=$(alive "${file%:*}" "${file##*:}"); then
    fail "${file##*:} already runs for $dir (pid $pid); '$0 stop $dir' first"
  fi
done
t0=${EPOCHREALTIME/./}

# If anything below fails, take down what was started.
trap 'status=$?; if ((status != 0)); then say "start failed; stopping what was started"; (stop) >/dev/null 2>&1 || true; fi' EXIT

# The daemons must not mistake the caller's job (when this runs inside a
# real Slurm job) or its configuration for theirs.
while read -r var; do unset "$var"; done < <(compgen -e | grep -E '^(SLURM|SBATCH|SRUN|SALLOC)_' || true)

# Fresh state on every start; logs of the previous run are kept as *.old.
rm -rf "$dir/state" "$dir/spool" "$munge_dir"
mkdir -p "$dir/etc" "$dir/state" "$dir/spool" "$dir/log" "$run"
mkdir -m 0755 "$munge_dir" # munged wants it not group/world-writable
for log in "$munged_log" "$ctld_log" "$slurmd_log"; do
  [[ -f $log ]] && mv -f "$log" "$log.old"
  : >"$log" # there from the start, for await_line's tail to follow
done

# --- munge: a key and a daemon of our own, on a socket inside DIR.
head -c 1024 /dev/urandom >"$munge_dir/munge.key"
chmod 0400 "$munge_dir/munge.key"
# --force: munged refuses paths whose parents are group/world-writable (a
# build tree under umask 002, say); it then only warns.
munged --force --key-file="$munge_dir/munge.key" --socket="$socket" \
  --pid-file="$munged_pid" --log-file="$munged_log" \
  --seed-file="$munge_dir/munged.seed" --num-threads=2 \
  </dev/null >>"$munged_log" 2>&1 || fail "munged did not start" "$munged_log"
# munged returns once its child has created the socket and written its pid.
alive "$munged_pid" munged >/dev/null || fail "munged did not start (no live pid in $munged_pid)" "$munged_log"
munge -n -S "$socket" 2>/dev/null | unmunge -S "$socket" >/dev/null 2>&1 ||
  fail "munged does not answer on $socket" "$munged_log"

# --- addresses. Slurm 22.05 resolves every address, 127.0.0.1 and the
# wildcard it binds to included, as AF_INET with AI_ADDRCONFIG, and glibc then
# answers nothing unless some IPv4 address other than 127.0.0.1 is configured
# ("getaddrinfo() failed: Name or service not known", slurmd exits). That is
# the case in a private network namespace holding only lo (tests/netns.sh).
# There lo gets a second loopback address, 127.0.0.2/8: nothing can leave such
# a namespace anyway. Elsewhere we say so and stop rather than touch the host.
if ! getent ahostsv4 127.0.0.1 >/dev/null; then
  if [[ $(ip -o link show 2>/dev/null | awk -F': ' '{ print $2 }') == lo ]]; then
    say "only lo in this network namespace: adding 127.0.0.2/8 to lo for Slurm's address lookups"
    if ! { ip link set lo up && ip addr add 127.0.0.2/8 dev lo; }; then
      fail "could not add 127.0.0.2/8 to lo (needed by Slurm's AI_ADDRCONFIG lookups)"
    fi
    getent ahostsv4 127.0.0.1 >/dev/null || fail "127.0.0.1 still does not resolve for AF_INET"
  else
    fail "no IPv4 address other than 127.0.0.1 is configured, so Slurm cannot resolve any address (getaddrinfo AI_ADDRCONFIG); e.g. 'ip addr add 127.0.0.2/8 dev lo'"
  fi
fi

# --- this machine, as slurmd sees it (CPUs, sockets, cores, memory).
node=$(hostname -s)
hw=$(slurmd -C 2>/dev/null | head -1) || true
[[ $hw == NodeName=* ]] || fail "'slurmd -C' did not describe this machine: $hw"
hw=${hw#NodeName=* } # drop NodeName=..., keep CPUs=... RealMemory=...
# The node's address. With NoInAddrAny/NoCtldInAddrAny slurmd and slurmctld
# listen only on what gethostname() resolves to (whatever NodeAddr says), so
# they are used only when the short name resolves to a loopback address
# (127.0.0.1 here, 127.0.1.1 on a stock Debian /etc/hosts), and NodeAddr and
# SlurmctldHost's address are then that same address. Otherwise (the name
# does not resolve, or resolves to a LAN address) the daemons listen on every
# interface and are reached at 127.0.0.1: the traffic still stays on loopback.
addr=$(getent ahostsv4 "$node" 2>/dev/null | awk 'NR == 1 { print $1 }') || true
if [[ $addr == 127.* ]]; then
  bind="CommunicationParameters=NoInAddrAny,NoCtldInAddrAny"
else
  say "host name '$node' resolves to '${addr:-nothing}', not to loopback: the daemons listen on all interfaces and are reached at 127.0.0.1"
  addr=127.0.0.1
  bind="# (daemons listen on all interfaces: '$node' does not resolve to loopback)"
fi
ports=$(free_ports 2) || exit 1
ctld_port=${ports%%$'\n'*}
slurmd_port=${ports##*$'\n'}
# ClusterName: lower case, distinct per DIR (state files carry it).
cluster=local$(printf '%s' "$dir" | cksum | cut -d' ' -f1)

# NodeAddr and SlurmctldHost's address are loopback ($addr): nothing goes
# beyond it, and slurmctld (NoCtldInAddrAny) listens there only.
cat >"$conf" <<EOF
# Written by tests/cluster/slurm-local.sh for a one-node test cluster.
ClusterName=$cluster
SlurmctldHost=$node($addr)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
$bind
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket

StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$ctld_pid
SlurmdPidFile=$slurmd_pid
SlurmctldLogFile=$ctld_log
SlurmdLogFile=$slurmd_log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/etc/plugstack.conf

# No cgroups, no accounting: works in containers, needs no slurmdbd.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true

# Cores are handed out one by one, so array tasks share the node.
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# FIFO, and a scheduling pass every second rather than every minute: a job
# whose dependency was met, or that waits for a core, starts within ~1 s.
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=1,sched_min_interval=0,batch_sched_delay=0
ReturnToService=2
SlurmdParameters=config_overrides
# Finished jobs stay visible to squeue/scontrol for 5 minutes (dependencies).
MinJobAge=300
KillWait=5
InactiveLimit=0
SlurmdTimeout=60

NodeName=$node NodeAddr=$addr NodeHostname=$node $hw State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
: >"$dir/etc/plugstack.conf" # not /etc/slurm's
export SLURM_CONF=$conf

# --- the controller, then the node daemon, in the foreground (-D) as
# background jobs of their own session: their pids are known at once, and
# their logs say when each is ready.
setsid slurmctld -D -f "$conf" </dev/null >/dev/null 2>&1 &
ctld=$!
await_line "$ctld_log" "Running as primary controller" "$ctld" 30 "slurmctld (pid $ctld) taking its role"
setsid slurmd -D -f "$conf" -N "$node" </dev/null >/dev/null 2>&1 &
slurmd=$!
await_line "$slurmd_log" "slurmd started on" "$slurmd" 30 "slurmd (pid $slurmd) starting"

# --- the node is up once a job can be given it: salloc returns when the
# controller grants the allocation (it tells salloc), and its `true` ends the
# job at once. Should a daemon exit first, that ends the wait.
timeout 60 salloc --quiet --job-name=slurm-local-ready true </dev/null >/dev/null 2>"$dir/log/ready.err" &
ready=$!
wait -n -p first "$ready" "$ctld" "$slurmd" && status=0 || status=$?
case ${first:-} in
  "$ready") ((status == 0)) || fail "node $node not given a job within 60 s (salloc status $status)" \
    "$dir/log/ready.err" "$ctld_log" "$slurmd_log" ;;
  "$ctld") fail "slurmctld exited" "$ctld_log" ;;
  *) fail "slurmd exited" "$slurmd_log" ;;
esac
for file in "$ctld_pid:slurmctld" "$slurmd_pid:slurmd"; do
  alive "${file%:*}" "${file##*:}" >/dev/null || fail "${file##*:} has not written its pid to ${file%:*}"
done

cat >"$dir/env.sh" <<EOF
export SLURM_CONF=$conf
export SLURM_LOCAL_MUNGE_SOCKET=$socket
EOF
cat "$dir/env.sh"
say "cluster $cluster up in $(((${EPOCHREALTIME/./} - t0) / 1000)) ms: node $node ($hw), slurmctld :$ctld_port, slurmd :$slurmd_port; stop with '$0 stop $dir'"
