#!/usr/bin/env bash
# A one-machine SLURM cluster for tests: munged, slurmctld and slurmd on
# localhost, every file (configuration, key, sockets, state, logs) inside one
# folder that the caller names.  Nothing outside that folder is touched.
#
#   cluster.sh start DIR [CPUS]   write DIR/slurm.conf, start the daemons, wait
#                                 until the node is idle; prints the line
#                                 "export SLURM_CONF=DIR/slurm.conf"
#   cluster.sh stop DIR           stop the daemons started in DIR, remove DIR
#
# Needs Debian's slurm-wlm and munge (installed by `tools/setup-deps --slurm`)
# and root (slurmd runs jobs as the submitting user).  CPUS (default 4) may
# exceed the machine's cores: the node is configured with
# SlurmdParameters=config_overrides so that array tasks overlap on a small
# machine.
set -euo pipefail
cmd=${1:?usage: cluster.sh start|stop DIR [CPUS]}
dir=${2:?usage: cluster.sh start|stop DIR [CPUS]}
cpus=${3:-4}

die() { echo "cluster.sh: $*" >&2; exit 1; }

free_port() {  # a TCP port nobody listens on, 20000-59999 (a refused connection means free)
    local p i
    for i in $(seq 200); do
        p=$((20000 + (RANDOM * 32768 + RANDOM) % 40000))
        if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then echo "$p"; return 0; fi
    done
    die "no free TCP port found on 127.0.0.1"
}

stop_pidfile() {  # FILE: TERM the process, wait up to 10 s, then KILL
    local f=$1 pid i
    [ -s "$f" ] || return 0
    pid=$(cat "$f")
    kill -TERM "$pid" 2>/dev/null || return 0
    for i in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null || true
}

case $cmd in
start)
    for p in munged slurmctld slurmd sbatch; do
        command -v "$p" >/dev/null || [ -x "/usr/sbin/$p" ] || die "$p not found (tools/setup-deps --slurm installs slurm-wlm and munge)"
    done
    [ "$(id -u)" -eq 0 ] || die "needs root (slurmd starts jobs as their user)"
    mkdir -p "$dir"
    dir=$(cd "$dir" && pwd)
    mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
    chmod 700 "$dir/munge"
    # munge: a key of its own, a socket of its own
    dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$dir/munge/munge.key"
    /usr/sbin/munged --force --key-file="$dir/munge/munge.key" \
        --socket="$dir/munge/munge.socket" --pid-file="$dir/munge/munged.pid" \
        --seed-file="$dir/munge/munged.seed" --log-file="$dir/log/munged.log" \
        || die "munged did not start (see $dir/log/munged.log)"
    ctlport=$(free_port); dport=$(free_port)
    while [ "$dport" = "$ctlport" ]; do dport=$(free_port); done
    cat > "$dir/slurm.conf" <<CONF
# one-machine test cluster written by test/slurm/cluster.sh
ClusterName=heliodon-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctlport
SlurmdPort=$dport
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmdParameters=config_overrides
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=600
KillWait=5
NodeName=hdnode NodeHostname=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=4000 State=UNKNOWN
PartitionName=test Nodes=hdnode Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF="$dir/slurm.conf"
    /usr/sbin/slurmctld -f "$SLURM_CONF" -i || die "slurmctld did not start (see $dir/log/slurmctld.log)"
    /usr/sbin/slurmd -f "$SLURM_CONF" -N hdnode || die "slurmd did not start (see $dir/log/slurmd.log)"
    for i in $(seq 100); do
        st=$(sinfo -h -N -o '%t' 2>/dev/null | head -1 || true)
        case $st in idle*|mix*|alloc*) echo "export SLURM_CONF=$SLURM_CONF"; exit 0 ;; esac
        [ "$i" -eq 30 ] && scontrol update nodename=hdnode state=resume >/dev/null 2>&1 || true
        sleep 0.3
    done
    echo "cluster.sh: node not idle after 30 s (state '${st:-none}'); logs:" >&2
    tail -5 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
    exit 1 ;;
stop)
    [ -d "$dir" ] || exit 0
    dir=$(cd "$dir" && pwd)
    [ -f "$dir/slurm.conf" ] || die "$dir/slurm.conf not found: not a cluster folder"
    stop_pidfile "$dir/slurmd.pid"
    stop_pidfile "$dir/slurmctld.pid"
    stop_pidfile "$dir/munge/munged.pid"
    rm -rf "$dir" ;;
*) die "unknown command '$cmd' (start or stop)" ;;
esac
