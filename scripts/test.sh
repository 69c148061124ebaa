#!/usr/bin/env bash
# Install what afford needs, build, and run the whole test suite (unit tests,
# in-process choreography tests, and the real processes over udpm in a private
# network namespace). Usage: scripts/test.sh [ctest arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd build
# One test more than the cores: many tests spend part of their time waiting on processes over the bus
# (at -j2 on 2 cores the suite used 73% of the CPU); the tests that measure under load run alone (RUN_SERIAL).
ctest --output-on-failure -j"$(($(nproc) + 1))" "$@"
