#!/usr/bin/env bash
# One scripts/procs.sh group asked for the same run again and again: the same
# experiment, seed and --run-prefix, N times in a row, the earlier run's folder
# removed by `afford clean --all --delete`, moved aside, or kept (in turn). Each
# request must really run, with the first one's weights: every step in its log
# (its manifest complete, its PREDICTION events counted), its checkpoint
# written, a plausible speed. A kept folder is refused before anything runs,
# naming it, and nothing is reported. (With --no-reuse-agents each request
# runs; one that takes a stored agent says so, reused_from, and claims no log,
# speed or memory.) A group that had finished a run used to answer the next
# request of it with the earlier result: "done in 0.1 s", 1.78e9 steps a
# second, a checkpoint that did not exist.
#   tests/requests/same_id.sh BUILD_DIR WORK_DIR [N] [STEPS]
# Not a ctest test (it takes minutes): its figures are in docs/performance.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
n=${3:-100}
steps=${4:-2000}
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_LOGS=$out/logs AFFORD_GRACE=3
export AFFORD_URL="udpm://239.255.76.67:7731?ttl=0&recv_buf_size=2097152"
procs=$root/scripts/procs.sh
trap '"$procs" stop g >/dev/null 2>&1 || true' EXIT
"$procs" start g >/dev/null
"$procs" status g --wait-for environment,eye,predictors,motivation,planner,logger --state waiting --seconds 30 >/dev/null
id=exp1-base-IMP-s7
ran=0 refused=0 first=""
request() {  # LABEL: the same run again, into out-LABEL
  "$procs" run g base --system IMP --reps 1 --steps "$steps" --seed 7 --extrinsic-reps 0 --run-prefix exp1 \
    --no-reuse-agents --quiet --out "$out/out-$1" >"$out/run-$1.txt" 2>&1
}
for ((i = 1; i <= n; i++)); do
  request "$i" || { cat "$out/run-$i.txt"; echo "request $i failed"; exit 1; }
  read -r sum ckpt sps < <(/usr/bin/python3 - "$out/out-$i/summary.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["systems"]["IMP"]["runs"][0]
print(r["weights_checksum"], r["checkpoint"] or "-", r.get("steps_per_second", 0))
PY
)
  [[ -f $ckpt ]] || { cat "$out/run-$i.txt"; echo "request $i: its checkpoint $ckpt does not exist"; exit 1; }
  PYTHONPATH=$build/python /usr/bin/python3 - "$out/logs/$id" "$steps" "$sps" <<'PY' || { echo "request $i did not really run"; exit 1; }
import collections, json, sys
import afford
folder, steps, sps = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
m = json.load(open(folder + "/manifest.json"))
assert m["complete"], "its log is incomplete: " + m.get("incomplete", "")
n = collections.Counter(e.channel for e in afford.read_log(folder).messages)
assert n["PREDICTION"] == steps, f"{n['PREDICTION']} PREDICTION events in its log, not {steps}"
assert 0 < sps < 100000, f"{sps} steps a second"
PY
  [[ -n $first ]] || first=$sum
  [[ $sum == "$first" ]] || { echo "request $i: weights $sum, the first request's $first"; exit 1; }
  ran=$((ran + 1))
  case $(((i - 1) % 3)) in
    0) "$build/bin/afford" clean --log-root "$out/logs" --all --delete >"$out/clean-$i.txt" ;;
    1) mv "$out/logs/$id" "$out/logs/aside-$i" ;;
    2)  # kept: the same request again is refused before anything runs, naming the folder; then it goes
      if request "kept-$i"; then echo "a request whose run folder is kept was not refused"; exit 1; fi
      grep -q "the log folder $out/logs/$id exists already" "$out/run-kept-$i.txt" ||
        { cat "$out/run-kept-$i.txt"; echo "the refusal does not name the folder"; exit 1; }
      [[ ! -e $out/out-kept-$i/summary.json ]] || { echo "a refused request reported a run"; exit 1; }
      refused=$((refused + 1))
      rm -rf "${out:?}/logs/$id" ;;
  esac
done
echo "the same run id asked for $n times of one group: $ran ran (weights $first each time, every step in its" \
  "log, its checkpoint written); $refused more, with the earlier folder kept, refused up front naming it"
