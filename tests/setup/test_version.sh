#!/usr/bin/env bash
# The version a build says is the checkout's commit when it was built, not when CMake configured it:
# cmake/version.cmake (run at every build) in a git repository of its own, committed to, edited, and left alone.
# Usage: tests/setup/test_version.sh BUILD ARTEFACTS
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
work=$2
rm -rf "$work" && mkdir -p "$work/repo/common/src"
cd "$work/repo"
cp "$src/common/src/version.cpp.in" common/src/
git init -q && git config user.email t@t && git config user.name t
echo a > file && git add -A && git commit -qm a
write() { cmake -D SOURCE_DIR="$work/repo" -D PROJECT_VERSION=9.9.9 -D OUT="$work/version.cpp" -P "$src/cmake/version.cmake"; }
says() { grep -o '"9\.9\.9+[^"]*"' "$work/version.cpp" | tr -d '"'; }
fail() { echo "FAIL: $*" >&2; exit 1; }

write
first=$(git rev-parse --short HEAD)
[[ $(says) == "9.9.9+$first" ]] || fail "after the first commit: $(says), not 9.9.9+$first"
echo b > file && git commit -qam b
write
second=$(git rev-parse --short HEAD)
[[ $(says) == "9.9.9+$second" ]] || fail "after a second commit: $(says), not 9.9.9+$second"
echo c > file
write
[[ $(says) == "9.9.9+$second-dirty" ]] || fail "with an edit not committed: $(says), not 9.9.9+$second-dirty"

touch -d '2000-01-01' "$work/version.cpp"
write
[[ $(stat -c %Y "$work/version.cpp") == $(date -d '2000-01-01' +%s) ]] || fail "an unchanged version rewrote the file"
echo "version: each commit and an uncommitted edit said, an unchanged checkout leaves the file as it was"
