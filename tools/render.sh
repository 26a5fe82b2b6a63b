#!/usr/bin/env bash
# Installs what is missing, builds, and renders a scene (default: the Cornell box) to out/.
#   tools/render.sh                                   -> out/cornell-box.exr + out/cornell-box.png
#   tools/render.sh scenes/sphere-cornell/sphere-cornell.gltf --spp 64
# Any extra arguments go to `tessera render`.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/bootstrap.sh"
cd "$TESSERA_ROOT"
scene="scenes/cornell-box/cornell-box.gltf"
if [ $# -gt 0 ] && [[ "$1" != -* ]]; then scene="$1"; shift; fi
name="$(basename "${scene%.*}")"
exec "$TESSERA_BUILD/src/tessera" render "$scene" -o "out/$name.exr" --png "out/$name.png" "$@"
