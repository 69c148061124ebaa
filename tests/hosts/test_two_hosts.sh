#!/usr/bin/env bash
# Two hosts: two network namespaces joined by a veth pair (a LAN of two
# machines with nothing else on it), multicast routed over the pair, ttl=1.
# The environment, the eye and the logger run on host A with the runner; the
# predictors, the motivation and the planner on host B. An experiment (an
# intrinsic run and extrinsic tests of its agent) driven across them must give
# the summary and CSV files of the same experiment in one process (memq), and
# its log must replay to the same weights.
#   tests/hosts/test_two_hosts.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"  # the shared helpers (this test makes its own namespaces)
build=$(cd "$1" && pwd)
rm -rf "$2" && mkdir -p "$2"
out=$(cd "$2" && pwd)
[[ $(id -u) -eq 0 ]] || { echo "needs root (network namespaces, veth)"; exit 1; }
seed=${AFFORD_HOSTS_SEED:-$((1 + RANDOM % 50))}
va=afa$$ vb=afb$$
# Every process on a simulated host: those in the namespace of one of the holders.
on_hosts() {
  local h ns p
  for h in "${holders[@]}"; do
    ns=$(readlink "/proc/$h/ns/net" 2>/dev/null) || continue
    for p in /proc/[0-9]*; do
      [[ ${p#/proc/} != "$h" && $(readlink "$p/ns/net" 2>/dev/null) == "$ns" ]] && echo "${p#/proc/}"
    done
  done
}
cleanup() {
  local rc=$?
  # The processes started on the hosts, then the holders: the hosts' namespaces
  # and the veth pair go with them. (A backgrounded `on` is a subshell, and
  # killing it left its nsenter'd process running.)
  kill $(on_hosts) 2>/dev/null || true
  kill $(jobs -p) "${holders[@]}" 2>/dev/null || true
  wait 2>/dev/null || true
  if ((rc != 0)); then
    echo "--- diagnostics (seed $seed)"
    tail -n 8 "$out/two-hosts.txt" 2>/dev/null || true
    grep -h -E "\] \[(warning|error)\]" "$out"/*.log 2>/dev/null | tail -n 12 || true
  fi
}
trap cleanup EXIT

# A host is a network namespace held by a sleeping process; commands enter it
# with nsenter (not `ip netns exec`, which remounts / and fails in a chroot).
# The holder says its pid once it is in its namespace.
holders=()
newhost() {
  local fd
  exec {fd}< <(unshare --net sh -c 'echo $$; exec sleep infinity')
  read -r host_pid <&"$fd"
  holders+=("$host_pid")
}
newhost; a=$host_pid
newhost; b=$host_pid
on() { local pid=$1; shift; nsenter --net="/proc/$pid/ns/net" "$@"; }
ip link add "$va" type veth peer name "$vb"
ip link set "$va" netns "$a"
ip link set "$vb" netns "$b"
host() {  # host a|b: the interface's address and the multicast route
  local pid=$1 dev=$2 addr=$3
  on "$pid" ip link set lo up
  on "$pid" ip addr add "$addr/24" dev "$dev"
  on "$pid" ip link set "$dev" up multicast on
  on "$pid" ip route add 224.0.0.0/4 dev "$dev"
}
host "$a" "$va" 10.77.0.1
host "$b" "$vb" 10.77.0.2
echo "hosts: A (10.77.0.1) and B (10.77.0.2), seed $seed"

url="udpm://239.255.76.67:7997?ttl=1&recv_buf_size=2097152"
for p in environment eye; do on "$a" "$build/bin/afford-$p" --lcm-url "$url" >"$out/$p.log" 2>&1 & done
on "$a" "$build/bin/afford-logger" --lcm-url "$url" --log-dir "$out/logs" >"$out/logger.log" 2>&1 &
on "$b" "$build/bin/afford-predictors" --lcm-url "$url" --checkpoint-dir "$out/logs" >"$out/predictors.log" 2>&1 &
for p in motivation planner; do on "$b" "$build/bin/afford-$p" --lcm-url "$url" >"$out/$p.log" 2>&1 & done

# Host A hears all six: the processes of host B across the link.
for _ in $(seq 100); do
  on "$a" "$build/bin/afford" status --lcm-url "$url" --seconds 0.6 >"$out/status.txt"
  (($(grep -c -E "^(environment|eye|predictors|motivation|planner|logger) " "$out/status.txt") >= 6)) && break
done
cat "$out/status.txt"
(($(grep -c -E "^(environment|eye|predictors|motivation|planner|logger) " "$out/status.txt") >= 6)) ||
  { echo "host A does not hear the six processes"; exit 1; }

args=(experiment base --system IMP --reps 1 --steps 1500 --seed "$seed" --extrinsic-reps 2 --scenarios scenario3 --quiet
      --run-prefix hosts)
on "$a" "$build/bin/afford" "${args[@]}" --attach "$url" --out "$out/two-hosts" --log-root "$out/logs" \
  >"$out/two-hosts.txt" 2>&1 || { cat "$out/two-hosts.txt"; echo "the experiment across two hosts failed"; exit 1; }
"$build/bin/afford" "${args[@]}" --transport memq --keep-logs none --out "$out/one-process" \
  --log-root "$out/one-process-logs" >"$out/one-process.txt" 2>&1

same_results "$out/one-process" "$out/two-hosts" || exit 1
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/two-hosts/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "weights_checksum $sum across two hosts, equal to one process's; summary and CSV files equal"
# What crossed the link.
on "$b" ip -s link show "$vb" | awk '/RX:/ {getline; print "host B received " $2 " packets over the link"}'

"$build/bin/afford" replay "$out/logs/hosts-base-IMP-s$seed" | tee "$out/replay.txt"
grep -q "weights_checksum: $sum" "$out/replay.txt" || { echo "the log replays differently"; exit 1; }
