#!/usr/bin/env bash
# Install every Debian package afford needs (idempotent), fetch LCM's source
# (scripts/fetch-lcm.sh), then configure and build a Release build into build/
# (executables in build/bin/, the Python package in build/python/, put on
# /usr/bin/python3's path).
# Usage: scripts/setup.sh [--no-build]
# Works as root on a fresh Debian bookworm with only the compiler toolchain.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config git ca-certificates patch
  liblcm-bin liblcm-java libglib2.0-dev  # lcm-gen, the LCM tools and lcm.jar; liblcm itself is built (below)
  libeigen3-dev libopencv-dev libspdlog-dev libfmt-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev zlib1g-dev libgsl-dev libsodium-dev
  libgtest-dev libgmock-dev
  default-jdk-headless default-jre libjchart2d-java
  iproute2 iptables util-linux procps gnuplot-nox time
  xvfb imagemagick x11-utils
  slurmctld slurmd slurm-client munge  # scripts/slurm-submit.sh; tests/cluster/slurm-local.sh
  clang libclang-rt-14-dev llvm  # scripts/fuzz.sh: libFuzzer, ASan, UBSan, llvm-symbolizer
  # the Python package (python/, docs/python.md), for Debian's /usr/bin/python3
  python3-dev pybind11-dev python3-numpy python3-pandas python3-matplotlib python3-pytest
  python3-nbclient python3-nbformat python3-ipykernel python3-venv python3-pip python3-setuptools python3-wheel
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""; [[ $(id -u) -eq 0 ]] || sudo="sudo"
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# LCM's source, which the build patches (third_party/lcm/README.md).
scripts/fetch-lcm.sh

[[ ${1:-} == --no-build ]] && exit 0
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"

# `import afford` in Debian's /usr/bin/python3: a .pth file in its site folder
# for local installs names the package built in build/python.
site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
sudo=""; [[ $(id -u) -eq 0 || -w $(dirname "$site") ]] || sudo="sudo"
$sudo mkdir -p "$site"
echo "$PWD/build/python" | $sudo tee "$site/afford.pth" >/dev/null
