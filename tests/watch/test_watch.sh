#!/usr/bin/env bash
# afford watch in headless Chromium (tests/watch/browser.py says what is checked): the page that `afford
# experiment --watch` serves from the experiment itself, its runs in their private network namespace, followed
# through a GOALS run and its tests; `afford watch` finding that experiment by its folder and by its log root, and
# a group by its log root; the run's log played afterwards; a page with no run; a server bound off loopback,
# which prints addresses that open and refuses every request without its token; a second watcher on a port in
# use, refused; a keyed bus. The run watched gives the results of the same run unwatched (in one process); run
# again with its agent stored, --watch says the page will not see it learn and names --no-reuse-agents.
# Screenshots stay as artefacts: watch-live.png, watch-end.png, watch-playback.png, watch-idle.png, watch-table.png.
#   tests/watch/test_watch.sh BUILD_DIR ARTEFACT_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
export PYTHONPATH=$build/python

port=7995
url="udpm://239.255.76.67:$port?ttl=0"
experiment=(goals --system GOALS --reps 1 --steps 2000 --extrinsic-reps 2 --scenarios scenario3 --quiet
            --run-prefix watch)
state() { /usr/bin/python3 -c "import json, sys, urllib.request
s = json.load(urllib.request.urlopen(sys.argv[1] + '/state'))
print(s['run']['id'], s['step'])" "$1" 2>/dev/null || true; }

# The experiment serves its own page (--watch), its runs in a private network namespace of their own: the
# browser, here, opens it with nothing set up by hand.
/usr/bin/python3 "$root/tests/watch/browser.py" live http://127.0.0.1:8090/ "$out" >"$out/browser-live.log" 2>&1 &
browser=$!
wait_until 60 test -e "$out/page-ready" || { cat "$out/browser-live.log"; echo "Chromium never started"; exit 1; }
"$build/bin/afford" experiment "${experiment[@]}" --watch --watch-port 8090 --keep-logs all --out "$out/run" \
  --log-root "$out/logs" >"$out/run.log" 2>&1 &
run=$!
wait_until 30 grep -qs "the page of this experiment (--watch): http://127.0.0.1:8090/" "$out/run.log" ||
  { cat "$out/run.log"; echo "afford experiment --watch printed no page"; exit 1; }
# Found while it runs: by its folder, and as the one experiment running in its log root (afford watch enters
# its namespace); nothing to watch in a log root where nothing runs.
wait_until 30 test -s "$out/run/bus.json" || { cat "$out/run.log"; echo "no bus.json"; exit 1; }
"$build/bin/afford" watch --out "$out/run" --port 8088 >"$out/watch-out.log" 2>&1 &
"$build/bin/afford" watch --log-root "$out/logs" --port 8089 >"$out/watch-root.log" 2>&1 &
follows() { [[ $(state "$1") == watch-goals-GOALS-s1* ]]; }  # (the run, or one of its tests)
for p in 8088 8089; do
  wait_until 60 follows http://127.0.0.1:$p ||
    { cat "$out/watch-out.log" "$out/watch-root.log"; echo "afford watch on port $p shows '$(state http://127.0.0.1:$p)'"; exit 1; }
done
grep -q "watching experiment goals in $out/run: udpm://239.255.76.67:7700" "$out/watch-out.log" ||
  { cat "$out/watch-out.log"; echo "afford watch --out does not say what it watches"; exit 1; }
echo "found: afford watch --out and --log-root follow the experiment in its namespace"
mkdir -p "$out/nothing"
nothing=0
"$build/bin/afford" watch --log-root "$out/nothing" --port 0 >"$out/watch-nothing.log" 2>&1 || nothing=$?
[[ $nothing == 1 ]] && grep -q "nothing to watch in $out/nothing" "$out/watch-nothing.log" ||
  { cat "$out/watch-nothing.log"; echo "afford watch with nothing running: exit $nothing"; exit 1; }
wait "$run" || { echo "the run failed:"; cat "$out/run.log"; exit 1; }
wait "$browser" || { cat "$out/browser-live.log"; exit 1; }
cat "$out/browser-live.log"

# Watched over udpm, unwatched in one process: the same results.
"$build/bin/afford" experiment "${experiment[@]}" --transport memq --keep-logs none --out "$out/unwatched" \
  --log-root "$out/logs-unwatched" >"$out/unwatched.log" 2>&1
same_results "$out/unwatched" "$out/run"
echo "watched: the results of the run unwatched"
# Again, its agent stored: the page will not see it learn, and says how to train it again.
"$build/bin/afford" experiment goals --system GOALS --reps 1 --steps 2000 --quiet --run-prefix watch-again --watch --watch-port 0 \
  --keep-logs none --out "$out/again" --log-root "$out/logs" >"$out/again.log" 2>&1 || { cat "$out/again.log"; exit 1; }
grep -q -- "--watch: the page will not show 1 intrinsic run(s) learning: their agents were stored.*--no-reuse-agents" \
  "$out/again.log" || { cat "$out/again.log"; echo "--watch did not say the stored agent is not seen"; exit 1; }
echo "again: $(grep -o -- "--watch: the page will not show.*" "$out/again.log" | cut -c1-100)..."


# The log played: the controls; then, in the same browser, a page with no run (the keyless watcher below).
"$build/bin/afford" bus-key "$out/bus.key" >/dev/null
"$build/bin/afford" watch --lcm-url "$url" --bus-key "$out/bus.key" --port 8093 >"$out/watch-keyed.log" 2>&1 &
"$build/bin/afford" watch --lcm-url "$url" --port 8094 >"$out/watch-keyless.log" 2>&1 &
log=$(ls -d "$out"/logs/watch-goals-GOALS-s1)
"$build/bin/afford" watch --log "$log" --port 8091 --paused >"$out/watch-log.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-log.log" || { cat "$out/watch-log.log"; echo "afford watch --log never served"; exit 1; }
wait_until 30 grep -qs "the page:" "$out/watch-keyed.log" || { cat "$out/watch-keyed.log"; exit 1; }
wait_until 30 grep -qs "the page:" "$out/watch-keyless.log" || { cat "$out/watch-keyless.log"; exit 1; }
/usr/bin/python3 "$root/tests/watch/browser.py" playback http://127.0.0.1:8091/ "$out" http://127.0.0.1:8094/
# A run of the physical table played: the camera's image and the table's actions.
"$build/bin/afford" experiment table --system IMP --reps 1 --steps 60 --set table.truth.trials=2 --transport memq --quiet \
  --run-prefix watch --out "$out/table" --log-root "$out/logs" >"$out/table.log" 2>&1 || { cat "$out/table.log"; exit 1; }
"$build/bin/afford" watch --log "$out/logs/watch-table-IMP-s1" --port 8096 --paused >"$out/watch-table.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-table.log" || { cat "$out/watch-table.log"; exit 1; }
/usr/bin/python3 "$root/tests/watch/browser.py" table http://127.0.0.1:8096/ "$out" "$out/logs/watch-table-IMP-s1"

# Off loopback: the addresses printed open (this namespace has loopback alone), and the token.
"$build/bin/afford" watch --lcm-url "$url" --bind 0.0.0.0 --port 8092 >"$out/watch-bound.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-bound.log" || { cat "$out/watch-bound.log"; echo "afford watch --bind never served"; exit 1; }
page=$(sed -n 's/^the page: //p' "$out/watch-bound.log")
[[ $page == "http://127.0.0.1:8092/?token="* ]] || { cat "$out/watch-bound.log"; echo "the address printed: $page"; exit 1; }
! grep -q "0\.0\.0\.0" "$out/watch-bound.log" || { cat "$out/watch-bound.log"; echo "an address no one can open"; exit 1; }
/usr/bin/python3 "$root/tests/watch/browser.py" token "$page"
# A keyed bus: the watcher with the key follows the run, one without it shows nothing of it. The second watcher on a port in use is refused, naming it (the port is never shared).
second=0
timeout 10 "$build/bin/afford" watch --lcm-url "$url" --port 8094 >"$out/watch-second.log" 2>&1 || second=$?
[[ $second == 1 ]] || { cat "$out/watch-second.log"; echo "a second afford watch on port 8094: exit $second, not 1 (124: it served)"; exit 1; }
grep -q "cannot serve on 127.0.0.1:8094: Address already in use" "$out/watch-second.log" ||
  { cat "$out/watch-second.log"; echo "the second watcher's refusal does not name the port"; exit 1; }
echo "a second watcher on port 8094: refused ($(tail -1 "$out/watch-second.log"))"
# A scripts/procs.sh group on this bus (its folder as procs.sh keeps it: lcm-url, bus.key, a live process's pid
# and start time), found in its log root.
group=$out/groups/demo
mkdir -p "$group"
echo "$url" >"$group/lcm-url"
cp "$out/bus.key" "$group/bus.key"
sleep infinity &
echo $! >"$group/eye.pid"
awk '{print $22}' "/proc/$!/stat" >"$group/eye.started"
"$build/bin/afford" watch --log-root "$out/groups" --port 8095 >"$out/watch-group.log" 2>&1 &
wait_until 30 grep -qs "the page:" "$out/watch-group.log" || { cat "$out/watch-group.log"; exit 1; }
grep -q "watching group 'demo' (scripts/procs.sh): $url (keyed)" "$out/watch-group.log" ||
  { cat "$out/watch-group.log"; echo "afford watch did not find the group"; exit 1; }
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 300 --quiet --run-prefix keyed --netns off \
  --base-port "$port" --bus-key "$out/bus.key" --keep-logs none --out "$out/keyed" --log-root "$out/logs-keyed" \
  >"$out/keyed.log" 2>&1 || { cat "$out/keyed.log"; exit 1; }
# (the keyed watchers have the result once the run's RESULT came: the run's last step)
for p in 8093 8095; do
  wait_until 30 test "$(state http://127.0.0.1:$p)" = "keyed-base-IMP-s1 300" ||
    { echo "the keyed watcher on $p shows '$(state http://127.0.0.1:$p)'"; exit 1; }
done
[[ $(state http://127.0.0.1:8094) == " -1" ]] || { echo "a watcher without the key shows '$(state http://127.0.0.1:8094)'"; exit 1; }
echo "keyed: the watchers with the key (one found as the group's) followed the run to step 300, the one without it showed nothing"
echo "screenshots: $out/watch-live.png $out/watch-end.png $out/watch-playback.png $out/watch-idle.png $out/watch-table.png"
