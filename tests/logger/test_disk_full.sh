#!/usr/bin/env bash
# A full disk under the logger: hand-started processes, the logger writing on
# a 256 KB tmpfs, a run whose log does not fit. The run must fail with a clear
# message naming the logger and the write that failed; the logger must stay
# alive; the run's manifest must say it is incomplete; and once there is room
# again, the same logger must record the next run whole.
#   tests/logger/test_disk_full.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_mount_namespace "$0" "$@"  # for the file systems it mounts
enter_test "$0" "$@"
url="udpm://239.255.76.67:7998?ttl=0&recv_buf_size=2097152"
disk="$out/disk"
mkdir -p "$disk"
mount -t tmpfs -o size=256k tmpfs "$disk"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; umount -l "$disk" 2>/dev/null || true' EXIT

for p in $("$build/bin/afford" processes --phase intrinsic --no-logger); do
  extra=()
  [[ $p == predictors ]] && extra=(--checkpoint-dir "$out/checkpoints")  # the runner's --log-root
  "$build/bin/afford-$p" --lcm-url "$url" "${extra[@]}" >"$out/$p.log" 2>&1 &
done
"$build/bin/afford-logger" --lcm-url "$url" --log-dir "$disk/logs" >"$out/logger.log" 2>&1 &
logger=$!
for _ in $(seq 100); do
  (($("$build/bin/afford" status --lcm-url "$url" --seconds 0.6 | grep -c -E "^(environment|eye|predictors|motivation|logger) ") >= 5)) && break
done

# 3000 steps make a log of about 10 MB: the disk fills during the run.
set +e
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 3000 --quiet --attach "$url" --run-prefix full \
  --out "$out/full" --log-root "$out/checkpoints" >"$out/full.txt" 2>&1
rc=$?
set -e
cat "$out/full.txt"
((rc != 0)) || { echo "the run succeeded although its log did not fit"; exit 1; }
grep -q "process 'logger' failed: .*cannot write to log file .*No space left on device" "$out/full.txt" ||
  { echo "the failure does not say the logger could not write"; exit 1; }
kill -0 "$logger" 2>/dev/null || { echo "the logger is gone"; exit 1; }
manifest="$disk/logs/full-base-IMP-s1/manifest.json"
grep -q '"complete": false' "$manifest" || { cat "$manifest"; echo "the manifest does not say incomplete"; exit 1; }
echo "the run failed naming the write; the logger is alive; the manifest says incomplete"

# Room again: the same logger records the next run whole.
mount -o remount,size=64m "$disk"
"$build/bin/afford" experiment base --system IMP --reps 1 --steps 100 --quiet --attach "$url" --run-prefix room \
  --out "$out/room" --log-root "$out/checkpoints" >"$out/room.txt" 2>&1 || { cat "$out/room.txt"; exit 1; }
grep -q '"complete": true' "$disk/logs/room-base-IMP-s1/manifest.json" || { echo "the next run's log is not complete"; exit 1; }
grep -q "$logger" <(pgrep -f afford-logger) || { echo "another logger recorded it"; exit 1; }
"$build/bin/afford" replay "$disk/logs/room-base-IMP-s1" | tail -1
echo "the same logger (pid $logger) recorded the next run whole"
