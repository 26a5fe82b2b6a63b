#!/usr/bin/env bash
# Equal-time comparison of Tessera's `bdpt` with SmallVCM's bidirectional path tracer (`-a bpt`) on
# SmallVCM's Cornell box (large mirror sphere, ceiling light box, diffuse floor), reproduced as
# scenes/smallvcm-cornell (tools/make_scenes.py). One thread each, pinned to one core.
#
#   tools/bench_smallvcm.sh --fetch            # clone and build SmallVCM into the cache folder
#   tools/bench_smallvcm.sh [options]          # run the comparison, print a Markdown table
#
# Options:
#   --fetch              clone SmallVCM (MIT, github.com/SmallVCM/SmallVCM, commit below) into
#                        $SMALLVCM_DIR (default: ${XDG_CACHE_HOME:-~/.cache}/tessera/smallvcm),
#                        make the two local changes below and build it (g++, OpenMP); then exit
#   --budgets "S ..."    equal-time budgets in seconds (default "5 10 20")
#   --runs N             runs per renderer and budget, each with its own seed (default 3)
#   --ref-seconds S      seconds of each renderer's reference render, on all cores (default 120)
#   --out DIR            working folder for the images (default out/bench-smallvcm)
#   --tessera PATH       the tessera binary (default build/src/tessera)
#   --cpu N              the core the timed runs are pinned to (default 1)
#
# Local changes made to SmallVCM's config.hxx (sed, never committed anywhere): one more scene
# configuration, kLargeMirrorSphere | kLightCeiling without kGlossyFloor (scene id 4: SmallVCM's
# glossy floor is a Phong lobe Tessera does not have), and the base seed read from $SMALLVCM_SEED
# (default 1234 as upstream) so that repeated runs are independent.
#
# The reference is the average of one long render of each renderer (their means are printed first:
# they must agree within noise for the comparison to mean anything); relMSE is `tessera compare`'s
# mean over pixels and RGB of (x − r)² / (r² + 0.01).
set -euo pipefail

SMALLVCM_URL=https://github.com/SmallVCM/SmallVCM
SMALLVCM_COMMIT=a13690f
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SMALLVCM_DIR=${SMALLVCM_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera/smallvcm}
BUDGETS="5 10 20"
RUNS=3
REF_SECONDS=120
OUT=$ROOT/out/bench-smallvcm
TESSERA=$ROOT/build/src/tessera
CPU=1
FETCH=0
while [ $# -gt 0 ]; do
    case $1 in
    --fetch) FETCH=1 ;;
    --budgets) BUDGETS=$2; shift ;;
    --runs) RUNS=$2; shift ;;
    --ref-seconds) REF_SECONDS=$2; shift ;;
    --out) OUT=$2; shift ;;
    --tessera) TESSERA=$2; shift ;;
    --cpu) CPU=$2; shift ;;
    *) echo "bench_smallvcm.sh: unknown option '$1' (see the header of $0)" >&2; exit 2 ;;
    esac
    shift
done

if [ $FETCH = 1 ]; then
    if [ ! -d "$SMALLVCM_DIR/.git" ]; then
        mkdir -p "$(dirname "$SMALLVCM_DIR")"
        git clone -q "$SMALLVCM_URL" "$SMALLVCM_DIR"
    fi
    cd "$SMALLVCM_DIR"
    git checkout -q "$SMALLVCM_COMMIT" -- src/config.hxx
    sed -i 's/^\(    Scene::kGlossyFloor | Scene::kBothSmallSpheres  | Scene::kLightBackground\)$/\1,\n    Scene::kLargeMirrorSphere | Scene::kLightCeiling/' src/config.hxx
    sed -i 's/^    oConfig.mBaseSeed      = 1234;$/    oConfig.mBaseSeed      = getenv("SMALLVCM_SEED") ? atoi(getenv("SMALLVCM_SEED")) : 1234;/' src/config.hxx
    grep -q 'kLargeMirrorSphere | Scene::kLightCeiling$' src/config.hxx && grep -q SMALLVCM_SEED src/config.hxx ||
        { echo "bench_smallvcm.sh: $SMALLVCM_DIR/src/config.hxx: the local changes did not apply" >&2; exit 1; }
    make -s
    echo "built $SMALLVCM_DIR/smallvcm"
    exit 0
fi

SMALLVCM=$SMALLVCM_DIR/smallvcm
[ -x "$SMALLVCM" ] || { echo "bench_smallvcm.sh: $SMALLVCM missing: run with --fetch first" >&2; exit 2; }
[ -x "$TESSERA" ] || { echo "bench_smallvcm.sh: $TESSERA missing: build the tessera target" >&2; exit 2; }
SCENE=$ROOT/scenes/smallvcm-cornell/smallvcm-cornell.gltf
mkdir -p "$OUT"

json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }
# Tessera: `bdpt`, max depth 9 bounces = SmallVCM's default maximum path length of 10 segments.
tessera() {  # seconds threads seed output [taskset prefix...]
    local sec=$1 threads=$2 seed=$3 out=$4; shift 4
    "$@" "$TESSERA" render "$SCENE" --integrator bdpt --max-depth 9 --time "$sec" --threads "$threads" \
        --seed "$seed" -o "$out" --no-png --quiet --json
}
smallvcm() {  # seconds threads seed output [taskset prefix...]
    local sec=$1 threads=$2 seed=$3 out=$4; shift 4
    SMALLVCM_SEED=$seed OMP_NUM_THREADS=$threads "$@" "$SMALLVCM" -s 4 -a bpt -t "$sec" -o "$out" > "$out.log"
    sed -n 's/.*done in \([0-9.]*\) s.*/\1/p' "$out.log"
}
relmse() { "$TESSERA" compare "$1" "$2" --json | json "d['relmse']"; }
means() { "$TESSERA" compare "$1" "$1" --json | json "' '.join('%.5f' % m for m in d['mean_test'])"; }

NPROC=$(nproc)
if [ ! -f "$OUT/ref.exr" ]; then
    echo "references: $REF_SECONDS s each on $NPROC threads" >&2
    tessera "$REF_SECONDS" "$NPROC" 1000 "$OUT/ref-tessera.exr" > "$OUT/ref-tessera.json"
    smallvcm "$REF_SECONDS" "$NPROC" 1000 "$OUT/ref-smallvcm.hdr" > /dev/null
    oiiotool "$OUT/ref-tessera.exr" "$OUT/ref-smallvcm.hdr" --add --mulc 0.5 -d float -o "$OUT/ref.exr"
fi
echo "Reference means (R G B): Tessera $(means "$OUT/ref-tessera.exr") ($(json "d['spp']" < "$OUT/ref-tessera.json") spp)," \
     "SmallVCM $(means "$OUT/ref-smallvcm.hdr"); relMSE between the two references:" \
     "$(relmse "$OUT/ref-tessera.exr" "$OUT/ref-smallvcm.hdr")"
echo
echo "| budget (s) | Tessera bdpt: s, spp | relMSE (mean, min–max) | SmallVCM bpt: s | relMSE (mean, min–max) | SmallVCM / Tessera relMSE·s |"
echo "|---|---|---|---|---|---|"
for sec in $BUDGETS; do
    t_err=() s_err=() t_spp=() t_sec=() s_sec=()
    for run in $(seq "$RUNS"); do
        # Interleaved, pinned to one core: both see the same machine load.
        tessera "$sec" 1 "$run" "$OUT/t-$sec-$run.exr" taskset -c "$CPU" > "$OUT/t-$sec-$run.json"
        t_spp+=("$(json "d['spp']" < "$OUT/t-$sec-$run.json")")
        t_sec+=("$(json "d['seconds']" < "$OUT/t-$sec-$run.json")")
        t_err+=("$(relmse "$OUT/t-$sec-$run.exr" "$OUT/ref.exr")")
        s_sec+=("$(smallvcm "$sec" 1 "$run" "$OUT/s-$sec-$run.hdr" taskset -c "$CPU")")
        s_err+=("$(relmse "$OUT/s-$sec-$run.hdr" "$OUT/ref.exr")")
    done
    # Both renderers finish the pass (one sample per pixel) they are in when the budget runs out:
    # the last column compares relMSE × the seconds each actually took (inverse efficiency).
    python3 - "$sec" "${t_spp[*]}" "${t_sec[*]}" "${t_err[*]}" "${s_sec[*]}" "${s_err[*]}" <<'EOF2'
import sys
f = lambda a: [float(x) for x in a.split()]
sec, spp, ts, t, ss, s = sys.argv[1], sys.argv[2].split(), f(sys.argv[3]), f(sys.argv[4]), f(sys.argv[5]), f(sys.argv[6])
mean = lambda a: sum(a) / len(a)
ratios = [si * sv / (ti * tv) for si, sv, ti, tv in zip(s, ss, t, ts)]
print("| %s | %.1f, %s | %.4f (%.4f–%.4f) | %.1f | %.4f (%.4f–%.4f) | %.2f× (%.2f–%.2f) |" % (
    sec, mean(ts), "/".join(spp), mean(t), min(t), max(t), mean(ss), mean(s), min(s), max(s),
    mean(s) * mean(ss) / (mean(t) * mean(ts)), min(ratios), max(ratios)))
EOF2
done
