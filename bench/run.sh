#!/usr/bin/env bash
# Benchmarks (docs/performance.md).
#   bench/run.sh [--steps N] [--reps R] [--out DIR]
#     the intrinsic phase: steps per second over udpm and memq and their ratio,
#     log bytes per step, peak memory per process;
#   bench/run.sh boundaries [--tests K] [--runs R] [--run-steps S] [--transports udpm,memq]
#                           [--parts extrinsic,short,main] [--train-steps N] [--out DIR]
#     run boundaries, logs kept and not: extrinsic tests per second and their
#     wall times, short runs per minute, the main job's wall time; PASS/FAIL
#     against the floors (exit 1 on a FAIL).
set -euo pipefail
cd "$(dirname "$0")/.."
[[ -x build/bin/afford-bench ]] || scripts/setup.sh
exec build/bin/afford-bench "$@"
