#!/usr/bin/env bash
# Builds the libFuzzer targets for the scene loaders, the batch jobs parser and the partial reader
# with clang + ASan/UBSan and runs them.
#   tools/fuzz.sh [SECONDS] [gltf|mesh|batch|partial|all]      (default 300 s per target, all)
# Seed corpora: gltf: the shipped scenes, tests/corpus/malformed and tests/fuzz/seeds (textured GLB and data-URI scenes); mesh: tests/corpus/malformed-mesh,
# partial: tests/fuzz/seeds/*.partial (a 6x4 bdpt partial of the Cornell box);
# a valid quad in PLY (ASCII, binary) and OBJ, and the smallest Stanford bunny when TESSERA_ASSETS
# (default ../shared/data) has it; batch (the JOBS files of `tessera batch`): tests/fuzz/seeds/jobs.json.
# New crashes are written to build-fuzz/crashes-TARGET/; add each
# one to tests/corpus/malformed or tests/corpus/malformed-mesh (batch: a case of
# Batch.MalformedJobsFileIsOneLineNamingThePointer in tests/test_batch.cpp) once fixed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-300}"
which="${2:-all}"
bash "$root/tools/bootstrap.sh" --install build fuzz
build="$root/build-fuzz"
targets=()
[ "$which" = gltf ] || [ "$which" = all ] && targets+=(gltf)
[ "$which" = mesh ] || [ "$which" = all ] && targets+=(mesh)
[ "$which" = batch ] || [ "$which" = all ] && targets+=(batch)
[ "$which" = partial ] || [ "$which" = all ] && targets+=(partial)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DTESSERA_FUZZ=ON -DTESSERA_BUILD_TESTS=OFF -DTESSERA_SANITIZE=address,undefined >/dev/null
# The loaders' targets are fuzz_NAME_loader; the batch parser's is fuzz_batch_jobs.
fuzz_target() { if [ "$1" = batch ]; then echo fuzz_batch_jobs; else echo "fuzz_$1_loader"; fi; }
for t in "${targets[@]}"; do
  nice cmake --build "$build" -j "$(nproc)" --target "$(fuzz_target "$t")" >/dev/null
done

# Seeds.
mkdir -p "$build/corpus-gltf" "$build/corpus-mesh" "$build/corpus-batch" "$build/corpus-partial"
cp "$root"/tests/fuzz/seeds/*.json "$build/corpus-batch/"
cp "$root"/tests/fuzz/seeds/*.partial "$build/corpus-partial/"
cp "$root"/scenes/*/*.gltf "$root"/tests/corpus/malformed/*.gl[tb]* "$root"/tests/fuzz/seeds/*.gl[tb]* "$build/corpus-gltf/" 2>/dev/null || true
cp "$root"/tests/corpus/malformed-mesh/* "$build/corpus-mesh/"
printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n' \
  > "$build/corpus-mesh/quad-ascii.ply"
python3 - "$build/corpus-mesh/quad-binary.ply" <<'PY'
import struct, sys
h = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
v = b"".join(struct.pack("<3f", *p) for p in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
f = struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B3i", 3, 0, 2, 3)
open(sys.argv[1], "wb").write(h + v + f)
PY
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 -1/1\n' > "$build/corpus-mesh/quad.obj"
assets="${TESSERA_ASSETS:-$root/../shared/data}"
[ -f "$assets/stanford-bunny/bun_zipper_res4.ply" ] && cp "$assets/stanford-bunny/bun_zipper_res4.ply" "$build/corpus-mesh/"

cd "$build"
for t in "${targets[@]}"; do
  mkdir -p "crashes-$t"
  echo "== $(fuzz_target "$t"), ${seconds} s"
  dict=()
  [ "$t" = batch ] && dict=(-dict="$root/tests/fuzz/jobs.dict")
  UBSAN_OPTIONS=halt_on_error=1 nice "./tests/fuzz/$(fuzz_target "$t")" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -artifact_prefix="$build/crashes-$t/" "corpus-$t" 2>&1 | tee "fuzz-$t.log" | grep -E "^#[0-9]+ +(DONE|pulse)|ERROR|SUMMARY" || true
  tail -n 3 "fuzz-$t.log"
  echo "crash inputs: $(ls "crashes-$t" | wc -l)"
done
