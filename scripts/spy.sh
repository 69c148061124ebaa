#!/usr/bin/env bash
# Watch a run's channels with lcm-spy, decoded with the project's types.
#   scripts/spy.sh [URL] [lcm-spy options...]
# URL: the run's LCM URL (default $LCM_DEFAULT_URL, else LCM's default
# udpm://239.255.76.67:7667?ttl=0). A run started by `afford experiment` uses
# udpm://239.255.76.67:<base-port + slot>?ttl=0 inside its own network
# namespace; see docs/operating.md for watching such a run.
# Debian's lcm-spy wrapper passes -Xincgc, which Java 17 refuses, so this
# starts lcm.spy.Spy directly, with the types jar and jchart2d (its charts).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
url=${1:-${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0}}
[[ $# -gt 0 ]] && shift
jar=$root/build/share/afford-lcmtypes.jar
[[ -f $jar || ! -f $root/java/afford-lcmtypes.jar ]] || jar=$root/java/afford-lcmtypes.jar  # an installed copy
for f in "$jar" /usr/share/java/lcm.jar /usr/share/java/jchart2d.jar; do
  [[ -f $f ]] || { echo "spy.sh: $f is missing (run scripts/setup.sh)" >&2; exit 2; }
done
# lcm-spy is a window: say so before Java does, with the ways to get one and what works without.
no_display() {
  echo "spy.sh: lcm-spy opens a window, and there is no display ($1). Run it on a desktop, over ssh -X," >&2
  echo "  or in a virtual display: xvfb-run -a scripts/spy.sh URL (then screenshot it: xwd or import)." >&2
  echo "  Without a window: build/bin/afford status --lcm-url URL (each process's state and step), or" >&2
  echo "  build/bin/afford-viewer --lcm-url URL --png DIR (the viewer's frames as PNG files)." >&2
  exit 2
}
[[ -n ${DISPLAY:-} ]] || no_display "DISPLAY is not set"
if command -v xdpyinfo >/dev/null && ! xdpyinfo >/dev/null 2>&1; then no_display "cannot open display '$DISPLAY'"; fi
exec java -Djava.net.preferIPv4Stack=true -Xmx256m -Xms64m \
  -cp "$jar:/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar" lcm.spy.Spy --lcm-url="$url" "$@"
