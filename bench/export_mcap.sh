#!/usr/bin/env bash
# afford export's speed and size (docs/watching.md): one run of a system (IMP: intrinsic; GOALS: its
# own goals) recorded over real processes (udpm, `afford experiment`), its log exported as an MCAP
# file, the export's wall time beside the run's own, the file's bytes a step (and its chunks' records
# before compression), and the file read by tools/mcapcheck/check.mjs (Foxglove's reader, every CRC),
# whose messages per channel must be the log's (afford export's own count, and the Python package's
# when the build has it).
#   bench/export_mcap.sh [--build DIR] [--system IMP|GOALS|...] [--steps N] [--transport udpm|memq]
#                        [--compression zstd|none] [--out DIR]
# Defaults: --build build, --system IMP, --steps 6000, --transport udpm, --compression zstd (the export's),
# --out out/bench-export-mcap (made anew).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build system=IMP steps=6000 transport=udpm compression=zstd out=out/bench-export-mcap
while (($#)); do
  case $1 in
    --build) build=$2; shift 2 ;;
    --system) system=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    --transport) transport=$2; shift 2 ;;
    --compression) compression=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "export_mcap.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ -x $build/bin/afford ]] || { echo "no $build/bin/afford: build it first (scripts/setup.sh)" >&2; exit 1; }
[[ -d tools/mcapcheck/node_modules/@mcap/core && -d tools/mcapcheck/node_modules/fzstd ]] || npm ci --prefix tools/mcapcheck --no-audit --no-fund --loglevel=error
rm -rf "$out" && mkdir -p "$out"
now() { date +%s.%N; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }

t0=$(now)
"$build/bin/afford" experiment base --system "$system" --reps 1 --steps "$steps" --transport "$transport" --quiet \
  --keep-logs all --no-reuse-agents --run-prefix mcap --out "$out/run" --log-root "$out/logs" >"$out/run.txt" 2>&1 ||
  { cat "$out/run.txt"; echo "the run failed" >&2; exit 1; }
t1=$(now)
log=$out/logs/mcap-base-$system-s1
/usr/bin/time -o "$out/export.time" -f "%U %S %M" "$build/bin/afford" export "$log" --mcap "$out/run.mcap" --compression "$compression" >"$out/export.txt" 2>&1 ||
  { cat "$out/export.txt"; echo "the export failed" >&2; exit 1; }
t2=$(now)
node tools/mcapcheck/check.mjs "$out/run.mcap" --digest >"$out/check.jsonl"
t3=$(now)

run_s=$(seconds "$t0" "$t1") export_s=$(seconds "$t1" "$t2") check_s=$(seconds "$t2" "$t3")
log_bytes=$(du -cb "$log"/*.lcm | tail -1 | cut -f1)
mcap_bytes=$(stat -c %s "$out/run.mcap")
cat "$out/export.txt"
# Every channel's count in the checked file against the export's count of the log's messages.
/usr/bin/python3 - "$out/check.jsonl" "$out/export.txt" <<'EOF'
import json, re, sys
totals = json.loads(open(sys.argv[1]).read().splitlines()[-1])["totals"]
said = {m.group(1): int(m.group(2)) for m in re.finditer(r"^  (\S+) +\S+ +(\d+)", open(sys.argv[2]).read(), re.M)}
if totals["per_topic"] != said:
    sys.exit(f"the checked file's messages {totals['per_topic']} are not the export's {said}")
print(f"checked: {totals['messages']} messages on {totals['channels']} channels in {totals['chunks']} chunks, "
      "each channel's count the export's")
EOF
if [[ -f $build/python/afford/__init__.py ]]; then
  PYTHONPATH=$build/python /usr/bin/python3 - "$log" "$out/check.jsonl" <<'EOF'
import json, sys
import afford
totals = json.loads(open(sys.argv[2]).read().splitlines()[-1])["totals"]
log = afford.read_log(sys.argv[1])
counts = {}
for m in log:
    counts[m.channel] = counts.get(m.channel, 0) + 1
exported = {t: n for t, n in totals["per_topic"].items() if not t.startswith("/")}
if counts != exported or log.refused:
    sys.exit(f"the log's messages {counts} (refused {log.refused}) are not the file's {exported}")
print(f"the Python package reads the same {sum(counts.values())} messages from the log")
EOF
fi
own_s=$(/usr/bin/python3 -c 'import json, sys; print("%.2f" % json.load(open(sys.argv[1]))["systems"][sys.argv[2]]["runs"][0]["wall_seconds"])' \
  "$out/run/summary.json" "$system")
chunks=$(/usr/bin/python3 - "$out/check.jsonl" <<'EOF'
import json, sys
t = json.loads(open(sys.argv[1]).read().splitlines()[-1])["totals"]
print(f"{t['chunks']} chunks, compression {t['compression'] or 'none'}, {t['record_bytes']} bytes of records before it")
EOF
)
printf '%s\n' \
  "system: $system, steps: $steps ($transport)" \
  "run (afford experiment, wall): ${run_s} s; the run's own wall_seconds (summary.json): ${own_s} s" \
  "export (afford export, wall): ${export_s} s ($(awk -v e="$export_s" -v r="$own_s" 'BEGIN { printf "%.0f", 100 * e / r }')% of the run's own time)" \
  "export's CPU: $(awk '{ printf "%.2f s, peak memory %.0f MB", $1 + $2, $3 / 1024 }' "$out/export.time")" \
  "check (node check.mjs, wall): ${check_s} s" \
  "log: ${log_bytes} bytes; mcap: ${mcap_bytes} bytes, $((mcap_bytes / steps)) bytes a step ($chunks)" |
  tee "$out/figures.txt"
