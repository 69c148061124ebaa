#!/usr/bin/env bash
# afford watch in headless Chromium, during a real run over udpm and on its log
# afterwards (tests/watch/browser.py says what is checked); a server bound off
# loopback refuses every request without its token; a second watcher on a port
# in use is refused. The run watched gives the results of the same run
# unwatched (in one process). Screenshots stay as artefacts: watch-live.png,
# watch-playback.png.
#   tests/watch/test_watch.sh BUILD_DIR ARTEFACT_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
export PYTHONPATH=$build/python

port=7995
url="udpm://239.255.76.67:$port?ttl=0"
experiment=(base --system IMP --reps 1 --steps 3000 --extrinsic-reps 1 --scenarios scenario3 --quiet
            --run-prefix watch)

"$build/bin/afford" watch --lcm-url "$url" --port 8090 >"$out/watch-live.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-live.log" || { cat "$out/watch-live.log"; echo "afford watch never served"; exit 1; }
# A second watcher on the port in use is refused, naming it (the port is never shared).
second=0
timeout 10 "$build/bin/afford" watch --lcm-url "$url" --port 8090 >"$out/watch-second.log" 2>&1 || second=$?
[[ $second == 1 ]] || { cat "$out/watch-second.log"; echo "a second afford watch on port 8090: exit $second, not 1 (124: it served)"; exit 1; }
grep -q "cannot serve on 127.0.0.1:8090: Address already in use" "$out/watch-second.log" ||
  { cat "$out/watch-second.log"; echo "the second watcher's refusal does not name the port"; exit 1; }
echo "a second watcher on port 8090: refused ($(tail -1 "$out/watch-second.log"))"
/usr/bin/python3 "$root/tests/watch/browser.py" live http://127.0.0.1:8090/ "$out" >"$out/browser-live.log" 2>&1 &
browser=$!
wait_until 60 test -e "$out/page-ready" || { cat "$out/browser-live.log"; echo "the page never opened"; exit 1; }
"$build/bin/afford" experiment "${experiment[@]}" --netns off --base-port "$port" --keep-logs all \
  --out "$out/run" --log-root "$out/logs" >"$out/run.log" 2>&1 || { echo "the run failed:"; cat "$out/run.log"; exit 1; }
wait "$browser" || { cat "$out/browser-live.log"; tail -20 "$out/watch-live.log"; exit 1; }
cat "$out/browser-live.log"

# Watched over udpm, unwatched in one process: the same results.
"$build/bin/afford" experiment "${experiment[@]}" --transport memq --keep-logs none --out "$out/unwatched" \
  --log-root "$out/logs-unwatched" >"$out/unwatched.log" 2>&1
same_results "$out/unwatched" "$out/run"
echo "watched: the results of the run unwatched"

# The log played: the controls.
log=$(ls -d "$out"/logs/watch-base-IMP-s1)
"$build/bin/afford" watch --log "$log" --port 8091 --paused >"$out/watch-log.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-log.log" || { cat "$out/watch-log.log"; echo "afford watch --log never served"; exit 1; }
/usr/bin/python3 "$root/tests/watch/browser.py" playback http://127.0.0.1:8091/ "$out"

# Off loopback: the token.
"$build/bin/afford" watch --lcm-url "$url" --bind 0.0.0.0 --port 8092 >"$out/watch-bound.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-bound.log" || { cat "$out/watch-bound.log"; echo "afford watch --bind never served"; exit 1; }
page=$(sed -n 's/^the page: //p' "$out/watch-bound.log")
[[ $page == *"?token="* ]] || { echo "no token in the address printed: $page"; exit 1; }
/usr/bin/python3 "$root/tests/watch/browser.py" token "${page/0.0.0.0/127.0.0.1}"
# A keyed bus: the watcher with the key follows the run, one without it shows nothing of it.
"$build/bin/afford" bus-key "$out/bus.key" >/dev/null
"$build/bin/afford" watch --lcm-url "$url" --bus-key "$out/bus.key" --port 8093 >"$out/watch-keyed.log" 2>&1 &
"$build/bin/afford" watch --lcm-url "$url" --port 8094 >"$out/watch-keyless.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-keyed.log" || { cat "$out/watch-keyed.log"; exit 1; }
wait_until 30 grep -qs "the page:" "$out/watch-keyless.log" || { cat "$out/watch-keyless.log"; exit 1; }
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 300 --quiet --run-prefix keyed --netns off \
  --base-port "$port" --bus-key "$out/bus.key" --keep-logs none --out "$out/keyed" --log-root "$out/logs-keyed" \
  >"$out/keyed.log" 2>&1 || { cat "$out/keyed.log"; exit 1; }
shown() { /usr/bin/python3 -c "import json, sys, urllib.request
s = json.load(urllib.request.urlopen(sys.argv[1] + '/state'))
print(s['run']['id'], s['step'])" "$1"; }
# (the keyed watcher has the result once the run's RESULT came: the run's last step)
wait_until 30 test "$(shown http://127.0.0.1:8093)" = "keyed-base-IMP-s1 300" ||
  { echo "the keyed watcher shows '$(shown http://127.0.0.1:8093)'"; exit 1; }
[[ $(shown http://127.0.0.1:8094) == " -1" ]] || { echo "a watcher without the key shows '$(shown http://127.0.0.1:8094)'"; exit 1; }
echo "keyed: the watcher with the key followed the run to step 300, the one without it showed nothing"
echo "screenshots: $out/watch-live.png $out/watch-playback.png"
