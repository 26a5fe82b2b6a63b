#!/usr/bin/env bash
# Shared set-up for tools/render.sh and tools/test.sh: installs the Debian 12 packages Tessera needs
# (only those missing; silent when all are present), then configures and builds incrementally.
# Source it; it defines TESSERA_ROOT and TESSERA_BUILD.
set -euo pipefail

TESSERA_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
TESSERA_BUILD="${TESSERA_BUILD:-$TESSERA_ROOT/build}"

tessera_packages=(
  cmake g++ make git pkg-config
  libembree-dev libopenimageio-dev libopencolorio-dev libglm-dev libtinygltf-dev
  libgtest-dev libtbb-dev libcli11-dev nlohmann-json3-dev zlib1g-dev
)

tessera_install_packages() {
  local missing=()
  for p in "${tessera_packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
      echo "tessera: these packages are missing and I am not root (no sudo): ${missing[*]}" >&2
      exit 1
    fi
  fi
  echo "tessera: installing ${missing[*]}" >&2
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq >/dev/null
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

tessera_build() {
  local jobs
  jobs="$(nproc 2>/dev/null || echo 2)"
  if [ ! -f "$TESSERA_BUILD/CMakeCache.txt" ]; then
    cmake -S "$TESSERA_ROOT" -B "$TESSERA_BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
  fi
  cmake --build "$TESSERA_BUILD" -j "$jobs" -- --no-print-directory 2>&1 | { grep -vE '^\[ *[0-9]+%\]|^-- ' || true; }
  test "${PIPESTATUS[0]}" -eq 0
}

tessera_install_packages
tessera_build
