#!/usr/bin/env bash
# Writes the tables of keys of docs/configuration.md from the declaration of
# every key and config/defaults.yaml (`afford config --keys`), between its
# markers. A test fails while they differ.
#   scripts/docs-keys.sh [BUILD_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
doc=$root/docs/configuration.md
tables=$(mktemp)
trap 'rm -f "$tables"' EXIT
# The tables come from the declaration compiled in: build it first, or a binary
# older than the sources writes the keys as they were.
cmake --build "$build" --target afford >/dev/null
"$build/bin/afford" --config-dir "$root/config" config --keys >"$tables"
/usr/bin/python3 - "$doc" "$tables" <<'PY'
import sys
doc, tables = sys.argv[1], sys.argv[2]
text = open(doc).read()
begin, end = "<!-- the keys: `afford config --keys` -->\n", "<!-- end of the keys -->"
a, b = text.index(begin) + len(begin), text.index(end)
open(doc, "w").write(text[:a] + open(tables).read() + "\n" + text[b:])
PY
echo "wrote the tables of keys in $doc"
