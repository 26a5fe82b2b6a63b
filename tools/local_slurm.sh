#!/usr/bin/env bash
# A one-node Slurm on this machine, for the farm test (tests/test_farm_slurm.sh) and for trying
# `tessera farm` without a cluster.
#   tools/local_slurm.sh start DIR   install slurm-wlm and munge when missing (tools/bootstrap.sh
#                                    --install slurm), write DIR/slurm.conf and a MUNGE key, start
#                                    munged, slurmctld and slurmd; then `export SLURM_CONF=DIR/slurm.conf`
#   tools/local_slurm.sh stop DIR    stop exactly the daemons `start DIR` started (their pid files)
# Everything lives in DIR: configuration, key, socket, state, spool, logs and pid files; nothing in
# /etc, no systemd, no cgroups (proctrack/linuxproc, task/none). Slurm's daemons need root: run it as
# root or with password-less sudo. Exit status of start: 0 running, 3 cannot run here (the reason on
# stderr: not root, packages absent), 1 a daemon failed to come up (its log is printed).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmd="${1:-}"
dir="${2:-}"
if [ -z "$cmd" ] || [ -z "$dir" ]; then
  echo "usage: tools/local_slurm.sh start|stop DIR" >&2
  exit 2
fi
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then SUDO="sudo -n"; else
    echo "local_slurm: cannot run Slurm's daemons: not root and no password-less sudo" >&2
    exit 3
  fi
fi

# The pid in FILE, if that process is still the daemon DIR's configuration started (its command line
# names DIR or the daemon binary): a recycled pid is never touched.
live_pid() {  # pidfile daemon-name
  local f="$1" name="$2" pid
  [ -s "$f" ] || return 1
  pid="$($SUDO cat "$f")"
  [[ "$pid" =~ ^[0-9]+$ ]] || return 1
  [ -r "/proc/$pid/cmdline" ] || return 1
  tr '\0' ' ' <"/proc/$pid/cmdline" | grep -q -- "$name" || return 1
  echo "$pid"
}

stop_daemons() {
  local name pid i
  for name in slurmd slurmctld munged; do
    pid="$(live_pid "$dir/$name.pid" "$name")" || continue
    $SUDO kill -TERM "$pid" 2>/dev/null || true
    for i in $(seq 50); do [ -d "/proc/$pid" ] || break; sleep 0.1; done
    [ -d "/proc/$pid" ] && $SUDO kill -KILL "$pid" 2>/dev/null || true
  done
  return 0
}

if [ "$cmd" = stop ]; then
  stop_daemons
  exit 0
fi
if [ "$cmd" != start ]; then
  echo "usage: tools/local_slurm.sh start|stop DIR" >&2
  exit 2
fi

if ! bash "$ROOT/tools/bootstrap.sh" --install slurm >&2; then
  echo "local_slurm: cannot run Slurm: the packages slurm-wlm and munge are absent and cannot be installed" >&2
  exit 3
fi
for b in munged slurmctld slurmd sbatch; do
  command -v "$b" >/dev/null 2>&1 || PATH="$PATH:/usr/sbin"
  command -v "$b" >/dev/null 2>&1 || { echo "local_slurm: cannot run Slurm: $b not found after installing" >&2; exit 3; }
done

stop_daemons  # a previous run's leftovers in this DIR
mkdir -p "$dir/state" "$dir/spool" "$dir/log"
user="$(id -un)"
[ -n "$SUDO" ] && user=root

# A free TCP port pair for slurmctld and slurmd (another Slurm or test may hold the defaults).
read -r ctld_port slurmd_port < <(python3 - <<'PY'
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*(x.getsockname()[1] for x in s))
PY
)
cpus="$(nproc)"
mem_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 9 / 10 ))

cat >"$dir/slurm.conf" <<CONF
ClusterName=tessera-local
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF

# MUNGE: a key of our own, a socket in DIR. munged refuses a key readable by others.
if [ ! -s "$dir/munge.key" ]; then
  (umask 077; head -c 1024 /dev/urandom >"$dir/munge.key")
fi
chmod 700 "$dir"
$SUDO munged --force --key-file="$dir/munge.key" --socket="$dir/munge.socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/log/munged.log" --seed-file="$dir/munge.seed" || {
  echo "local_slurm: munged did not start:" >&2; tail -5 "$dir/log/munged.log" >&2 || true; exit 1; }

export SLURM_CONF="$dir/slurm.conf"
# -c: a clean start, no state of an earlier run; -N: this node's name in slurm.conf.
$SUDO env SLURM_CONF="$SLURM_CONF" slurmctld -c -f "$SLURM_CONF" || {
  echo "local_slurm: slurmctld did not start:" >&2; tail -20 "$dir/log/slurmctld.log" >&2 || true; stop_daemons; exit 1; }
$SUDO env SLURM_CONF="$SLURM_CONF" slurmd -N localhost -f "$SLURM_CONF" || {
  echo "local_slurm: slurmd did not start:" >&2; tail -20 "$dir/log/slurmd.log" >&2 || true; stop_daemons; exit 1; }

# Up when the node reports idle (at most 30 s).
for i in $(seq 150); do
  state="$(sinfo -h -N -o '%t' 2>/dev/null | head -1 || true)"
  [ "$state" = idle ] && { echo "local_slurm: running in $dir (export SLURM_CONF=$SLURM_CONF)" >&2; exit 0; }
  sleep 0.2
done
echo "local_slurm: the node did not become idle (state '${state:-none}'):" >&2
tail -10 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
stop_daemons
exit 1
