#!/usr/bin/env bash
# Fetch the source of LCM 1.3.1 that afford builds with its own patches
# (third_party/lcm/README.md): the original tarball of Debian's source package
# lcm 1.3.1+repack1, from the Debian mirror this machine's apt uses, checked
# against its SHA-256 (the one Debian's lcm_1.3.1+repack1-3.dsc gives).
# Kept in third_party/lcm/dist/ (not in git); nothing is fetched when it is
# there already. AFFORD_LCM_TARBALL=FILE takes a copy from FILE instead (a
# machine without a mirror). Usage: scripts/fetch-lcm.sh
set -euo pipefail
cd "$(dirname "$0")/.."
exec scripts/fetch-source.sh lcm_1.3.1+repack1.orig.tar.gz pool/main/l/lcm \
  abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8 third_party/lcm/dist "${AFFORD_LCM_TARBALL:-}"
