# Sourced by the tests that watch a live run under Xvfb (tests/spy, tests/viewer).
# First call: re-runs the calling script in a private network namespace of its
# own (root), so its multicast stays on this machine's loopback. Inside: routes
# multicast over lo, starts Xvfb on a free display (killed with every other
# background job on exit) and exports DISPLAY.
#   in_netns_with_xvfb WIDTHxHEIGHT LOGFILE "$0" "$@"
in_netns_with_xvfb() {
  local screen=$1 log=$2
  shift 2
  if [[ -z ${AFFORD_TEST_NETNS:-} ]]; then
    exec unshare --net env AFFORD_TEST_NETNS=1 bash "$@"
  fi
  ip link set lo up multicast on
  ip route add 224.0.0.0/4 dev lo
  local display=:$((100 + $$ % 400))
  Xvfb "$display" -screen 0 "${screen}x24" -nolisten tcp >"$log" 2>&1 &
  trap 'kill $(jobs -p) 2>/dev/null || true' EXIT
  export DISPLAY=$display
  for _ in $(seq 50); do [[ -e /tmp/.X11-unix/X${display#:} ]] && return 0; sleep 0.1; done
  echo "Xvfb did not start (see $log)" >&2
  return 1
}
