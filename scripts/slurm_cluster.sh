#!/usr/bin/env bash
# A real single-node Slurm cluster on this host, for the farm tests: controller and compute node
# both here, state under one directory. Usage:
#   scripts/slurm_cluster.sh install          # Debian's slurm-wlm daemons + munge (idempotent)
#   scripts/slurm_cluster.sh start DIR        # writes DIR/slurm.conf, starts munged, slurmctld, slurmd
#   scripts/slurm_cluster.sh stop DIR
# Clients need SLURM_CONF=DIR/slurm.conf in their environment.
set -euo pipefail

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

install() {
  local missing=()
  for pkg in slurmctld slurmd slurm-client munge; do
    dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    as_root apt-get update -qq
    DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq "${missing[@]}" >/dev/null
  fi
}

start() {
  local dir=$1 host cpus mem
  mkdir -p "$dir/state" "$dir/spool"
  host=$(hostname -s)
  cpus=$(nproc)
  mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))

  # munge: a key, a socket directory, the daemon (as the munge user it insists on).
  if [ ! -s /etc/munge/munge.key ]; then
    as_root mkdir -p /etc/munge
    as_root dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
  fi
  as_root chown munge:munge /etc/munge/munge.key && as_root chmod 400 /etc/munge/munge.key
  as_root mkdir -p /run/munge /var/lib/munge /var/log/munge
  as_root chown munge:munge /run/munge /var/lib/munge /var/log/munge
  if ! munge -n >/dev/null 2>&1; then
    as_root runuser -u munge -- /usr/sbin/munged
    for _ in $(seq 50); do munge -n >/dev/null 2>&1 && break; sleep 0.1; done
  fi

  cat > "$dir/slurm.conf" <<CONF
ClusterName=coif-test
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=${COIF_SLURMCTLD_PORT:-16817}
SlurmdPort=${COIF_SLURMD_PORT:-16818}
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=coif Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$dir/slurm.conf
  as_root env SLURM_CONF="$SLURM_CONF" slurmctld -c
  as_root env SLURM_CONF="$SLURM_CONF" slurmd -c
  for _ in $(seq 100); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
      echo "slurm: up (SLURM_CONF=$SLURM_CONF)"
      return 0
    fi
    sleep 0.2
  done
  echo "slurm: the node did not come up; logs in $dir" >&2
  return 1
}

stop() {
  local dir=$1
  for daemon in slurmd slurmctld; do
    if [ -s "$dir/$daemon.pid" ]; then
      as_root kill "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
    fi
  done
  for _ in $(seq 50); do
    { [ -s "$dir/slurmd.pid" ] && kill -0 "$(cat "$dir/slurmd.pid")" 2>/dev/null; } || \
    { [ -s "$dir/slurmctld.pid" ] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; } || break
    sleep 0.1
  done
}

case "${1:-}" in
  install) install ;;
  start) start "${2:?state directory}" ;;
  stop) stop "${2:?state directory}" ;;
  *) echo "usage: $0 install | start DIR | stop DIR" >&2; exit 2 ;;
esac
