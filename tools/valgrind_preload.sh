#!/usr/bin/env bash
# Prints what LD_PRELOAD must hold for BINARY to run under Valgrind on this host, or nothing.
#
#   tools/valgrind_preload.sh BINARY
#
# Debian 12's OpenImageIO pulls in Highway (libhwy, through libjxl), whose load-time initialiser
# measures its timer with RDTSCP. Valgrind 3.19 (Debian 12's) cannot decode RDTSCP: on a CPU that
# reports it, every Tessera process dies of SIGILL under Valgrind before main(), and callgrind's
# totals are then those of the dynamic linker alone. The preloaded library replaces that one
# function, hwy::platform::TimerResolution(), which only Highway's own benchmarking uses; Tessera
# never calls it, so the program runs as it does outside Valgrind. It is compiled once into the
# cache folder ($TESSERA_CACHE, else $XDG_CACHE_HOME/tessera, else ~/.cache/tessera).
# Used by tools/bench_bdpt_speed.sh --instructions and tools/profile_accel.py.
set -euo pipefail
[ $# -eq 1 ] && [ -x "$1" ] || { echo "usage: tools/valgrind_preload.sh BINARY (an executable)" >&2; exit 2; }
LIBS=$(ldd "$1" 2>/dev/null || true)
case $LIBS in *libhwy.so*) ;; *) exit 0 ;; esac
CACHE=${TESSERA_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera}
SHIM=$CACHE/valgrind-hwy-timer.so
if [ ! -f "$SHIM" ]; then
    mkdir -p "$CACHE"
    SRC=$(mktemp --suffix=.cpp)
    trap 'rm -f "$SRC"' EXIT
    cat > "$SRC" <<'EOF'
// Highway's timer resolution without RDTSCP (tools/valgrind_preload.sh): one tick.
#include <cstdint>
namespace hwy { namespace platform { uint64_t TimerResolution() { return 1; } } }
EOF
    g++ -O2 -shared -fPIC -o "$SHIM.tmp" "$SRC"
    mv "$SHIM.tmp" "$SHIM"
fi
echo "$SHIM"
