#!/usr/bin/env bash
# How `tessera merge` scales (writeup.md, "Farm rendering"): 3840x2160 partials of one sample each
# (samples 0:1, 1:2, ... of a 16-spp render), merged K at a time for K = 1, 2, 4, 8 (--allow-gaps:
# the merge reads, checks and sums exactly as for a complete split). Prints per K the bytes of one
# partial, the merge's wall time (read and CRC-check every partial, sum, write the EXR) and its peak
# memory, and the render + write time of one partial. The partials are rendered cheaply (pt,
# --max-depth 0): a partial's size and the merge's cost do not depend on what was rendered.
# Needs 1.23 GB free in DIR per partial.
#   tools/bench_merge.sh [DIR] [MAXPARTS]       (default DIR /tmp/tessera-bench-merge, MAXPARTS 8)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tessera="${TESSERA:-$root/build/src/tessera}"
dir="${1:-/tmp/tessera-bench-merge}"
max="${2:-8}"
scene="$root/scenes/cornell-box/cornell-box.gltf"
opts=(--resolution 3840x2160 --spp 16 --integrator pt --max-depth 0 --seed 1 --quiet)
mkdir -p "$dir"
files=()
for ((i = 0; i < max; i++)); do
  /usr/bin/time -f "%e" -o "$dir/render-time.txt" nice -n 10 "$tessera" render "$scene" "${opts[@]}" --samples "$i:$((i + 1))" -o "$dir/p$i.partial"
  echo "partial $i: rendered and written in $(cat "$dir/render-time.txt") s" >&2
  files+=("$dir/p$i.partial")
done
sync
printf "%-6s %-14s %-12s %s\n" parts "bytes/part" "merge s" "merge peak RSS MiB"
for ((k = 1; k <= max; k *= 2)); do
  /usr/bin/time -f "%e %M" -o "$dir/time.txt" nice -n 10 "$tessera" merge "${files[@]:0:k}" -o "$dir/merged.exr" --no-png --quiet --allow-gaps 2>/dev/null
  read -r secs kib <"$dir/time.txt"
  printf "%-6s %-14s %-12s %s\n" "$k" "$(stat -c %s "${files[0]}")" "$secs" "$((kib / 1024))"
done
rm -f "$dir"/p*.partial
