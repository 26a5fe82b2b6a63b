#!/usr/bin/env bash
# Builds and runs the test suite under ASan+UBSan (build-asan/: every test) and the threaded tests
# under TSan (build-tsan/: scheduler, film, render, resume, determinism, furnace). Prints the wall
# time of each build and run. Usage: tools/sanitize.sh [asan|tsan|all]   (default all)
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
  # TBB, Embree and OIIO are not instrumented; the tests that exercise our threading (the tiled
  # scheduler, the film, splat merging, checkpoints written between passes, the interrupt flag)
  # are the point. The suppressions file lists only reports inside uninstrumented libraries, each
  # with the reason.
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tools/tsan.supp" \
    run tsan thread -R 'Determinism|Render|Furnace|Resume|NonFinite|RobustOutputs|DebugPixel' || status=1
fi
exit $status
