#!/usr/bin/env bash
# Builds and runs the test suite under ASan+UBSan (build-asan/) and the scheduler/film tests under
# TSan (build-tsan/). Usage: tools/sanitize.sh [asan|tsan|all]   (default all)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
what="${1:-all}"
run() {  # name sanitizers ctest-args...
  local name="$1" san="$2"; shift 2
  cmake -S "$root" -B "$root/build-$name" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTESSERA_SANITIZE="$san" >/dev/null
  cmake --build "$root/build-$name" -j "$(nproc)" >/dev/null
  (cd "$root/build-$name" && ctest --output-on-failure -j "$(nproc)" "$@")
}
if [ "$what" = asan ] || [ "$what" = all ]; then
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 run asan address,undefined
fi
if [ "$what" = tsan ] || [ "$what" = all ]; then
  # TBB and Embree are not instrumented; the tests that exercise our threading are the point here.
  TSAN_OPTIONS=halt_on_error=1 run tsan thread -R 'Determinism|Render|Furnace'
fi
