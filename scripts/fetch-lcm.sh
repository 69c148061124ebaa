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
name=lcm_1.3.1+repack1.orig.tar.gz
sha256=abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8
dist=third_party/lcm/dist
target=$dist/$name

verified() { [[ -f $1 ]] && [[ $(sha256sum "$1" | cut -d' ' -f1) == "$sha256" ]]; }

verified "$target" && exit 0
mkdir -p "$dist"
if [[ -n ${AFFORD_LCM_TARBALL:-} ]]; then
  verified "$AFFORD_LCM_TARBALL" || {
    echo "fetch-lcm.sh: $AFFORD_LCM_TARBALL is not $name (SHA-256 $sha256)" >&2
    exit 1
  }
  cp "$AFFORD_LCM_TARBALL" "$target.part"
else
  # The first Debian mirror of apt's sources (deb822 or one-line), security aside.
  mirror=$(sed -n 's/^URIs:[[:space:]]*//p' /etc/apt/sources.list.d/*.sources 2>/dev/null | tr ' ' '\n' |
    grep -v -e security -e '^$' | head -n 1 || true)
  [[ -n $mirror ]] || mirror=$(awk '$1 == "deb" && $0 !~ /security/ {print $2; exit}' /etc/apt/sources.list \
    /etc/apt/sources.list.d/*.list 2>/dev/null || true)
  [[ -n $mirror ]] || { echo "fetch-lcm.sh: no Debian mirror in apt's sources; set AFFORD_LCM_TARBALL" >&2; exit 1; }
  url=${mirror%/}/pool/main/l/lcm/$name
  echo "fetch-lcm.sh: fetching $url"
  rm -f "$target.part"
  # apt's own downloader checks the hash.
  /usr/lib/apt/apt-helper download-file "$url" "$target.part" "SHA256:$sha256" >/dev/null 2>"$dist/fetch.log" || {
    cat "$dist/fetch.log" >&2
    echo "fetch-lcm.sh: cannot fetch $url (set AFFORD_LCM_TARBALL to a copy of $name)" >&2
    exit 1
  }
fi
verified "$target.part" || { echo "fetch-lcm.sh: $target.part does not have SHA-256 $sha256" >&2; exit 1; }
mv "$target.part" "$target"
echo "fetch-lcm.sh: $target"
