#!/usr/bin/env bash
# afford-viewer on a live run, under Xvfb: a screenshot of its window is not
# blank, and --png writes the same frames as files. Both stay as artefacts.
#   tests/viewer/test_viewer.sh BUILD_DIR ARTEFACT_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
start_xvfb 1400x1000 "$out/xvfb.log"

port=7991
url="udpm://239.255.76.67:$port?ttl=0"
rm -rf "$out/frames"
"$build/bin/afford-viewer" --lcm-url "$url" >"$out/viewer-window.log" 2>&1 &
"$build/bin/afford-viewer" --lcm-url "$url" --png "$out/frames" --every 250 >"$out/viewer-png.log" 2>&1 &
# Both viewers listen (they say so once subscribed) before the run's first message.
for v in window png; do
  wait_until 30 grep -q "watching" "$out/viewer-$v.log" || { cat "$out/viewer-$v.log"; echo "the $v viewer never listened"; exit 1; }
done
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 6000 --extrinsic-reps 1 --scenarios scenario3 \
  --netns off --base-port "$port" --keep-logs none --quiet --out "$out/run" --log-root "$out/logs" \
  --run-prefix viewer >"$out/run.log" 2>&1 &
run=$!
# Mid-run: once the window viewer shows the run and the environment runs it.
wait_until 60 grep -q "showing run" "$out/viewer-window.log" || { cat "$out/viewer-window.log"; echo "the viewer never showed the run"; exit 1; }
"$build/bin/afford" status --lcm-url "$url" --wait-for environment --state running --seconds 60 >/dev/null ||
  { cat "$out/run.log"; echo "the run never started"; exit 1; }
import -window root "$out/viewer-during-run.png"
wait "$run" || { echo "the run failed:"; cat "$out/run.log"; exit 1; }
import -window root "$out/viewer.png"
sd=$(convert "$out/viewer-during-run.png" -colorspace Gray -format '%[fx:standard_deviation]' info:)
echo "screenshot: $out/viewer-during-run.png (grey standard deviation $sd)"
awk -v sd="$sd" 'BEGIN { exit !(sd > 0.05) }' || { echo "the screenshot is blank"; exit 1; }
frames=$(ls "$out/frames" | wc -l)
echo "frames written: $frames"
# 6000 intrinsic steps at one frame per 250, and the extrinsic test's first frame.
[[ $frames -ge 20 ]] || { echo "too few frames"; ls "$out/frames"; exit 1; }
ls "$out/frames" | grep -q -- "-scenario3-e0_" || { echo "no frame of the extrinsic test"; exit 1; }
# Each run is announced once, however often the runner says its configuration (2 runs: the intrinsic and the test).
shown=$(grep -c "showing run" "$out/viewer-window.log")
[[ $shown -eq 2 ]] || { grep "showing run" "$out/viewer-window.log"; echo "'showing run' said $shown times for 2 runs"; exit 1; }
