#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for testing `ndcontour experiment --executor slurm`
# (docs/experiments.md, tests/slurm_executor_test.sh). Everything lives under DIR: a MUNGE key and
# its own munged (socket, pid, log, seed), slurm.conf, the controller's state, the
# node's spool, logs and pid files. Needs the packages of `scripts/setup.sh --slurm`.
#
# Usage: scripts/slurm-cluster.sh start DIR   starts munged, slurmctld and slurmd and waits until
#                                             the node is idle; then use the cluster with
#                                             SLURM_CONF=DIR/slurm.conf in the environment
#        scripts/slurm-cluster.sh stop DIR    stops the daemons started in DIR
# Run as root (as slurmd must be).
#
# Environment: NDC_SLURM_PORT  the controller's port (default 6817); the node uses the next one
#              NDC_SLURM_WAIT  seconds to wait for each daemon and for the idle node (default 60)
set -euo pipefail

usage() {
  echo "usage: scripts/slurm-cluster.sh start|stop DIR" >&2
  exit 2
}
[[ $# -eq 2 ]] || usage
action=$1
mkdir -p "$2"
dir=$(cd "$2" && pwd)
port=${NDC_SLURM_PORT:-6817}
wait_s=${NDC_SLURM_WAIT:-60}

die() {
  echo "slurm-cluster: $*" >&2
  exit 1
}

# Prints the last lines of a log, to explain a failure.
show_log() {
  if [[ -s $1 ]]; then
    echo "slurm-cluster: last lines of $1:" >&2
    tail -n 15 "$1" >&2
  fi
}

# Runs "$@" every half second until it succeeds, at most $wait_s seconds; its status.
wait_for() {
  local deadline=$((SECONDS + wait_s))
  until "$@" >/dev/null 2>&1; do
    ((SECONDS < deadline)) || return 1
    sleep 0.5
  done
}

# Stops the daemon whose pid file is $1: SIGTERM, then SIGKILL after five seconds.
stop_daemon() {
  local pid
  [[ -s $1 ]] || return 0
  pid=$(<"$1")
  if [[ $pid =~ ^[0-9]+$ ]] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -KILL "$pid" 2>/dev/null || true
  fi
  rm -f "$1"
}

stop() {
  stop_daemon "$dir/run/slurmd.pid"
  stop_daemon "$dir/run/slurmctld.pid"
  stop_daemon "$dir/munge/munged.pid"
}

write_config() {
  local host cpus
  host=$(hostname -s)
  cpus=$(nproc)
  cat >"$dir/slurm.conf" <<EOF
# A single-node cluster on localhost for tests (scripts/slurm-cluster.sh).
ClusterName=ndctest
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
MailProg=/bin/true
# No cgroups (containers often have none to give): processes tracked through /proc.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1024 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  # No cgroup.conf: Slurm 22.05 has no `CgroupPlugin=disabled`, and with proctrack/linuxproc and
  # task/none no cgroup plugin is used.
  rm -f "$dir/cgroup.conf"
  : >"$dir/plugstack.conf"
}

start_munge() {
  local m=$dir/munge
  mkdir -p "$m"
  chmod 0700 "$m"
  [[ -s $m/munge.key ]] || mungekey --create --keyfile="$m/munge.key" >/dev/null
  chmod 0400 "$m/munge.key"
  munged --force --socket="$m/munge.socket" --key-file="$m/munge.key" \
    --pid-file="$m/munged.pid" --log-file="$m/munged.log" --seed-file="$m/munged.seed" ||
    { show_log "$m/munged.log"; die "munged did not start"; }
  wait_for munge -n -S "$m/munge.socket" ||
    { show_log "$m/munged.log"; die "munged does not answer on $m/munge.socket"; }
}

# Starts a Slurm daemon ($1: slurmctld or slurmd) and waits for its pid file.
start_daemon() {
  local name=$1
  shift
  timeout "$wait_s" "$name" -f "$dir/slurm.conf" "$@" ||
    { show_log "$dir/log/$name.log"; die "$name did not start"; }
  wait_for test -s "$dir/run/$name.pid" ||
    { show_log "$dir/log/$name.log"; die "$name wrote no pid file in $wait_s s"; }
}

node_idle() {
  [[ $(timeout 10 sinfo -h -N -o %t 2>/dev/null) == idle ]]
}

start() {
  [[ $(id -u) -eq 0 ]] || die "needs root (slurmd starts the jobs as their users)"
  for program in munged mungekey munge slurmctld slurmd sinfo; do
    command -v "$program" >/dev/null || die "$program not found (scripts/setup.sh --slurm)"
  done
  stop # a cluster left behind in DIR by an earlier run
  rm -rf "$dir/state" "$dir/spool"
  mkdir -p "$dir/state" "$dir/spool" "$dir/run" "$dir/log"
  write_config
  export SLURM_CONF=$dir/slurm.conf
  start_munge
  start_daemon slurmctld -c -i
  start_daemon slurmd
  if ! wait_for node_idle; then
    timeout 10 sinfo -N -l >&2 || true
    timeout 10 sinfo -R >&2 || true
    show_log "$dir/log/slurmctld.log"
    show_log "$dir/log/slurmd.log"
    stop
    die "the node did not become idle in $wait_s s"
  fi
  echo "slurm-cluster: up in $dir (export SLURM_CONF=$dir/slurm.conf)" >&2
}

case "$action" in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
