#!/usr/bin/env bash
# The README's test command (tools/test.sh) on a sanitizer build: the whole suite under ASan+UBSan
# (build-asan/), and every test that renders under TSan (build-tsan/: the scheduler's pool, film,
# render, resume, determinism, furnace, non-finite, robust outputs, debug pixel, integrators, scenes,
# stability). The builds and the sanitizers' run-time options are tools/bootstrap.sh's
# (TESSERA_SANITIZE). Prints the wall time of each. Usage: tools/sanitize.sh [asan|tsan|all]
# (default all); extra arguments go to ctest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
what="${1:-all}"; shift || true
run() {  # asan|tsan ctest-args...
  local name="$1"; shift
  local t0=$SECONDS rc=0
  TESSERA_SANITIZE="$name" bash "$root/tools/test.sh" "$@" || rc=$?
  echo "== $name: build and tests $((SECONDS - t0)) s, exit $rc"
  return $rc
}
status=0
if [ "$what" = asan ] || [ "$what" = all ]; then
  run asan "$@" || status=1
fi
if [ "$what" = tsan ] || [ "$what" = all ]; then
  # Left out under TSan: tests that run nothing in parallel (maths, samplers, camera, image I/O, scene
  # errors, the malformed-input corpora, the installed-library consumer); the acceleration-structure
  # tests, whose BVH builder and ray validator run on oneTBB (uninstrumented in Debian: its hand-offs
  # look like races; also the alpha-mask tests that run the validator, and the instancing tests, whose
  # structures are our BVHs); and the statistical tests and the per-scene surveys (agreement, furnace,
  # stability, caustic (MirrorCaustic included) and convergence tests, the shipped scenes against their references, every
  # WebXR model), which run the same pool, film and scheduler as the tests kept, only with more
  # samples: 1,900 of the 3,000 s the suite took under TSan on 2 cores (2026-11-27, all 208 clean).
  run tsan -E '^(Accel|AccelRender|Bvh|KdTree|MalformedCorpus|MalformedMeshCorpus|Math|SamplingChi2|SceneErrors|Camera|ImageIo|ValidationVerdicts|Instances|IntegratorAgreement|Stability|BdptCaustic|MirrorCaustic|SamplerConvergence|GltfBsdf|Furnace|VolumeAttenuation|EnvironmentFurnace|IntegratorFurnace|TexturedAgreement)\.|^(Shipped|Shards)/|^AlphaMask\.Validat|^Sppm\.KernelBias|^library_consumer$' "$@" || status=1
fi
exit $status
