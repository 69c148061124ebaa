#!/usr/bin/env bash
# Install every Debian package afford needs (idempotent), fetch LCM's and
# cpp-httplib's source (scripts/fetch-lcm.sh, scripts/fetch-httplib.sh), then
# configure and build a Release build into build/ (executables in build/bin/,
# the Python package in build/python/, put on /usr/bin/python3's path), and
# put `afford` on the PATH (a link in /usr/local/bin to build/bin/afford).
# Usage: scripts/setup.sh [--main] [--no-build] [--dry-run]
#   --main      only what the main job needs (scripts/main.sh): the packages to
#               build and run the processes and the `afford` command, and those
#               targets; scripts/test.sh installs and builds the rest
#   --no-build  install and fetch only
#   --dry-run   say what would be installed, fetched and run; do none of it
# Works as root on a fresh Debian bookworm with only the compiler toolchain.
set -euo pipefail
cd "$(dirname "$0")/.."

main=0 build=1 dry=0
for arg in "$@"; do
  case $arg in
    --main) main=1 ;;
    --no-build) build=0 ;;
    --dry-run) dry=1 ;;
    *) echo "setup.sh: unknown option '$arg' (--main, --no-build, --dry-run)" >&2; exit 2 ;;
  esac
done
run() { if ((dry)); then echo "would run: $*"; else "$@"; fi; }

# What the processes and the `afford` command need to build and run (over udpm in a private network namespace).
packages=(
  build-essential cmake pkg-config git ca-certificates patch
  liblcm-bin libglib2.0-dev  # lcm-gen and the LCM tools; liblcm itself is built (below)
  libeigen3-dev libopencv-dev libspdlog-dev libfmt-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev zlib1g-dev libgsl-dev libsodium-dev libzstd-dev
  iproute2 util-linux procps
  ffmpeg              # afford render: video and GIF
  # The table world (world.kind: table): MuJoCo, and an OpenGL context from EGL without a display (Mesa). Debian's
  # MuJoCo CMake package names libqhull's headers, which libmujoco-dev does not pull in.
  libmujoco-dev libqhull-dev libegl-dev libegl-mesa0 libgl1-mesa-dri
)
# ... and what the tests, the figures, lcm-spy, the cluster scripts and the Python package need.
((main)) || packages+=(
  liblcm-java  # lcm.jar, for lcm-spy's types jar
  libgtest-dev libgmock-dev
  default-jdk-headless default-jre libjchart2d-java
  iptables gnuplot-nox time
  xvfb imagemagick x11-utils
  slurmctld slurmd slurm-client munge  # scripts/slurm-submit.sh; tests/cluster/slurm-local.sh
  clang libclang-rt-14-dev llvm  # scripts/fuzz.sh: libFuzzer, ASan, UBSan, llvm-symbolizer
  # the Python package (python/, docs/python.md), for Debian's /usr/bin/python3
  python3-dev pybind11-dev python3-numpy python3-pandas python3-matplotlib python3-pytest
  python3-pyte  # tests/terminal: a VT100 emulator reads what the progress board leaves on a terminal
  python3-nbclient python3-nbformat python3-ipykernel python3-venv python3-pip python3-setuptools python3-wheel
  chromium chromium-driver python3-selenium  # tests/watch: the live page in a real browser
  python3-torch  # examples/torch-predictor: an affordance predictor written with PyTorch
  python3-optuna  # afford tune (python/afford/study.py): studies with samplers, pruning and a shared journal
)
# Node.js and npm, for the MCAP checker (tools/mcapcheck: Foxglove's @mcap/core): Debian's, unless a Node.js
# with its own npm is installed already (NodeSource's package, which Debian's npm conflicts with).
((main)) || command -v npm >/dev/null || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((dry)); then
  echo "would install: ${missing[*]:-(nothing: every package is there)}"
elif ((${#missing[@]})); then
  sudo=""; [[ $(id -u) -eq 0 ]] || sudo="sudo"
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# LCM's and cpp-httplib's source, which the build patches (third_party/lcm/README.md, third_party/httplib/README.md).
run scripts/fetch-lcm.sh
run scripts/fetch-httplib.sh

# The MCAP checker's packages (tools/mcapcheck: @mcap/core and fzstd, pinned by its package-lock.json) from
# npm's registry, unless the pinned versions are installed already (so an offline machine keeps its copy).
if ((!main)); then
  stale=0
  while read -r name pinned; do
    have=$(sed -n 's/^  "version": "\(.*\)",$/\1/p' "tools/mcapcheck/node_modules/$name/package.json" 2>/dev/null || true)
    [[ $have == "$pinned" ]] || stale=1
  done < <(sed -n 's/^    "\(.*\)": "\(.*\)",\{0,1\}$/\1 \2/p' tools/mcapcheck/package.json)
  if ((stale)); then
    run npm ci --prefix tools/mcapcheck --no-audit --no-fund --loglevel=error
  fi
fi

((build)) || exit 0
# `afford` as the docs write it: a link in /usr/local/bin (on every PATH) to this checkout's build/bin/afford;
# one there already that is not a link to an afford build is left alone, and said.
on_path() {
  local link=/usr/local/bin/afford target=$PWD/build/bin/afford
  if [[ -e $link && ! -L $link ]]; then
    echo "setup.sh: $link exists and is not a link: left alone (run $target instead)" >&2
    return 0
  fi
  local sudo=""; [[ $(id -u) -eq 0 || -w /usr/local/bin ]] || sudo="sudo"
  run $sudo ln -sfn "$target" "$link"
}
configure() { if ((dry)); then echo "would run: cmake $*"; else cmake "$@" >/dev/null; fi; }
if ((main)); then
  # The main job's targets only: the processes and the front door (no tests, benchmarks or Python).
  configure -S . -B build -DCMAKE_BUILD_TYPE=Release -DAFFORD_TESTS=OFF -DAFFORD_EXTRAS=OFF
  run cmake --build build -j"$(nproc)" --target afford afford-environment afford-eye afford-predictors \
    afford-motivation afford-planner afford-logger
  on_path
  exit 0
fi
configure -S . -B build -DCMAKE_BUILD_TYPE=Release -DAFFORD_TESTS=ON -DAFFORD_EXTRAS=ON
run cmake --build build -j"$(nproc)"
on_path
((dry)) && exit 0

# `import afford` in Debian's /usr/bin/python3: a .pth file in its site folder
# for local installs names the package built in build/python.
site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
sudo=""; [[ $(id -u) -eq 0 || -w $(dirname "$site") ]] || sudo="sudo"
$sudo mkdir -p "$site"
echo "$PWD/build/python" | $sudo tee "$site/afford.pth" >/dev/null
