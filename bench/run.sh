#!/usr/bin/env bash
# Benchmark of the intrinsic phase: steps per second over udpm and memq and
# their ratio, log bytes per step, peak memory per process (docs/performance.md).
# Usage: bench/run.sh [--steps N] [--reps R] [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
[[ -x build/bin/afford-bench ]] || scripts/setup.sh
exec build/bin/afford-bench "$@"
