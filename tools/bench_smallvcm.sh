#!/usr/bin/env bash
# Equal-time comparison of Tessera's `bdpt` with SmallVCM's bidirectional path tracer (`-a bpt`) on
# SmallVCM's Cornell box (large mirror sphere, ceiling light box, diffuse floor), reproduced as
# scenes/smallvcm-cornell (tools/make_scenes.py). One thread each, pinned to one core, equal CPU time.
#
#   tools/bench_smallvcm.sh --fetch            # clone and build SmallVCM into the cache folder
#   tools/bench_smallvcm.sh [options]          # run the comparison, print a Markdown table
#
# Options:
#   --fetch              clone SmallVCM (MIT, github.com/SmallVCM/SmallVCM, commit below) into
#                        $SMALLVCM_DIR (default: ${XDG_CACHE_HOME:-~/.cache}/tessera/smallvcm),
#                        make the two local changes below and build it (g++, OpenMP); then exit
#   --spp "N ..."        samples per pixel of the timed runs (SmallVCM: iterations; default "2 4 8")
#   --runs N             runs per renderer and sample count, each with its own seed (default 3)
#   --ref-seconds S      seconds of each renderer's reference render, on all cores (default 120)
#   --out DIR            working folder for the images (default out/bench-smallvcm)
#   --tessera PATH       the tessera binary (default build/src/tessera)
#   --cpu N              the core the timed runs are pinned to (default 1)
#   --accel NAME         Tessera's acceleration structure for the timed runs (default embree; the
#                        references always use embree)
#
# Local changes made to SmallVCM's config.hxx (sed, never committed anywhere): one more scene
# configuration, kLargeMirrorSphere | kLightCeiling without kGlossyFloor (scene id 4: SmallVCM's
# glossy floor is a Phong lobe Tessera does not have), and the base seed read from $SMALLVCM_SEED
# (default 1234 as upstream) so that repeated runs are independent.
#
# The reference is the average of one long render of each renderer (their means are printed first:
# they must agree within noise for the comparison to mean anything); relMSE is `tessera compare`'s
# mean over pixels and RGB of (x − r)² / (r² + 0.01).
#
# Time is CPU time (user + sys of the process, one thread), not wall time: on a shared machine a
# pinned process may get a fraction of its core, and the two renderers' wall-clock budgets then
# measure the load, not the renderer. Each renderer's CPU time is fitted over all its runs as
# start-up + spp × time per pass (start-up: loading libraries and the scene, allocating, writing
# the image: about 0.4 s each on 512²), and only the per-pass part counts, for both alike (with a
# single --spp value no start-up can be fitted, and whole CPU times count). Both estimators are
# unbiased, so relMSE falls as 1/time and relMSE × CPU seconds (inverse efficiency) compares them
# at equal time: the last column is SmallVCM's relMSE·s over Tessera's, i.e. how many times lower
# Tessera's error is at equal time; the last line gives the same from every run at once (relMSE ×
# spp averaged over the budgets).
set -euo pipefail

SMALLVCM_URL=https://github.com/SmallVCM/SmallVCM
SMALLVCM_COMMIT=a13690f
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SMALLVCM_DIR=${SMALLVCM_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera/smallvcm}
SPPS="2 4 8"
RUNS=3
REF_SECONDS=120
OUT=$ROOT/out/bench-smallvcm
TESSERA=$ROOT/build/src/tessera
CPU=1
ACCEL=embree
FETCH=0
while [ $# -gt 0 ]; do
    case $1 in
    --fetch) FETCH=1 ;;
    --spp) SPPS=$2; shift ;;
    --runs) RUNS=$2; shift ;;
    --ref-seconds) REF_SECONDS=$2; shift ;;
    --out) OUT=$2; shift ;;
    --tessera) TESSERA=$2; shift ;;
    --cpu) CPU=$2; shift ;;
    --accel) ACCEL=$2; shift ;;
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
# cpu OUT COMMAND...: runs COMMAND (its stdout into OUT.log), prints its CPU seconds (user + sys).
cpu() { /usr/bin/time -f "%U %S" -o "$1.time" "${@:2}" > "$1.log" && awk '{print $1 + $2}' "$1.time"; }
# Tessera: `bdpt`, max depth 9 bounces = SmallVCM's default maximum path length of 10 segments.
tessera() {  # spp threads seed output [prefix...]: prints CPU seconds
    local spp=$1 threads=$2 seed=$3 out=$4; shift 4
    cpu "$out" "$@" "$TESSERA" render "$SCENE" --integrator bdpt --max-depth 9 --spp "$spp" --threads "$threads" \
        --seed "$seed" --accel "$ACCEL" -o "$out" --no-png --quiet
}
smallvcm() {  # iterations threads seed output [prefix...]: prints CPU seconds
    local it=$1 threads=$2 seed=$3 out=$4; shift 4
    cpu "$out" env SMALLVCM_SEED="$seed" OMP_NUM_THREADS="$threads" "$@" "$SMALLVCM" -s 4 -a bpt -i "$it" -o "$out"
}
relmse() { "$TESSERA" compare "$1" "$2" --json | json "d['relmse']"; }
means() { "$TESSERA" compare "$1" "$1" --json | json "' '.join('%.5f' % m for m in d['mean_test'])"; }

NPROC=$(nproc)
if [ ! -f "$OUT/ref.exr" ]; then
    echo "references: $REF_SECONDS s each on $NPROC threads" >&2
    "$TESSERA" render "$SCENE" --integrator bdpt --max-depth 9 --time "$REF_SECONDS" --threads "$NPROC" --seed 1000 \
        -o "$OUT/ref-tessera.exr" --no-png --quiet --json > "$OUT/ref-tessera.json"
    (cd "$OUT" && SMALLVCM_SEED=1000 OMP_NUM_THREADS=$NPROC "$SMALLVCM" -s 4 -a bpt -t "$REF_SECONDS" -o ref-smallvcm.hdr > ref-smallvcm.log)
    oiiotool "$OUT/ref-tessera.exr" "$OUT/ref-smallvcm.hdr" --add --mulc 0.5 -d float -o "$OUT/ref.exr"
fi
echo "Reference means (R G B): Tessera $(means "$OUT/ref-tessera.exr") ($(json "d['spp']" < "$OUT/ref-tessera.json") spp)," \
     "SmallVCM $(means "$OUT/ref-smallvcm.hdr"); relMSE between the two references:" \
     "$(relmse "$OUT/ref-tessera.exr" "$OUT/ref-smallvcm.hdr")"
echo
echo "| spp | Tessera bdpt: CPU s | relMSE (mean, min–max) | SmallVCM bpt: CPU s | relMSE (mean, min–max) | SmallVCM / Tessera relMSE·s (mean, min–max) |"
echo "|---|---|---|---|---|---|"
: > "$OUT/runs.txt"
for spp in $SPPS; do
    for run in $(seq "$RUNS"); do
        # Interleaved, pinned to one core.
        t_sec=$(tessera "$spp" 1 "$run" "$OUT/t-$spp-$run.exr" taskset -c "$CPU")
        t_err=$(relmse "$OUT/t-$spp-$run.exr" "$OUT/ref.exr")
        s_sec=$(cd "$OUT" && smallvcm "$spp" 1 "$run" "s-$spp-$run.hdr" taskset -c "$CPU")
        s_err=$(relmse "$OUT/s-$spp-$run.hdr" "$OUT/ref.exr")
        echo "$spp $t_sec $t_err $s_sec $s_err" >> "$OUT/runs.txt"
    done
done
# The fit and the ratios of the header's "Time is CPU time" paragraph (least squares over every run).
python3 - "$OUT/runs.txt" <<'EOF2'
import sys
rows = [[float(x) for x in line.split()] for line in open(sys.argv[1]) if line.strip()]
mean = lambda a: sum(a) / len(a)
def fit(xs, ys):
    mx, my = mean(xs), mean(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else my / mx
    return my - slope * mx, slope
spps = sorted(set(r[0] for r in rows))
t0, tb = fit([r[0] for r in rows], [r[1] for r in rows])
s0, sb = fit([r[0] for r in rows], [r[3] for r in rows])
for spp in spps:
    rs = [r for r in rows if r[0] == spp]
    t, s = [r[2] for r in rs], [r[4] for r in rs]
    tt, st = tb * spp, sb * spp
    ratios = [si * st / (ti * tt) for si, ti in zip(s, t)]
    print("| %g | %.2f | %.4f (%.4f–%.4f) | %.2f | %.4f (%.4f–%.4f) | %.2f× (%.2f–%.2f) |" % (
        spp, tt, mean(t), min(t), max(t), st, mean(s), min(s), max(s), mean(s) * st / (mean(t) * tt), min(ratios), max(ratios)))
# relMSE × spp is each estimator's error per sample pass.
et = mean([r[2] * r[0] for r in rows])
es = mean([r[4] * r[0] for r in rows])
print()
print("CPU s = start-up + spp × s per pass (fit over all runs): Tessera %.2f + %.3f·spp, SmallVCM %.2f + %.3f·spp;"
      " time per pass SmallVCM / Tessera %.2f×" % (t0, tb, s0, sb, sb / tb))
print("relMSE × spp (mean over all runs): Tessera %.3f, SmallVCM %.3f; equal-time error ratio SmallVCM / Tessera: %.2f×"
      % (et, es, es * sb / (et * tb)))
EOF2
