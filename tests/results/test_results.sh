#!/usr/bin/env bash
# The results of a small experiment of every kind (tests/results/cases.txt)
# equal those recorded in tests/data/results/, but for timings, memory, sizes,
# paths and the network (tests/results/normalise.py): summary.json, checksums
# included, and every CSV file. A case marked @shards runs as two shards
# merged (afford merge), and must equal the same experiment run whole. Every
# summary.json reads through its structure and writes back the same.
#   tests/results/test_results.sh BUILD_DIR WORK_DIR [--write]
# --write records the results of this build as the expected ones.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
here=$root/tests/results
build=$(cd "$1" && pwd)
rm -rf "$2" && mkdir -p "$2"
out=$(cd "$2" && pwd)
write=${3:-}
expected=$root/tests/data/results
py=/usr/bin/python3
afford=$build/bin/afford
common=(--transport memq --quiet --keep-logs none --progress none)
failed=0
run() {  # run NAME OUT LOG_ROOT ARGS...
  local name=$1 dir=$2 logs=$3
  shift 3
  "$afford" experiment "$@" "${common[@]}" --run-prefix "results-$name" --out "$dir" --log-root "$logs" \
    --no-reuse-agents >"$dir.txt" 2>&1 || { echo "$name: afford experiment failed:"; tail -20 "$dir.txt"; exit 1; }
}
while IFS='|' read -r name args; do
  name=$(echo "$name" | xargs)
  [[ -z $name || $name == \#* ]] && continue
  read -r -a argv <<<"$args"
  shards=0
  for i in "${!argv[@]}"; do
    [[ ${argv[$i]} == @shards ]] && { shards=1; unset 'argv[i]'; }
    [[ ${argv[$i]:-} == *.yaml ]] && argv[$i]=$here/${argv[$i]}
  done
  if ((shards)); then
    run "$name" "$out/$name" "$out/$name-logs" "${argv[@]}"
    # The shards share a log root, as on a cluster's shared file system.
    run "$name" "$out/$name-0" "$out/$name-shard-logs" "${argv[@]}" --shard 0/2
    run "$name" "$out/$name-1" "$out/$name-shard-logs" "${argv[@]}" --shard 1/2
    "$afford" merge "$out/$name-0" "$out/$name-1" --out "$out/$name-merged" --quiet >"$out/$name-merged.txt" 2>&1 ||
      { echo "$name: afford merge failed:"; tail -20 "$out/$name-merged.txt"; exit 1; }
    "$py" "$here/normalise.py" "$out/$name-merged" >"$out/$name-merged.norm"
  else
    run "$name" "$out/$name" "$out/$name-logs" "${argv[@]}"
  fi
  "$py" "$here/normalise.py" "$out/$name" >"$out/$name.norm"
  # Every summary.json (a sweep's conditions' too) reads through its structure and writes back the same.
  mapfile -t summaries < <(find "$out/$name" "$out/$name-merged" -name summary.json -printf '%h\n' 2>/dev/null)
  "$build/bin/summary-roundtrip" "${summaries[@]}" || { echo "$name: a summary.json does not read back"; failed=1; }
  [[ $(wc -l <"$out/$name.norm") -gt 20 ]] || { echo "$name: hardly any results"; exit 1; }
  if [[ $write == --write ]]; then
    mkdir -p "$expected" && cp "$out/$name.norm" "$expected/$name.txt"
    echo "$name: recorded ($(wc -l <"$out/$name.norm") lines)"
    continue
  fi
  if ! diff -u "$expected/$name.txt" "$out/$name.norm" >"$out/$name.diff"; then
    echo "$name: the results differ from tests/data/results/$name.txt:"; head -40 "$out/$name.diff"; failed=1
  else
    echo "$name: equal ($(wc -l <"$out/$name.norm") lines)"
  fi
  if ((shards)); then
    if ! diff -u "$out/$name.norm" "$out/$name-merged.norm" >"$out/$name-merged.diff"; then
      echo "$name: two shards merged differ from the whole:"; head -40 "$out/$name-merged.diff"; failed=1
    else
      echo "$name: two shards merged equal the whole"
    fi
  fi
done <"$here/cases.txt"
exit $failed
