#!/usr/bin/env bash
# Install what afford needs, build, and run the whole test suite (unit tests,
# in-process choreography tests, and the real processes over udpm in a private
# network namespace). Usage: scripts/test.sh [ctest arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd build
ctest --output-on-failure -j"$(nproc)" "$@"
