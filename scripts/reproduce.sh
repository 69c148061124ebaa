#!/usr/bin/env bash
# Regenerate the paper's results with the paper's repetition counts and write
# docs/results.md (our tables and figures beside the paper's numbers).
#   scripts/reproduce.sh deterministic   base, late1, late2, late3: 10 intrinsic runs per
#                                        system, 10 tests of each scenario per run (Tables
#                                        1, 2, 4-6; Figures 5-10)
# Environment: JOBS (runs at a time, default: cores), REPS and EXT_REPS (default 10),
# OUT (default out/reproduce). Runs over real processes (udpm); keeps the logs
# of the first run of each system. Takes about 40 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
what=${1:-deterministic}
case $what in
  deterministic) experiments=(base late1 late2 late3) ;;
  *) echo "usage: scripts/reproduce.sh deterministic" >&2; exit 2 ;;
esac
scripts/setup.sh
out=${OUT:-out/reproduce}
mkdir -p "$out"
start=$SECONDS
dirs=()
for exp in "${experiments[@]}"; do
  rm -rf "${out:?}/$exp"
  build/bin/afford experiment "$exp" --system all --reps "${REPS:-10}" --extrinsic-reps "${EXT_REPS:-10}" \
    --jobs "${JOBS:-$(nproc)}" --keep-logs first --out "$out/$exp" --log-root "$out/logs" --run-prefix "$(date +%Y%m%d-%H%M%S)"
  build/bin/afford plot "$out/$exp"
  dirs+=("$out/$exp")
done
build/bin/afford report "${dirs[@]}" --out docs/results.md --figures docs/results --wall-seconds $((SECONDS - start))
echo "docs/results.md written; wall time $((SECONDS - start)) s"
