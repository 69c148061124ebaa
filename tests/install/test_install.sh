#!/usr/bin/env bash
# An installed copy works anywhere: `cmake --install BUILD --prefix DIR`, DIR
# copied to another folder, and the source folder hidden (a mount namespace
# lays an empty folder over it). From the copy, `afford experiments`,
# `afford config` and an experiment over memq and over udpm (the copy's own
# processes) run with the copy's config, the run equals the build's, and
# scripts/procs.sh of the copy starts and stops a group of the copy's
# processes. The types jar for lcm-spy is in the copy. The copy's config
# carries a mark (a protocol value that changes no result) that `afford
# config` must show: the copy reads its own config, not the source's. Where no
# private mount namespace can be made (a chroot whose root is no mount point),
# the source folder stays visible and the mark alone tells.
#   tests/install/test_install.sh BUILD_DIR WORK_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
if [[ -z ${AFFORD_TEST_MOUNTNS:-} ]]; then
  enter_test "$0" "$@"
  cmake --install "$build" --prefix "$out/prefix" >"$out/install.txt"
  copy=$(mktemp -d /tmp/afford-installed.XXXXXX)
  trap 'rm -rf "$copy"' EXIT
  cp -a "$out/prefix/." "$copy/"
  sed -i 's/^  resend_batch: 64 /  resend_batch: 63 /' "$copy/share/afford/config/defaults.yaml"
  grep -q "^  resend_batch: 63 " "$copy/share/afford/config/defaults.yaml" || { echo "the copy's config has no mark"; exit 1; }
  # The build's run, for comparison, before the source folder is hidden.
  "$build/bin/afford" experiment base --system IMP --reps 1 --steps 400 --transport memq --quiet --keep-logs none \
    --out "$copy/work/build-run" --log-root "$copy/work/build-logs" >/dev/null
  if unshare --mount --propagation private true 2>/dev/null; then
    AFFORD_TEST_MOUNTNS=hide unshare --mount --propagation private bash "$0" "$build" "$out" "$copy"
  else
    echo "no private mount namespace here: the source folder stays visible; the copy's mark tells"
    AFFORD_TEST_MOUNTNS=visible bash "$0" "$build" "$out" "$copy"
  fi
  exit
fi
build=$1 out=$2 copy=$3
if [[ $AFFORD_TEST_MOUNTNS == hide ]]; then
  mount -t tmpfs none "$root"  # the source folder (and the build inside it) is empty from here on
  [[ ! -e $root/config/defaults.yaml && ! -e $build/bin/afford ]] || { echo "the source folder is still visible"; exit 1; }
fi
cd "$copy/work"
bin=$copy/bin
"$bin/afford" experiments | tee experiments.txt | head -3
grep -q "^base" experiments.txt || { echo "the copy lists no experiment base"; exit 1; }
"$bin/afford" config base --system IMP >config.txt
grep -q "leak: 0.1" config.txt || { echo "the copy's afford config shows no motivation.leak"; exit 1; }
grep -q "resend_batch: 63" config.txt || { echo "the copy's afford config is not the copy's (no mark)"; exit 1; }
checksum() { grep -o '"weights_checksum": "[0-9a-f]*"' "$1/summary.json" | head -1 | grep -o '[0-9a-f]\{16\}'; }
for transport in memq udpm; do
  AFFORD_NETNS=none "$bin/afford" experiment base --system IMP --reps 1 --steps 400 --transport $transport --quiet \
    --keep-logs none --out "run-$transport" --log-root "logs-$transport" >"run-$transport.txt" 2>&1 ||
    { cat "run-$transport.txt"; echo "the copy's afford experiment over $transport failed"; exit 1; }
  [[ $(checksum "run-$transport") == $(checksum build-run) ]] ||
    { echo "over $transport the copy gave $(checksum "run-$transport"), the build $(checksum build-run)"; exit 1; }
done
echo "the installed copy's runs over memq and udpm: weights $(checksum run-udpm), the build's"
# procs.sh of the copy: the copy's processes, logs in the working folder.
export AFFORD_NETNS=none AFFORD_URL="udpm://239.255.76.67:7995?ttl=0" AFFORD_GRACE=3
"$copy/share/afford/scripts/procs.sh" start mine >start.txt
"$copy/share/afford/scripts/procs.sh" status mine --wait-for environment,eye,predictors,motivation,planner,logger \
  --state waiting --seconds 30 >status.txt || { cat start.txt status.txt; echo "the copy's group did not come up"; exit 1; }
grep -q "$copy/bin/afford-eye" "logs/mine/eye.cmd" || { cat logs/mine/eye.cmd; echo "procs.sh did not start the copy's eye"; exit 1; }
"$copy/share/afford/scripts/procs.sh" stop mine >/dev/null
[[ -f $copy/share/afford/java/afford-lcmtypes.jar ]] || { echo "no types jar for lcm-spy in the copy"; exit 1; }
echo "procs.sh of the copy started and stopped the copy's processes; the types jar is there"
