#!/usr/bin/env bash
# Install what afford needs, build, and run the main job over real processes:
# one intrinsic base-test run of IMP (6000 steps), then three tests of each of
# the five extrinsic scenarios with the trained agent; it ends with the learned
# affordances beside the paper's Table 1 and the scenarios beside its Table 2.
# Installs and builds only what that needs (scripts/setup.sh --main); scripts/test.sh the rest.
# Usage: scripts/main.sh [more `afford experiment` options]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --main
# --replace: out/main holds the previous main job's results, which this one replaces (nothing else is there).
exec build/bin/afford experiment base --system IMP --reps 1 --extrinsic-reps 3 --out out/main --replace "$@"
