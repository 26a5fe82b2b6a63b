#!/usr/bin/env bash
# Proves the README's two set-up commands on a machine that has never seen the project: a minimal
# Debian 12 root file system (`mmdebstrap --variant=apt bookworm`: essential packages and apt,
# nothing else), the committed tree (`git archive HEAD`) copied into it, then inside it, as a new
# user would type them:
#     tools/render.sh     (installs what is missing, builds, renders the Cornell box)
#     tools/test.sh       (installs what is missing, builds, fetches the test meshes, runs every test)
# Prints the time of each step and fails loudly naming the step that broke (exit 1).
#
#   tools/fresh_check.sh [--keep] [--no-cache] [--study]
#     --keep       keep the root file system (its path is printed) instead of deleting it
#     --no-cache   bootstrap a new root file system even when today's is cached
#     --study      then, as the README says for the study: tools/bootstrap.sh --install study and
#                  tools/study --quick (CI's smoke test of the study, on this Release build)
#
# Only the bootstrap tarball is cached (one a day, in $TESSERA_CACHE or ~/.cache/tessera/fresh-check):
# it holds nothing of the project. The project's packages, build and test meshes are never cached.
# Needs root (chroot, mounts in a private mount namespace, so nothing stays mounted) and the
# network to Debian's archive and the npm registry, as a new user's machine has.
# Uncommitted changes are NOT checked: commit first (a warning says so).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
keep=0; use_cache=1; study=0
for a in "$@"; do
  case "$a" in
    --keep) keep=1 ;;
    --no-cache) use_cache=0 ;;
    --study) study=1 ;;
    *) echo "usage: tools/fresh_check.sh [--keep] [--no-cache] [--study]" >&2; exit 2 ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "fresh_check: needs root (chroot and mounts)" >&2; exit 2; }
# Everything below runs in a private mount namespace: the root file system's tmpfs and its proc,
# sys and dev mounts vanish with this process, however it ends.
if [ -z "${TESSERA_FRESH_CHECK_NS:-}" ]; then
  exec unshare --mount --propagation private env TESSERA_FRESH_CHECK_NS=1 bash "$0" "$@"
fi

t_start=$SECONDS
step_name=""; step_t0=0
declare -a report=()
begin() { step_name="$1"; step_t0=$SECONDS; echo "== fresh_check: $1"; }
end() { local dt=$((SECONDS - step_t0)); report+=("$(printf '%-50s %5d s' "$step_name" "$dt")"); echo "== fresh_check: $step_name: ${dt} s"; step_name=""; }
on_exit() {
  local rc=$?
  if [ -n "$step_name" ] && [ $rc -ne 0 ]; then
    echo "" >&2
    echo "fresh_check: FAILED at step '$step_name' (exit $rc, after $((SECONDS - step_t0)) s)" >&2
  fi
  if [ -n "${rootfs:-}" ] && [ -d "$rootfs" ]; then
    if [ $keep -eq 1 ]; then echo "fresh_check: root file system kept at $rootfs" >&2
    else umount -R "$rootfs" 2>/dev/null; rmdir "$rootfs" 2>/dev/null || true; fi
  fi
  exit $rc
}
trap on_exit EXIT

begin "host packages (mmdebstrap)"
bash "$root/tools/bootstrap.sh" --install fresh
end

if [ -n "$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
  echo "fresh_check: warning: uncommitted changes are not part of the check (it uses git archive HEAD)" >&2
fi

cache="${TESSERA_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera}/fresh-check"
mkdir -p "$cache"
tarball="$cache/bookworm-apt-$(date -u +%Y%m%d).tar.zst"
begin "bootstrap Debian 12 (mmdebstrap --variant=apt)"
if [ $use_cache -eq 0 ] || [ ! -f "$tarball" ]; then
  rm -f "$cache"/bookworm-apt-*.tar.zst "$cache"/*.part
  mmdebstrap --quiet --variant=apt --mode=root bookworm "$tarball.part.tar.zst"
  mv "$tarball.part.tar.zst" "$tarball"
else
  echo "fresh_check: today's bootstrap tarball is cached: $tarball"
fi
end

begin "unpack root file system, copy git archive HEAD"
rootfs="$(mktemp -d "${TMPDIR:-/var/tmp}/tessera-fresh.XXXXXX")"
# On a tmpfs (unless kept): about 3 GiB with packages and build; deleting that many files from a disk
# that discards freed blocks takes minutes.
[ $keep -eq 1 ] || mount -t tmpfs -o size=12G,mode=755 tessera-fresh "$rootfs"
chmod 755 "$rootfs"
tar --zstd -xf "$tarball" -C "$rootfs"
# The network is the host's, and so are its settings: name servers, proxy variables, and the extra
# certificate authority of a network that intercepts TLS (named by NODE_EXTRA_CA_CERTS, as npm reads
# it). Nothing of the project is copied this way.
cp -L /etc/resolv.conf "$rootfs/etc/resolv.conf" 2>/dev/null || true
network_env=()
for v in http_proxy https_proxy no_proxy HTTP_PROXY HTTPS_PROXY NO_PROXY; do
  if [ -n "${!v:-}" ]; then network_env+=("$v=${!v}"); fi
done
if [ -n "${NODE_EXTRA_CA_CERTS:-}" ] && [ -f "$NODE_EXTRA_CA_CERTS" ]; then
  mkdir -p "$rootfs/etc/ssl"
  cp -L "$NODE_EXTRA_CA_CERTS" "$rootfs/etc/ssl/host-network-ca.crt"
  network_env+=("NODE_EXTRA_CA_CERTS=/etc/ssl/host-network-ca.crt")
fi
mkdir -p "$rootfs/root/tessera"
git -C "$root" archive --format=tar HEAD | tar -xf - -C "$rootfs/root/tessera"
echo "fresh_check: $(git -C "$root" rev-parse --short HEAD) in $rootfs/root/tessera"
end

# Commands run inside the root file system with proc, sys and dev mounted (in this process's private
# mount namespace) and a new user's environment: no TESSERA_* variables, no shared/ beside the
# checkout, HOME=/root; only the network settings above come from the host.
mount -t proc proc "$rootfs/proc"
mount -t sysfs sys "$rootfs/sys"
mount --rbind /dev "$rootfs/dev"
in_fresh() {
  env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 TERM=dumb ${network_env[@]+"${network_env[@]}"} \
    chroot "$rootfs" /bin/bash -c "cd /root/tessera && $*"
}

begin "README command 1: tools/render.sh"
in_fresh tools/render.sh
in_fresh 'test -s out/cornell-box.exr && test -s out/cornell-box.png' ||
  { echo "fresh_check: tools/render.sh did not write out/cornell-box.exr and .png" >&2; exit 1; }
end

begin "README command 2: tools/test.sh"
in_fresh 'tools/test.sh 2>&1 | tee /root/test.log; exit ${PIPESTATUS[0]}'
# Every test runs on a fresh machine: a skip here means an install or fetch step is missing (the
# test meshes come from the npm registry; when it cannot be reached this fails, saying so).
# The one exception: farm_local_slurm needs CI set (then tools/test.sh installs slurm-wlm and the
# test must run; .ci/run's own tools/test.sh step, under ASan, does that on the host), and the fresh
# root has no CI.
skipped="$(grep -E '\*\*\*Skipped|Skipped  *[0-9.]+ sec' "$rootfs/root/test.log" | grep -cv 'farm_local_slurm' || true)"
summary="$(grep -E 'tests passed|tests failed' "$rootfs/root/test.log" | tail -n 1)"
echo "fresh_check: $summary; skipped: $skipped"
if [ "$skipped" -ne 0 ]; then
  grep -E '\*\*\*Skipped|Skipped  *[0-9.]+ sec' "$rootfs/root/test.log" | grep -v 'farm_local_slurm' >&2
  echo "fresh_check: $skipped test(s) skipped on the fresh machine" >&2
  exit 1
fi
end

if [ $study -eq 1 ]; then
  begin "study smoke test: tools/study --quick"
  in_fresh 'tools/bootstrap.sh --install study && tools/study --quick'
  end
fi

echo ""
echo "fresh_check: passed in $((SECONDS - t_start)) s on $(nproc) cores ($(git -C "$root" rev-parse --short HEAD), $(date -u +%Y-%m-%d))"
for line in "${report[@]}"; do echo "  $line"; done
