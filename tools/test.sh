#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite with CTest (2 jobs).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/bootstrap.sh"
cd "$TESSERA_BUILD"
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "$@"
