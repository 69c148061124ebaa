#!/usr/bin/env bash
# What a run must leave, it leaves, or the run says why not. A read-only log root (a read-only tmpfs: root
# cannot write there either) with --run-prefix and --keep-logs none is refused before anything runs, naming
# the folder and the error. Predictors that cannot write the run's checkpoint (their log root is a tmpfs too
# small for it) fail the run, on the terminal and in summary.json, naming the checkpoint and where their log is.
#   tests/folders/test_unwritable.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_mount_namespace "$0" "$@"  # for the file systems it mounts
enter_test "$0" "$@"
fail() { echo "$*"; exit 1; }
mkdir -p "$out/ro" "$out/logs"
mount -t tmpfs -o ro,size=64k tmpfs "$out/ro"
# Room for the runner's claims (run.json), not for a checkpoint (about 1 MB).
mount -t tmpfs -o size=128k tmpfs "$out/logs"
trap 'kill $(jobs -p) 2>/dev/null || true; umount -l "$out/ro" 2>/dev/null || true; umount -l "$out/logs" 2>/dev/null || true' EXIT

code=0
"$build/bin/afford" experiment base --system FIX --reps 1 --steps 100 --transport memq --run-prefix p \
  --keep-logs none --log-root "$out/ro" --out "$out/ro-out" --quiet --progress none >"$out/ro.txt" 2>&1 || code=$?
[[ $code -ne 0 ]] || { cat "$out/ro.txt"; fail "an experiment on a read-only log root exited 0"; }
grep -q "cannot make the log folder $out/ro/p-base-FIX-s1 (Read-only file system)" "$out/ro.txt" ||
  { cat "$out/ro.txt"; fail "the refusal does not name the folder and the error"; }
[[ ! -e $out/ro-out/summary.json ]] || fail "an experiment that could not claim its folders wrote a summary"

# The predictors cannot write the checkpoint where the runner could claim the run's folder.
code=0
"$build/bin/afford" experiment base --system FIX --reps 1 --steps 200 --keep-logs none --netns off --base-port 7721 \
  --run-prefix q --log-root "$out/logs" --out "$out/b" --quiet --progress none \
  >"$out/b.txt" 2>&1 || code=$?
[[ $code -eq 1 ]] || { cat "$out/b.txt"; fail "a run whose checkpoint was not written: exit $code, not 1"; }
said="run 'q-base-FIX-s1': its checkpoint $out/logs/q-base-FIX-s1/predictors.ckpt was not written (the predictors"
said+=" reported they could not write it; their log says why: $out/b/processes/slot0/predictors.log)"
grep -qF "$said" "$out/b.txt" || { cat "$out/b.txt"; fail "the terminal does not say which file is missing and why"; }
grep -qF "$said" "$out/b/summary.json" || fail "summary.json does not hold the run's failure"
grep -q "No space left on device" "$out/b/processes/slot0/predictors.log" || fail "the predictors' log does not say why"
echo "a run's missing files are its failure, said where the user looks"
