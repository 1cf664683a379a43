#!/usr/bin/env bash
# A one-node Slurm on this machine, for trying `experiments slurm` and for CI.
#
#   scripts/slurm-local.sh up [--install]   # write /etc/slurm/slurm.conf, start munged, slurmctld, slurmd
#   scripts/slurm-local.sh status           # daemons and the node's state
#   scripts/slurm-local.sh down             # stop the three daemons by the PIDs in their pid files
#
# Needs root and the distribution's packages `slurm-wlm` and `munge`. It installs nothing unless
# asked: `up --install` runs `apt-get install -y --no-install-recommends slurm-wlm munge` when
# slurmctld is missing (run `apt-get update` first on a fresh machine). No systemd is used: the
# daemons are started directly and daemonize. One partition `debug` holds this node with every
# CPU it has; `DependencyParameters=kill_invalid_depend` makes a job whose `afterok` dependency
# failed or was cancelled end instead of staying pending forever. There is no accounting database,
# so `sacct` does not work: use `squeue` and `scontrol show job ID` (finished jobs stay visible for
# an hour, MinJobAge=3600). An existing slurm.conf that this script did not write is left alone.
set -euo pipefail

CONF=/etc/slurm/slurm.conf
MARK="# Written by scripts/slurm-local.sh (one-node Slurm for experiments)."
CTLD_PID=/run/slurmctld.pid
SLURMD_PID=/run/slurmd.pid
MUNGE_PID=/run/munge/munged.pid
LOGS=/var/log/slurm-local

die() { echo "slurm-local: $*" >&2; exit 1; }
alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

write_conf() {
  local host cpus mem
  host=$(hostname -s)
  # What slurmd sees; announcing more CPUs or memory than this would drain the node.
  cpus=$(slurmd -C | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' | head -1)
  mem=$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' | head -1)
  mem=$((mem * 9 / 10))
  if [ -f "$CONF" ] && ! grep -qF "$MARK" "$CONF"; then
    die "$CONF exists and was not written by this script; leaving it alone"
  fi
  mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd "$LOGS"
  cat > "$CONF" <<CONF
$MARK
ClusterName=local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$CTLD_PID
SlurmdPidFile=$SLURMD_PID
SlurmctldLogFile=$LOGS/slurmctld.log
SlurmdLogFile=$LOGS/slurmd.log
# No cgroups on this kind of machine.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# No accounting database: poll squeue / scontrol show job instead of sacct.
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MailProg=/bin/true
ReturnToService=2
# Keep finished jobs visible to scontrol for an hour.
MinJobAge=3600
# A job whose afterok dependency can no longer be met is cancelled, not left pending.
DependencyParameters=kill_invalid_depend
SchedulerType=sched/backfill
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
}

up() {
  [ "$(id -u)" = 0 ] || die "run as root (the daemons and /etc/slurm need it)"
  if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    if [ "${1:-}" = "--install" ]; then
      DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends slurm-wlm munge
    else
      die "slurm-wlm and munge are not installed: run 'apt-get install -y --no-install-recommends slurm-wlm munge' or '$0 up --install'"
    fi
  fi
  write_conf
  if [ ! -s /etc/munge/munge.key ]; then
    mungekey --create --keyfile /etc/munge/munge.key 2>/dev/null \
      || dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
  fi
  install -d -o munge -g munge /run/munge
  alive "$MUNGE_PID" || runuser -u munge -- /usr/sbin/munged
  alive "$CTLD_PID" || slurmctld
  alive "$SLURMD_PID" || slurmd
  # The node is idle within a second or two.
  local state=""
  for _ in $(seq 1 60); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -1 || true)
    case "$state" in idle|mixed|allocated) break ;; esac
    sleep 0.5
  done
  case "$state" in
    idle|mixed|allocated) echo "slurm-local: up, node $(hostname -s) $state (config $CONF, logs $LOGS)" ;;
    *) die "the node did not come up (state '${state:-none}'); see $LOGS" ;;
  esac
}

stop_pid() {
  local file=$1 name=$2 pid
  if ! [ -f "$file" ]; then echo "slurm-local: $name: no pid file"; return; fi
  pid=$(cat "$file")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then kill -9 "$pid" 2>/dev/null || true; fi
    echo "slurm-local: stopped $name (pid $pid)"
  else
    echo "slurm-local: $name (pid $pid) was not running"
  fi
  rm -f "$file"
}

down() {
  stop_pid "$SLURMD_PID" slurmd
  stop_pid "$CTLD_PID" slurmctld
  stop_pid "$MUNGE_PID" munged
}

status() {
  for f in "$MUNGE_PID" "$CTLD_PID" "$SLURMD_PID"; do
    if alive "$f"; then echo "$(basename "$f" .pid): running (pid $(cat "$f"))"; else echo "$(basename "$f" .pid): stopped"; fi
  done
  alive "$CTLD_PID" && sinfo || true
}

case "${1:-}" in
  up) shift; up "$@" ;;
  down) down ;;
  status) status ;;
  *) echo "usage: $0 up [--install] | status | down" >&2; exit 2 ;;
esac
