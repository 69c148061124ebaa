#!/usr/bin/env bash
# afford export, read by others: two stored extrinsic tests (tests/data/explain) and short runs
# of IMP and GOALS and of IMP on the physical table (memq, recorded here) exported as MCAP files (zstd chunks; one also without
# compression), each read with Foxglove's own reader by tools/mcapcheck/check.mjs (every record,
# the index, the summary, the CRCs, each message against its JSON Schema, each PNG by its signature,
# each image a message names on its topic), then every message compared with the run's
# log as the Python package decodes it (tests/mcap/compare.py): the same messages per channel at
# the same times with the same values, the images' pixels byte for byte. The same logs with their channels interleaved anew
# (shuffle-log: each channel in its own order, up to 1,000 steps apart, in two segments) give the same
# file, byte for byte. And an existing file is refused, untouched.
#   tests/mcap/test_mcap.sh BUILD_DIR WORK_DIR PYTHON_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
rm -rf "$2" && mkdir -p "$2"
out=$(cd "$2" && pwd)
python_dir=${3:-}
[[ -d $root/tools/mcapcheck/node_modules/@mcap/core && -d $root/tools/mcapcheck/node_modules/fzstd ]] ||
  { echo "no @mcap/core or fzstd in tools/mcapcheck: run npm ci --prefix tools/mcapcheck (scripts/setup.sh does)"; exit 1; }
[[ -n $python_dir && -f $python_dir/afford/__init__.py ]] ||
  { echo "no Python package in '$python_dir': configure with -DAFFORD_EXTRAS=ON and build afford_python"; exit 1; }

logs=()
for name in base-scenario3 multi-step-top-down-budget; do
  gzip -dc "$root/tests/data/explain/$name.lcm.gz" >"$out/$name.lcm"
  logs+=("$out/$name.lcm")
done
"$build/bin/afford" experiment base --system IMP,GOALS --reps 1 --steps 150 --transport memq --quiet --keep-logs all \
  --run-prefix mcap --out "$out/intrinsic" --log-root "$out/logs" >"$out/intrinsic.txt" 2>&1 ||
  { cat "$out/intrinsic.txt"; echo "the intrinsic and goals runs failed"; exit 1; }
logs+=("$out/logs/mcap-base-IMP-s1" "$out/logs/mcap-base-GOALS-s1")
# A run of the physical table (world.kind: table): the camera's 320 x 240 images, the table's actions.
"$build/bin/afford" experiment table --system IMP --reps 1 --steps 60 --set table.truth.trials=2 --transport memq --quiet \
  --keep-logs all --run-prefix mcap --out "$out/table" --log-root "$out/logs" >"$out/table.txt" 2>&1 ||
  { cat "$out/table.txt"; echo "the table run failed"; exit 1; }
logs+=("$out/logs/mcap-table-IMP-s1")

for log in "${logs[@]}"; do
  name=$(basename "$log" .lcm)
  "$build/bin/afford" export "$log" --mcap "$out/$name.mcap" >"$out/$name.export.txt" 2>&1 ||
    { cat "$out/$name.export.txt"; echo "afford export $log failed"; exit 1; }
  ! grep -q "^skipped" "$out/$name.export.txt" || { cat "$out/$name.export.txt"; echo "$name: messages skipped"; exit 1; }
  node "$root/tools/mcapcheck/check.mjs" "$out/$name.mcap" >"$out/$name.jsonl"
  tail -1 "$out/$name.jsonl"
  PYTHONPATH=$python_dir /usr/bin/python3 "$root/tests/mcap/compare.py" "$log" "$out/$name.jsonl" "$build/bin/afford"
done

# The goals run's chunks left uncompressed (--compression none): the same messages, a larger file.
name=mcap-base-GOALS-s1
"$build/bin/afford" export "${logs[3]}" --mcap "$out/$name.none.mcap" --compression none >"$out/$name.none.txt" 2>&1 ||
  { cat "$out/$name.none.txt"; echo "afford export --compression none failed"; exit 1; }
node "$root/tools/mcapcheck/check.mjs" "$out/$name.none.mcap" >"$out/$name.none.jsonl"
cmp <(head -n -1 "$out/$name.jsonl") <(head -n -1 "$out/$name.none.jsonl") ||
  { echo "the uncompressed file's messages are not the zstd file's"; exit 1; }
/usr/bin/python3 - "$out/$name.jsonl" "$out/$name.none.jsonl" <<'EOF'
import json, sys
zstd, none = (json.loads(open(f).read().splitlines()[-1])["totals"] for f in sys.argv[1:])
if (zstd["compression"], none["compression"]) != ("zstd", "") or not none["bytes"] > 2 * zstd["bytes"]:
    sys.exit(f"compression {zstd['compression']!r} ({zstd['bytes']} bytes) against {none['compression']!r} "
             f"({none['bytes']} bytes)")
print(f"{sys.argv[2]}: the same messages uncompressed, {none['bytes']} bytes against zstd's {zstd['bytes']}")
EOF

# A log shuffled: the same file (exported from a folder of the same name, so that the log's path in the
# file's metadata is the same too).
for log in "${logs[1]}" "${logs[2]}"; do
  name=$(basename "$log" .lcm)
  mkdir -p "$out/as-recorded/$name" "$out/shuffled/$name"
  cp -r "$log" "$out/as-recorded/$name/log"
  "$build/bin/shuffle-log" "$log" "$out/shuffled/$name/log" --window 1000 --segments 2 >"$out/shuffled/$name.txt"
  for kind in as-recorded shuffled; do
    (cd "$out/$kind/$name" && "$build/bin/afford" export log --mcap run.mcap >export.txt 2>&1) ||
      { cat "$out/$kind/$name/export.txt"; echo "afford export of the $kind $name failed"; exit 1; }
  done
  cmp "$out/as-recorded/$name/run.mcap" "$out/shuffled/$name/run.mcap" ||
    { cat "$out/shuffled/$name.txt"; echo "$name shuffled: another file"; exit 1; }
  echo "$name shuffled ($(cat "$out/shuffled/$name.txt")): the same file"
done

# The same file again: refused, and the file as it was.
before=$(sha256sum <"$out/base-scenario3.mcap")
if "$build/bin/afford" export "${logs[0]}" --mcap "$out/base-scenario3.mcap" >"$out/again.txt" 2>&1; then
  echo "an existing file was not refused"; exit 1
fi
grep -q "base-scenario3.mcap exists" "$out/again.txt" || { cat "$out/again.txt"; echo "the refusal does not say why"; exit 1; }
[[ $(sha256sum <"$out/base-scenario3.mcap") == "$before" && ! -e $out/base-scenario3.mcap.partial ]] ||
  { echo "the existing file was changed"; exit 1; }
echo "an existing file is refused and left as it was"
