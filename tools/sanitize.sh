#!/usr/bin/env bash
# Builds and runs the test suite under ASan+UBSan (build-asan/: every test) and every test that
# renders under TSan (build-tsan/: the scheduler's pool, film, render, resume, determinism, furnace,
# non-finite, robust outputs, debug pixel, integrators, scenes, stability). Prints the wall time of
# each build and run. Usage: tools/sanitize.sh [asan|tsan|all]   (default all)
#   JOBS=N  parallel build/test jobs (default: nproc)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
what="${1:-all}"
jobs="${JOBS:-$(nproc)}"
run() {  # name sanitizers ctest-args...
  local name="$1" san="$2"; shift 2
  local t0=$SECONDS
  cmake -S "$root" -B "$root/build-$name" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTESSERA_SANITIZE="$san" >/dev/null
  nice cmake --build "$root/build-$name" -j "$jobs" >/dev/null
  local t1=$SECONDS
  echo "== $name: build $((t1 - t0)) s"
  local rc=0
  (cd "$root/build-$name" && nice ctest --output-on-failure -j "$jobs" "$@") || rc=$?
  echo "== $name: tests $((SECONDS - t1)) s, exit $rc"
  return $rc
}
status=0
if [ "$what" = asan ] || [ "$what" = all ]; then
  # Leaks are errors too. UBSan stops at the first report so a finding fails the test.
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    run asan address,undefined || status=1
fi
if [ "$what" = tsan ] || [ "$what" = all ]; then
  # The renderer runs on its own std::thread pool, so TSan sees all of our synchronisation. Left
  # out: tests that run nothing in parallel (maths, samplers, camera, image I/O, scene errors, the
  # malformed-input corpora, the installed-library consumer) and the acceleration-structure tests,
  # whose BVH builder and ray validator run on oneTBB (uninstrumented in Debian: its hand-offs look
  # like races; also the alpha-mask tests that run the validator, and the instancing tests, whose structures are our BVHs). Embree's and OIIO's own threads are suppressed in tools/tsan.supp, with reasons.
  # history_size=7: the longest per-thread access history, so that the earlier access of a report
  # keeps its stack (a suppression can only match frames TSan restored; tools/tsan.supp).
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:history_size=7:suppressions=$root/tools/tsan.supp" \
    run tsan thread -E '^(Accel|AccelRender|Bvh|KdTree|MalformedCorpus|MalformedMeshCorpus|Math|SamplingChi2|SceneErrors|Camera|ImageIo|ValidationVerdicts|Instances)\.|^AlphaMask\.Validat|^library_consumer$' || status=1
fi
exit $status
