#!/usr/bin/env bash
# Install what afford needs, build, and run the main job: one intrinsic
# base-test run of IMP (6000 steps) over real processes, ending with the table
# of learned affordances beside the paper's Table 1.
# Usage: scripts/main.sh [more `afford experiment` options]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec build/bin/afford experiment base --system IMP --reps 1 --out out/main "$@"
