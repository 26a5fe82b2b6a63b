#!/usr/bin/env bash
# Builds the libFuzzer target for the glTF loader with clang + ASan/UBSan and runs it.
#   tools/fuzz.sh [SECONDS]      (default 300)
# Seed corpus: the shipped scenes and tests/corpus/malformed. New crashes are written to
# build-fuzz/crashes/; add each one to tests/corpus/malformed once fixed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-300}"
for p in clang libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=" $p"
done
if [ -n "${missing:-}" ]; then
  apt-get update -qq >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
build="$root/build-fuzz"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DTESSERA_FUZZ=ON -DTESSERA_BUILD_TESTS=OFF -DTESSERA_SANITIZE=address,undefined >/dev/null
cmake --build "$build" -j "$(nproc)" --target fuzz_gltf_loader >/dev/null
mkdir -p "$build/corpus" "$build/crashes"
cp "$root"/scenes/*/*.gltf "$root"/tests/corpus/malformed/*.gltf "$build/corpus/" 2>/dev/null || true
cd "$build"
UBSAN_OPTIONS=halt_on_error=1 ./tests/fuzz/fuzz_gltf_loader -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
  -artifact_prefix="$build/crashes/" "$build/corpus" 2>&1 | tee "$build/fuzz.log" | grep -E "^#[0-9]+ +(DONE|pulse)|ERROR|SUMMARY" || true
tail -n 3 "$build/fuzz.log"
