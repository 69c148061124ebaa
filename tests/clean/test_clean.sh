#!/usr/bin/env bash
# afford clean beside real experiments (memq): a run going on, a run cut by
# SIGINT (its experiment says to --resume) and the runs of the resumed
# experiment are never offered, each left alone with its reason; once the
# experiment has finished, its runs are offered.
#   tests/clean/test_clean.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
afford=$build/bin/afford
logs=$out/logs run=$out/logs/c-base-IMP-s3

# listed WHAT: afford clean's listing of the log root (--all, or what is given), into $out/clean-WHAT.txt.
listed() {
  local name=$1
  shift
  "$afford" clean --log-root "$logs" "${@:---all}" >"$out/clean-$name.txt"
}
offers() { grep -q "^would remove .*$logs/$2\$" "$out/clean-$1.txt"; }
fail() { cat "$out/clean-$1.txt"; echo "$2"; exit 1; }

experiment=(experiment base --transport memq --system IMP --reps 2 --seed 3 --steps 3000 --no-reuse-agents
  --run-prefix c --out "$out/exp" --log-root "$logs" --quiet --progress none)
"$afford" "${experiment[@]}" >"$out/first.txt" 2>&1 &
runner=$!
wait_until 60 test -f "$run/manifest.json" || { cat "$out/first.txt"; echo "the first run never began its log"; exit 1; }
listed going
offers going c-base-IMP-s3 && fail going "clean offers a run going on"
grep -q "^left alone .*$run: its experiment is running (in $out/exp)" "$out/clean-going.txt" ||
  fail going "clean does not say the run's experiment is running"
listed going-base --experiment base
offers going-base c-base-IMP-s3 && fail going-base "clean --experiment base offers a run going on"

kill -INT "$runner"
rc=0
wait "$runner" || rc=$?
((rc == 130)) || { cat "$out/first.txt"; echo "SIGINT: exit $rc, not 130"; exit 1; }
grep -q '"complete": false' "$run/manifest.json" || { echo "the cut run's log is not marked incomplete"; exit 1; }
listed cut
offers cut c-base-IMP-s3 && fail cut "clean offers a run cut by SIGINT, which --resume continues"
grep -q "^left alone .*$run: its experiment (in $out/exp) stopped before it finished (interrupted by SIGINT):" \
  "$out/clean-cut.txt" && grep -q "experiment --resume --out $out/exp\` (in $(pwd -P)) continues it$" "$out/clean-cut.txt" ||
  fail cut "clean does not say the cut run's experiment is resumable, and how"

"$afford" experiment --resume --out "$out/exp" >"$out/resumed.txt" 2>&1 &
runner=$!
wait_until 60 test -f "$run/manifest.json" -a -d "$run.cut-1" ||
  { cat "$out/resumed.txt"; echo "the resumed run never began its log"; exit 1; }
listed resumed
offers resumed c-base-IMP-s3 && fail resumed "clean offers the resumed experiment's run"
offers resumed c-base-IMP-s3.cut-1 && fail resumed "clean offers the cut run while its experiment runs again"
wait "$runner" || { cat "$out/resumed.txt"; echo "the resumed experiment failed"; exit 1; }

listed finished
for r in c-base-IMP-s3 c-base-IMP-s3.cut-1 c-base-IMP-s4; do
  offers finished "$r" || fail finished "the finished experiment's $r is not offered"
done
echo "afford clean: a run going on, a cut and resumable run, a resumed experiment's runs left alone; offered once finished"
