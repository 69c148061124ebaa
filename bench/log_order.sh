#!/usr/bin/env bash
# What the tools make of a long run's log does not depend on how its channels are interleaved
# (docs/watching.md): one intrinsic run of IMP recorded with its log, the same log with its channels
# up to --window steps apart (shuffle-log, tests/logorder/shuffle.hpp: each channel in its own
# order, in two segments), then afford render's frames (ffmpeg's framemd5 of each), afford export's
# file (byte for byte) and afford.read_log's messages compared, with the wall time and peak memory
# of render and export on each log.
#   bench/log_order.sh [--build DIR] [--steps N] [--window W] [--out DIR]
# Defaults: --build build, --steps 6000, --window 1000, --out out/bench-log-order (made anew). The build
# needs shuffle-log (built with the tests) and, for read_log, the Python package.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build steps=6000 window=1000 out=out/bench-log-order
while (($#)); do
  case $1 in
    --build) build=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "log_order.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
for p in afford shuffle-log; do
  [[ -x $build/bin/$p ]] || { echo "no $build/bin/$p: build it first (with the tests)" >&2; exit 1; }
done
build=$(cd "$build" && pwd)
rm -rf "$out" && mkdir -p "$out"
out=$(cd "$out" && pwd)

"$build/bin/afford" experiment base --system IMP --reps 1 --steps "$steps" --transport memq --quiet --keep-logs all \
  --no-reuse-agents --run-prefix order --out "$out/run" --log-root "$out/logs" >"$out/run.txt" 2>&1 ||
  { cat "$out/run.txt"; echo "the run failed" >&2; exit 1; }
mkdir -p "$out/recorded" "$out/shuffled"
cp -r "$out/logs/order-base-IMP-s1" "$out/recorded/log"
"$build/bin/shuffle-log" "$out/recorded/log" "$out/shuffled/log" --window "$window" --segments 2 | tee "$out/shuffle.txt"

# Each tool on each log, from the log's own folder (the same relative path: the same metadata in the file).
for kind in recorded shuffled; do
  (cd "$out/$kind" &&
    /usr/bin/time -f "%e s, %M KB" -o render.time "$build/bin/afford" render log --out run.mp4 >render.txt 2>&1 &&
    /usr/bin/time -f "%e s, %M KB" -o export.time "$build/bin/afford" export log --mcap run.mcap >export.txt 2>&1) ||
    { cat "$out/$kind"/*.txt; echo "a tool failed on the $kind log" >&2; exit 1; }
  ffmpeg -v error -i "$out/$kind/run.mp4" -f framemd5 - | grep -v '^#' >"$out/$kind/frames.md5"
  printf '%s: render %s (%s), export %s\n' "$kind" "$(cat "$out/$kind/render.time")" \
    "$(grep '^wrote' "$out/$kind/render.txt" | sed 's/^wrote [^:]*: //')" "$(cat "$out/$kind/export.time")"
done
cmp -s "$out/recorded/frames.md5" "$out/shuffled/frames.md5" ||
  { echo "render: the shuffled log's frames differ" >&2; exit 1; }
echo "render: the same $(wc -l <"$out/recorded/frames.md5") frames, decoded"
cmp "$out/recorded/run.mcap" "$out/shuffled/run.mcap" || { echo "export: another file" >&2; exit 1; }
echo "export: the same file, $(stat -c %s "$out/recorded/run.mcap") bytes"
if [[ -f $build/python/afford/__init__.py ]]; then
  PYTHONPATH=$build/python /usr/bin/python3 - "$out/recorded/log" "$out/shuffled/log" <<'EOF'
import sys, time
import numpy as np
import afford
t = time.perf_counter()
a = afford.read_log(sys.argv[1])
ta = time.perf_counter() - t
t = time.perf_counter()
b = afford.read_log(sys.argv[2])
tb = time.perf_counter() - t
same = len(a) == len(b) and all(x.channel == y.channel and all(
    np.array_equal(x[k], y[k]) if isinstance(x[k], np.ndarray) else x[k] == y[k] for k in x.fields) for x, y in zip(a, b))
if not same:
    sys.exit("read_log: the shuffled log's messages differ")
print(f"read_log: the same {len(a)} messages in the same order ({ta:.2f} s, shuffled {tb:.2f} s)")
EOF
fi
