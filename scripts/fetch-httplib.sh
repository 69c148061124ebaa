#!/usr/bin/env bash
# Fetch the source of cpp-httplib 0.11.4 that afford builds with its own patch
# (third_party/httplib/README.md): Debian bookworm's source package
# cpp-httplib 0.11.4+ds-1+deb12u1, its original tarball and its Debian tarball
# (which carries Debian's security fix), from the Debian mirror this machine's
# apt uses, each checked against the SHA-256 that
# cpp-httplib_0.11.4+ds-1+deb12u1.dsc gives. Kept in third_party/httplib/dist/
# (not in git); nothing is fetched when they are there already.
# AFFORD_HTTPLIB_ORIG=FILE and AFFORD_HTTPLIB_DEBIAN=FILE take copies instead.
# Usage: scripts/fetch-httplib.sh
set -euo pipefail
cd "$(dirname "$0")/.."
pool=pool/main/c/cpp-httplib dist=third_party/httplib/dist
scripts/fetch-source.sh cpp-httplib_0.11.4+ds.orig.tar.xz "$pool" \
  8b1a5df569003b6a4f24c68489bbda5c64aec94697bdc9ebba5d79408b2ae7eb "$dist" "${AFFORD_HTTPLIB_ORIG:-}"
scripts/fetch-source.sh cpp-httplib_0.11.4+ds-1+deb12u1.debian.tar.xz "$pool" \
  a0adf8a38610806f6d94ba69839438635e5e6580775e28ff31d6a081e34f1484 "$dist" "${AFFORD_HTTPLIB_DEBIAN:-}"
