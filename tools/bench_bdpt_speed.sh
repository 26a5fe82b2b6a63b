#!/usr/bin/env bash
# CPU time per sample of `bdpt` against `ptnee` (the issue #18 speed ratio), robust to a loaded machine.
#
#   tools/bench_bdpt_speed.sh [--scene GLTF] [--rounds N] [--cpu C] [BINARY ...]
#
# For each round and each binary (default build/src/tessera; give several to compare builds in the
# same minutes), renders the scene with `bdpt` then `ptnee`, one thread pinned to core C, at 256²
# with 1 and 9 spp, and takes (CPU₉ − CPU₁) / (8 · 256²): user + sys time, so that start-up, loading
# and output cancel and the load of other processes does not count (wall clock would measure it).
# Both integrators run with unlimited depth (Russian roulette), i.e. equal maximum path length.
# Prints one line per round and binary, then per binary the median and range of the ratio
# ptnee µs / bdpt µs (= bdpt's samples/s over ptnee's).
#
#   tools/bench_bdpt_speed.sh --instructions [--scene GLTF] [BINARY ...]
#
# The same ratio from instruction counts, for a host whose CPU times scatter: under valgrind's
# callgrind (deterministic, needs the `valgrind` package), each integrator at 64² with 1 and 17 spp,
# (I₁₇ − I₁)/(16 · 64²) instructions per sample, whole process, so that start-up and output cancel.
# Instructions track CPU time only roughly (they ignore cache misses and branch mispredictions).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENE=$ROOT/scenes/cornell-box/cornell-box.gltf
ROUNDS=5
CPU=1
MODE=cpu
BINS=()
while [ $# -gt 0 ]; do
    case $1 in
    --scene) SCENE=$2; shift ;;
    --rounds) ROUNDS=$2; shift ;;
    --cpu) CPU=$2; shift ;;
    --instructions) MODE=instructions ;;
    -*) echo "bench_bdpt_speed.sh: unknown option '$1' (see the header of $0)" >&2; exit 2 ;;
    *) BINS+=("$1") ;;
    esac
    shift
done
[ ${#BINS[@]} -gt 0 ] || BINS=("$ROOT/build/src/tessera")
for b in "${BINS[@]}"; do [ -x "$b" ] || { echo "bench_bdpt_speed.sh: $b is not an executable" >&2; exit 2; }; done
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

cpu() {  # binary integrator spp: prints CPU seconds
    /usr/bin/time -f "%U %S" -o "$TMP/time" taskset -c "$CPU" "$1" render "$SCENE" --integrator "$2" --threads 1 \
        --resolution 256x256 --spp "$3" --no-png --quiet -o "$TMP/out.exr" > /dev/null
    awk '{print $1 + $2}' "$TMP/time"
}
usPerSample() {  # binary integrator
    local t1 t9
    t1=$(cpu "$1" "$2" 1)
    t9=$(cpu "$1" "$2" 9)
    awk -v a="$t9" -v b="$t1" 'BEGIN { printf "%.3f", (a - b) / (8 * 65536) * 1e6 }'
}

instructions() {  # binary integrator spp: prints the instructions of the whole process
    # A run that fails (e.g. SIGILL in a library Valgrind cannot decode) must not be counted: its
    # total would be the start-up's alone.
    if ! LD_PRELOAD=$("$ROOT/tools/valgrind_preload.sh" "$1") valgrind --tool=callgrind --callgrind-out-file="$TMP/cg" \
        "$1" render "$SCENE" --integrator "$2" --threads 1 --resolution 64x64 --spp "$3" --no-png --quiet \
        -o "$TMP/out.exr" > "$TMP/valgrind.log" 2>&1; then
        echo "bench_bdpt_speed.sh: $1 $2 failed under valgrind:" >&2
        grep -v '^==[0-9]*== *$' "$TMP/valgrind.log" | tail -n 8 >&2
        exit 1
    fi
    awk '/^(summary|totals):/ { print $2; exit }' "$TMP/cg"
}
if [ "$MODE" = instructions ]; then
    command -v valgrind > /dev/null || { echo "bench_bdpt_speed.sh: --instructions needs valgrind (apt-get install valgrind)" >&2; exit 2; }
    for b in "${BINS[@]}"; do
        declare -A PER
        for i in bdpt ptnee; do
            i1=$(instructions "$b" "$i" 1)
            i17=$(instructions "$b" "$i" 17)
            PER[$i]=$(awk -v a="$i17" -v b="$i1" 'BEGIN { printf "%.0f", (a - b) / (16 * 4096) }')
        done
        echo "$b: instructions per sample: bdpt ${PER[bdpt]}, ptnee ${PER[ptnee]}; ptnee/bdpt ratio $(awk -v p="${PER[ptnee]}" -v q="${PER[bdpt]}" 'BEGIN { printf "%.4f", p / q }')"
    done
    exit 0
fi

declare -A RATIOS
for r in $(seq "$ROUNDS"); do
    for i in "${!BINS[@]}"; do
        b=${BINS[$i]}
        ub=$(usPerSample "$b" bdpt)
        up=$(usPerSample "$b" ptnee)
        ratio=$(awk -v p="$up" -v q="$ub" 'BEGIN { printf "%.3f", p / q }')
        RATIOS[$i]="${RATIOS[$i]:-} $ratio"
        echo "round $r  $b  bdpt $ub µs  ptnee $up µs  ratio $ratio"
    done
done
for i in "${!BINS[@]}"; do
    echo "${BINS[$i]}: ptnee/bdpt ratio $(echo "${RATIOS[$i]}" | tr ' ' '\n' | sort -n | awk 'NF { a[n++] = $1 }
        END { m = n % 2 ? a[int(n / 2)] : (a[n / 2 - 1] + a[n / 2]) / 2; printf "median %.3f, range %.3f–%.3f over %d rounds", m, a[0], a[n - 1], n }')"
done
