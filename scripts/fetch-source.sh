#!/usr/bin/env bash
# Fetch one file of a Debian source package (an original tarball, a Debian
# tarball) that afford builds with its own patches, from the Debian mirror this
# machine's apt uses, checked against its SHA-256 (the one the package's .dsc
# gives), into a folder kept out of git. Nothing is fetched when the file is
# there already. Used by scripts/fetch-lcm.sh and scripts/fetch-httplib.sh.
#   scripts/fetch-source.sh FILE POOL_DIR SHA256 DEST_DIR [COPY]
# POOL_DIR: the package's folder in the mirror's pool (pool/main/l/lcm);
# COPY: a copy of FILE to take instead (a machine without a mirror).
set -euo pipefail
name=$1 pool=$2 sha256=$3 dist=$4 copy=${5:-}
me=$(basename "$0")
target=$dist/$name

verified() { [[ -f $1 ]] && [[ $(sha256sum "$1" | cut -d' ' -f1) == "$sha256" ]]; }

verified "$target" && exit 0
mkdir -p "$dist"
if [[ -n $copy ]]; then
  verified "$copy" || { echo "$me: $copy is not $name (SHA-256 $sha256)" >&2; exit 1; }
  cp "$copy" "$target.part"
else
  # The first Debian mirror of apt's sources (deb822 or one-line), security aside.
  mirror=$(sed -n 's/^URIs:[[:space:]]*//p' /etc/apt/sources.list.d/*.sources 2>/dev/null | tr ' ' '\n' |
    grep -v -e security -e '^$' | head -n 1 || true)
  [[ -n $mirror ]] || mirror=$(awk '$1 == "deb" && $0 !~ /security/ {print $2; exit}' /etc/apt/sources.list \
    /etc/apt/sources.list.d/*.list 2>/dev/null || true)
  [[ -n $mirror ]] || { echo "$me: no Debian mirror in apt's sources; give a copy of $name" >&2; exit 1; }
  url=${mirror%/}/$pool/$name
  echo "$me: fetching $url"
  rm -f "$target.part"
  # apt's own downloader checks the hash.
  /usr/lib/apt/apt-helper download-file "$url" "$target.part" "SHA256:$sha256" >/dev/null 2>"$dist/fetch.log" || {
    cat "$dist/fetch.log" >&2
    echo "$me: cannot fetch $url (give a copy of $name)" >&2
    exit 1
  }
fi
verified "$target.part" || { echo "$me: $target.part does not have SHA-256 $sha256" >&2; exit 1; }
mv "$target.part" "$target"
echo "$me: $target"
