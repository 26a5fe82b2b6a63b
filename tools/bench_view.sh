#!/usr/bin/env bash
# The preview's responsiveness (writeup.md, "The interactive preview"): for each scene, on a virtual
# X server of its own (Xvfb -displayfd: a free display, ended by its pid), `tessera view` at
# 960x540 scripted as
#     0-8 s still (progressive 1-spp passes)      -> samples/s (samples / wall time, 3 s to 8 s)
#     8-10 s moving (W held at --speed 1e-4: the   -> frames per second while moving (reduced frames / 2 s)
#            camera changes every frame, the view stays put)
#     10 s stop                                    -> time from the restart to the first full-resolution frame
# then `tessera render --time 8` of the same view for its samples/s. REPEAT runs of each (default 3).
# Usage: tools/bench_view.sh [SCENE...]   (default: the Cornell box and the dragon)
#   TESSERA=path/to/tessera  REPEAT=N  THREADS=N (default: all cores)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tessera="${TESSERA:-$root/build/src/tessera}"
repeat="${REPEAT:-3}"
threads=(); [ -n "${THREADS:-}" ] && threads=(--threads "$THREADS")
scenes=("$@"); [ ${#scenes[@]} -eq 0 ] && scenes=("$root/scenes/cornell-box/cornell-box.gltf" "$root/scenes/dragon/dragon.gltf")
for tool in Xvfb; do command -v $tool >/dev/null || { echo "bench_view: $tool is not installed (tools/bootstrap.sh --install build)" >&2; exit 2; }; done
tmp="$(mktemp -d)"
Xvfb -displayfd 5 -screen 0 1280x720x24 -nolisten tcp 5>"$tmp/display" 2>/dev/null &
xvfb=$!
trap 'kill "$xvfb" 2>/dev/null; wait "$xvfb" 2>/dev/null; rm -rf "$tmp"' EXIT
for _ in $(seq 100); do grep -q . "$tmp/display" 2>/dev/null && break; sleep 0.1; done
display=":$(head -n1 "$tmp/display")"
cat > "$tmp/script" <<'SCRIPT'
3.0 press c
8.0 press c
8.0 down w
10.0 up w
13.0 press c
13.0 quit
SCRIPT
field() { sed -n "$1"p "$2" | tr ' ' '\n' | sed -n "s/^$3=//p"; }
printf '%-12s %3s %14s %14s %7s %10s %12s\n' scene run "view Msamp/s" "render Msamp/s" ratio "moving fps" "first full s"
for scene in "${scenes[@]}"; do
  name="$(basename "$scene" .gltf)"
  for r in $(seq "$repeat"); do
    DISPLAY="$display" "$tessera" view "$scene" --resolution 960x540 --speed 1e-4 "${threads[@]}" --script "$tmp/script" \
      -o "$tmp/v.exr" >"$tmp/out" 2>"$tmp/err" || { cat "$tmp/err" >&2; exit 1; }
    # Pairs of lines (render command, status) at 3, 8 and 13 s. The still rate is taken between 3 and
    # 8 s (steady state: the window's start-up is over), as the render's over its whole run.
    s0="$(field 2 "$tmp/out" samples)"; w0="$(field 2 "$tmp/out" wall_seconds)"
    s1="$(field 4 "$tmp/out" samples)"; w1="$(field 4 "$tmp/out" wall_seconds)"
    samples="$(awk -v a="$s0" -v b="$s1" 'BEGIN { print b - a }')"; wall="$(awk -v a="$w0" -v b="$w1" 'BEGIN { print b - a }')"
    frames="$(field 6 "$tmp/out" reduced_frames)"; first="$(field 6 "$tmp/out" first_full_frame_seconds)"
    render="$("$tessera" render "$scene" --resolution 960x540 --time 8 "${threads[@]}" --quiet --json -o "$tmp/r.exr" |
      sed -n 's/.*"samples_per_second":\([0-9.e+]*\).*/\1/p')"
    awk -v n="$name" -v r="$r" -v s="$samples" -v w="$wall" -v rr="$render" -v f="$frames" -v ff="$first" 'BEGIN {
      v = s / w / 1e6; printf "%-12s %3d %14.3f %14.3f %6.1f%% %10.1f %12.2f\n", n, r, v, rr / 1e6, 100 * v / (rr / 1e6), f / 2.0, ff }'
  done
done
