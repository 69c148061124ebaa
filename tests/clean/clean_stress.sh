#!/usr/bin/env bash
# afford clean, listing every 0.2 s, while runs go on in one log root: three
# experiments (memq; one stopped by SIGINT in its first run and resumed at
# once; udpm, the runner's own processes) and a scripts/procs.sh group's runs.
# A stress script (not part of ctest). It fails if a listing ever offers a
# folder whose experiment had not finished when the listing ended (its
# process exited, or its experiment.json says "finished"; the group's own
# folder never); those that finished while the listing ran are counted apart,
# and if, once all have finished, their runs are not all offered. The
# interrupted experiment stays interrupted for a few listings before it is
# resumed. Prints the listings' figures.
#   tests/clean/clean_stress.sh BUILD_DIR WORK_DIR [STEPS]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/tests/netns.sh"
enter_test "$0" "$@"
steps=${3:-5000}
afford=$build/bin/afford logs=$out/logs
export AFFORD_NETNS=none AFFORD_BIN=$build/bin AFFORD_LOGS=$logs AFFORD_GRACE=3
export AFFORD_URL="udpm://239.255.76.67:7510?ttl=0&recv_buf_size=2097152"
# The group's processes are procs.sh's: whatever happens, they end with this script.
trap 'kill $(jobs -p) 2>/dev/null || true; "$root/scripts/procs.sh" kill g environment eye predictors motivation planner logger >/dev/null 2>&1 || true' EXIT
common=(--reps 2 --steps "$steps" --no-reuse-agents --quiet --progress none --log-root "$logs")
done_mark() { touch "$out/done-$1"; }
listed() { (($(cat "$out/listings") >= $1)); }  # the poller has made $1 listings

# The owners: e1, e2 (interrupted, then resumed), e3 (udpm) and g (the group's runs); each marks itself done.
("$afford" experiment base --transport memq --system IMP --extrinsic-reps 1 --scenarios scenario1 "${common[@]}" \
  --run-prefix e1 --out "$out/e1" >"$out/e1.txt" 2>&1 && done_mark e1) &
(
  "$afford" experiment base --transport memq --system FIX "${common[@]}" --run-prefix e2 --out "$out/e2" \
    >"$out/e2.txt" 2>&1 &
  runner=$!
  wait_until 120 test -f "$logs/e2-base-FIX-s1/manifest.json" || exit 1
  kill -INT "$runner"
  rc=0
  wait "$runner" || rc=$?
  echo "e2 stopped by SIGINT: exit $rc" >"$out/e2-interrupted.txt"
  # Interrupted for three listings (the poller counts them in $out/listings), then resumed.
  after=$(($(cat "$out/listings") + 3))
  wait_until 120 listed "$after"
  "$afford" experiment --resume --out "$out/e2" >"$out/e2-resumed.txt" 2>&1 && done_mark e2
) &
("$afford" experiment base --system FIX --netns off --base-port 7520 "${common[@]}" --run-prefix e3 --out "$out/e3" \
  >"$out/e3.txt" 2>&1 && done_mark e3) &
(
  "$root/scripts/procs.sh" start g >"$out/g-start.txt"
  "$root/scripts/procs.sh" status g --wait-for environment,eye,predictors,motivation,planner,logger --state waiting \
    --seconds 60 >/dev/null
  "$root/scripts/procs.sh" run g base --system IMP "${common[@]:0:6}" --out "$out/g1" >"$out/g1.txt" 2>&1 &&
    done_mark g1 &&
    "$root/scripts/procs.sh" run g base --system FIX "${common[@]:0:6}" --out "$out/g2" >"$out/g2.txt" 2>&1 &&
    done_mark g2
) &
owners=(e1 e2 e3 g1 g2)

# The listings: every folder offered must be of an experiment finished by the listing's end (before it began, or
# while it ran: counted apart).
listings=0 bad=0 offered=0 during=0 alone=0 most=0
echo 0 >"$out/listings"
declare -A why
: >"$out/times.txt"
finished() { [[ -f $out/done-$1 ]] || grep -q '^  "state": "finished"' "$out/$1/experiment.json" 2>/dev/null; }
all_done() { local o; for o in "${owners[@]}"; do [[ -f $out/done-$o ]] || return 1; done; }
owner_of() {  # a folder of the log root -> its experiment (by its run prefix), or "" for what none made
  case $1 in
    g) echo "g (the group's folder)" ;;
    g-2-*) echo g2 ;;
    g-*) echo g1 ;;
    e1-* | e2-* | e3-*) echo "${1%%-*}" ;;
    *) echo "" ;;
  esac
}
while :; do
  before=()
  for o in "${owners[@]}"; do finished "$o" && before+=("$o"); done
  last=no
  all_done && last=yes
  t0=$(date +%s%N)
  : >"$out/listing.txt"
  if [[ -d $logs ]] && ! "$afford" clean --log-root "$logs" --all >"$out/listing.txt" 2>&1; then
    cat "$out/listing.txt"
    echo "afford clean failed"
    bad=$((bad + 1))
  fi
  echo $((($(date +%s%N) - t0) / 1000000)) >>"$out/times.txt"
  listings=$((listings + 1))
  echo "$listings" >"$out/listings.part" && mv "$out/listings.part" "$out/listings"  # whole when read
  n=$(grep -c "^would remove \|^left alone " "$out/listing.txt" || true)
  ((n > most)) && most=$n
  while read -r path; do
    name=${path##*/}
    o=$(owner_of "$name")
    [[ -z $o ]] && continue
    offered=$((offered + 1))
    if [[ " ${before[*]} " != *" $o "* ]]; then
      if finished "$o"; then during=$((during + 1)); continue; fi
      bad=$((bad + 1))
      echo "listing $listings offers $name, whose experiment $o had not finished:"
      grep "$name" "$out/listing.txt"
    fi
  done < <(awk '/^would remove / {print $NF}' "$out/listing.txt")
  while read -r reason; do
    alone=$((alone + 1))
    why[$reason]=$((${why[$reason]:-0} + 1))
  done < <(sed -n 's/^left alone .* MB  [^:]*: //p' "$out/listing.txt" | sed -E 's/\((in|running:) [^)]*\)/(\1 ...)/g' |
    cut -c1-72)
  [[ $last == yes ]] && break
  # Every owner gone without finishing: stop.
  if ! jobs -r | grep -q .; then all_done || { echo "an owner failed: see $out/*.txt"; bad=$((bad + 1)); break; }; fi
  # The next listing 0.2 s after this one began (at once if this one took longer).
  wait_ms=$((200 - ($(date +%s%N) - t0) / 1000000))
  ((wait_ms > 0)) && { read -r -t "0.$(printf '%03d' "$wait_ms")" <> <(:) || true; }
done

# Once all have finished, their runs are all offered (the group's folder still not).
"$root/scripts/procs.sh" stop g >/dev/null
missing=0
for d in "$logs"/e1-* "$logs"/e2-* "$logs"/e3-* "$logs"/g-*; do
  grep -q "^would remove .* $d\$" "$out/listing.txt" || { echo "not offered once finished: $d"; missing=$((missing + 1)); }
done
grep -q "^would remove .*$logs/g\$" "$out/listing.txt" && { echo "the group's folder is offered"; bad=$((bad + 1)); }
sort -n "$out/times.txt" >"$out/times-sorted.txt"
median=$(awk '{a[NR]=$1} END {print a[int((NR + 1) / 2)]}' "$out/times-sorted.txt")
slowest=$(tail -1 "$out/times-sorted.txt")
echo "listings: $listings (one begun every 0.2 s, or as the last ended), at most $most folders each;" \
  "clean took $median ms (median), $slowest ms at most"
echo "offered: $offered times a folder of an experiment that had finished ($during of them while the listing ran);" \
  "offered while in use: $bad"
echo "left alone, $alone times:"
for r in "${!why[@]}"; do printf '  %6d  %s\n' "${why[$r]}" "$r"; done | sort -rn
cat "$out/e2-interrupted.txt" 2>/dev/null || true
echo "once all finished: $(ls -d "$logs"/e1-* "$logs"/e2-* "$logs"/e3-* "$logs"/g-* | wc -l) run folders, $missing not offered"
((bad == 0 && missing == 0))
