#!/usr/bin/env bash
# A keyed recording played into a fresh group of the same key (issue 54's
# "something said again must be dropped and counted, never fail a run"): a
# group runs an experiment while Debian's lcm-logger records the bus (stamps
# and tags kept); then, K times, a fresh group of the same key (processes that
# never heard the recording's senders, so its stamps pass the freshness check
# while the recording is younger than protocol.freshness_ms: each round
# records anew) runs the same experiment under the same run ids while
# lcm-logplayer plays the recording into it, at a moment drawn for each:
# before the run, as it starts, at a step drawn in its middle, near its end;
# and a last round plays the first recording, older than freshness_ms. Each run must end with the undisturbed
# results (weights checksum included), each process must count what it
# dropped, and write at most 100 warning lines.
#   tests/requests/played_back.sh BUILD_DIR WORK_DIR [K] [STEPS]
# Not a ctest test (it takes minutes): its figures are in docs/performance.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
rounds=${3:-8}
steps=${4:-1500}
url="udpm://239.255.76.67:7733?ttl=0&recv_buf_size=2097152"
source "$root/tests/group.sh"
key=$out/bus.key
"$build/bin/afford" bus-key "$key" >/dev/null
export AFFORD_BUS_KEY=$key

experiment() {  # LABEL: the experiment on the group's bus, its logs in LABEL-logs
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps "$steps" --seed 5 --extrinsic-reps 1 \
    --scenarios scenario2 --quiet --attach "$url" --run-prefix pb --no-reuse-agents --out "$out/$1" \
    --log-root "$out/$1-logs" >"$out/$1.txt" 2>&1
}

# A recording of the experiment on a group of the key: LABEL's group runs it while lcm-logger records the bus.
record() {
  group_start "$1" --bus-key "$key"
  lcm-logger --lcm-url="$url" "$out/$1.lcm" >"$out/$1-lcm-logger.txt" 2>&1 &
  local recorder=$!
  experiment "$1" || { cat "$out/$1.txt"; echo "the recorded experiment failed"; exit 1; }
  kill -INT "$recorder"
  wait "$recorder" || true
  group_stop "$1"
}

record recorded  # the first recording, played again at the end when it is old
for ((k = 1; k <= rounds + 1; k++)); do
  label=fresh-$k
  recording=$out/recorded.lcm
  if ((k <= rounds)); then  # a young recording: played within protocol.freshness_ms of being made
    record "young-$k"
    recording=$out/young-$k.lcm
  fi
  group_start "$label" --bus-key "$key"
  play() { lcm-logplayer --lcm-url="$url" "$recording" >"$out/$label-player.txt" 2>&1 & player=$!; }
  case $(((k - 1) % 4)) in
    0) when="before the run"; play; experiment "$label" & runner=$! ;;
    1) when="as it starts"; experiment "$label" & runner=$!
       "$build/bin/afford" status --lcm-url "$url" --wait-for environment --state ready --seconds 60 >/dev/null || true
       play ;;
    2) at=$((steps / 4 + RANDOM % (steps / 2))); when="at step $at"; experiment "$label" & runner=$!
       "$build/bin/afford" status --lcm-url "$url" --wait-for environment --step "$at" --seconds 120 >/dev/null || true
       play ;;
    3) at=$((steps - steps / 10)); when="near its end (step $at)"; experiment "$label" & runner=$!
       "$build/bin/afford" status --lcm-url "$url" --wait-for environment --step "$at" --seconds 120 >/dev/null || true
       play ;;
  esac
  age=$(($(date +%s) - $(stat -c %Y "$recording")))
  wait "$runner" || { cat "$out/$label.txt"; group_errors "$label"; echo "round $k ($when): the run failed"; exit 1; }
  wait "$player" || true
  group_stop "$label"
  same_results "$out/recorded" "$out/$label" || { echo "round $k ($when): the results differ"; exit 1; }
  line="round $k, a recording ${age} s old played $when:"
  for p in "${processes[@]}"; do
    warnings=$(grep -c "\[warning\]" "$out/$label-$p.log" || true)
    dropped=$(sed -n 's/.*stopped; \([0-9]*\) messages dropped at the edge.*/\1/p' "$out/$label-$p.log" | tail -1)
    line+=" $p ${dropped:-0} dropped/${warnings} warning lines;"
    ((warnings <= 100)) || { echo "$line"; echo "process $p wrote $warnings warning lines"; exit 1; }
  done
  echo "$line"
done
sum=$(grep -o '"weights_checksum": "[0-9a-f]*"' "$out/recorded/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}')
echo "$((rounds + 1)) fresh groups of the same key given a recording at every kind of moment ($rounds young, one old):" \
  "each run the undisturbed one (weights $sum), every process within 100 warning lines"
