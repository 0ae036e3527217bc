#!/usr/bin/env bash
# Starts a one-node Slurm cluster on this machine (localhost), for the test of
# `rheodem study submit --slurm` (crates/rheodem-cli/tests/slurm.rs) and for trying the
# cluster path by hand. Installs Debian's slurm-wlm and munge when they are missing (needs
# root, as CI has). Everything Slurm writes goes under $RHEODEM_SLURM_DIR
# (default /tmp/rheodem-slurm); the configuration is $RHEODEM_SLURM_DIR/slurm.conf, so
# the Slurm commands need `export SLURM_CONF=$RHEODEM_SLURM_DIR/slurm.conf`.
#
#   bash .ci/slurm-local.sh          # start (or restart) the cluster; prints SLURM_CONF
#   bash .ci/slurm-local.sh stop     # stop it
set -euo pipefail
dir=${RHEODEM_SLURM_DIR:-/tmp/rheodem-slurm}
conf=$dir/slurm.conf

stop() {
    for daemon in slurmd slurmctld; do
        if [[ -f $dir/$daemon.pid ]]; then
            pid=$(cat "$dir/$daemon.pid")
            kill "$pid" 2>/dev/null || true
            # Wait for it to let go of its port before a new one starts.
            for _ in $(seq 50); do
                kill -0 "$pid" 2>/dev/null || break
                sleep 0.2
            done
            rm -f "$dir/$daemon.pid"
        fi
    done
}

if [[ ${1:-start} == stop ]]; then
    stop
    exit 0
fi

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "installing slurm-wlm and munge from Debian's packages" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurm-wlm munge >/dev/null
fi

stop
# A fresh controller state: no jobs of an earlier cluster come back.
rm -rf "$dir/state" "$dir/spool"
mkdir -p "$dir/state" "$dir/spool"
# munge: the package's key, or a fresh one; the daemon runs as root here.
if [[ ! -s /etc/munge/munge.key ]]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
fi
chmod 0400 /etc/munge/munge.key
mkdir -p /run/munge /var/log/munge /var/lib/munge
if ! munge -n >/dev/null 2>&1; then
    munged --force
fi
munge -n | unmunge >/dev/null

host=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))
cat >"$conf" <<CONF
ClusterName=rheodem-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$conf
slurmctld -f "$conf"
slurmd -f "$conf"
# Wait until the node takes jobs.
for _ in $(seq 60); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -n1 || true)
    if [[ $state == idle* || $state == mixed* ]]; then
        echo "Slurm is up on $host ($cpus CPUs); export SLURM_CONF=$conf"
        exit 0
    fi
    sleep 1
done
echo "Slurm did not come up; node state '${state:-none}'; logs in $dir" >&2
tail -n 20 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
exit 1
