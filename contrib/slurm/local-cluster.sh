#!/usr/bin/env bash
# Start or stop a throw-away, single-node Slurm cluster that lives entirely in
# one directory.  Meant for CI: run it as root on a Debian/Ubuntu machine with
#   apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge
# No systemd is needed (and none of the packages' system services is used).
#
#   local-cluster.sh start DIR   # writes DIR/slurm.conf, starts munged, slurmctld, slurmd
#   source DIR/env               # lets sbatch/squeue/scontrol/sinfo find the cluster
#   local-cluster.sh stop DIR    # kills the daemons by the PIDs recorded in DIR/run
#
# Everything the cluster writes goes below DIR:
#   DIR/slurm.conf  DIR/env
#   DIR/run/{munged,slurmctld,slurmd}.pid    the daemons' PIDs (what `stop` kills)
#   DIR/log/{munged,slurmctld,slurmd}.log    and DIR/log/jobcomp.log (one line per finished job)
#   DIR/munge/      a private munged's socket and seed (the system munged, if any, is left alone)
#   DIR/state/      slurmctld's StateSaveLocation and slurmd's spool
#
# Environment knobs (all optional):
#   SLURMCTLD_PORT (6817), SLURMD_PORT (6818)  change if a real Slurm runs on this host
#   MUNGE_KEY (/etc/munge/munge.key)           created if missing
#   START_TIMEOUT (60)                         seconds to wait for the node to become idle
#   STOP_TIMEOUT (15)                          seconds between SIGTERM and SIGKILL
set -euo pipefail

usage() {
    echo "usage: $0 start DIR | stop DIR | status DIR" >&2
    exit 2
}

log() { echo "local-cluster: $*" >&2; }
die() { log "error: $*"; exit 1; }

[[ $# -eq 2 ]] || usage
cmd=$1
mkdir -p "$2"
dir=$(cd "$2" && pwd -P)   # absolute: the config is read from other working directories

conf=$dir/slurm.conf
rundir=$dir/run
logdir=$dir/log
mungedir=$dir/munge
statedir=$dir/state

MUNGE_KEY=${MUNGE_KEY:-/etc/munge/munge.key}
SLURMCTLD_PORT=${SLURMCTLD_PORT:-6817}
SLURMD_PORT=${SLURMD_PORT:-6818}
START_TIMEOUT=${START_TIMEOUT:-60}
STOP_TIMEOUT=${STOP_TIMEOUT:-15}

# The daemons, in start order; `stop` goes through them backwards.
daemons=(munged slurmctld slurmd)

# pid_of NAME: prints the PID recorded for daemon NAME if that process is still
# alive *and* still that daemon (guards against a recycled PID); fails otherwise.
pid_of() {
    local name=$1 pidfile=$rundir/$1.pid pid comm
    [[ -s $pidfile ]] || return 1
    pid=$(tr -dc '0-9' <"$pidfile")
    [[ -n $pid ]] || return 1
    comm=$(cat "/proc/$pid/comm" 2>/dev/null) || return 1
    [[ $comm == "$name" ]] || return 1
    echo "$pid"
}

# wait_for SECONDS CMD...: retries CMD every half second until it succeeds.
wait_for() {
    local deadline=$((SECONDS + $1)); shift
    until "$@"; do
        ((SECONDS < deadline)) || return 1
        sleep 0.5
    done
}

# The daemons write their own pid files (they daemonize, then write the file),
# so wait until the file names a live process of the right name.
wait_pid() { wait_for "$2" pid_of "$1" >/dev/null; }

stop_cluster() {
    # Cancel whatever is still queued or running first, so no slurmstepd (and no
    # job) outlives slurmd.  Bounded, and harmless if slurmctld is already gone.
    if pid_of slurmctld >/dev/null && [[ -f $conf ]]; then
        local jobs
        jobs=$(SLURM_CONF=$conf timeout 10 squeue -h -o %A 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            # shellcheck disable=SC2086  # one argument per job id
            SLURM_CONF=$conf timeout 10 scancel $jobs 2>/dev/null || true
            sleep 1
        fi
    fi
    local i name pid
    for ((i = ${#daemons[@]} - 1; i >= 0; i--)); do
        name=${daemons[i]}
        if ! pid=$(pid_of "$name"); then
            rm -f "$rundir/$name.pid"
            continue
        fi
        log "stopping $name (pid $pid)"
        kill -TERM "$pid" 2>/dev/null || true
        if ! wait_for "$STOP_TIMEOUT" eval "! kill -0 $pid 2>/dev/null"; then
            log "$name (pid $pid) ignored SIGTERM for ${STOP_TIMEOUT}s, sending SIGKILL"
            kill -KILL "$pid" 2>/dev/null || true
            wait_for 5 eval "! kill -0 $pid 2>/dev/null" || log "warning: $name (pid $pid) still alive"
        fi
        rm -f "$rundir/$name.pid"
    done
    return 0
}

status_cluster() {
    local name pid rc=0
    for name in "${daemons[@]}"; do
        if pid=$(pid_of "$name"); then
            echo "$name: running (pid $pid)"
        else
            echo "$name: stopped"; rc=1
        fi
    done
    if [[ -f $conf ]] && pid_of slurmctld >/dev/null; then
        SLURM_CONF=$conf timeout 10 sinfo || true
    fi
    return $rc
}

# Prints the machine's memory in MiB, as slurmd measures it (RealMemory must
# not exceed what slurmd finds, or the node is drained as "Low RealMemory").
real_memory() {
    local mem
    mem=$(slurmd -C 2>/dev/null | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' | head -n1)
    if [[ -z $mem ]]; then
        mem=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 }' /proc/meminfo)
    fi
    echo "${mem:-1000}"
}

start_cluster() {
    [[ $(id -u) -eq 0 ]] || die "must run as root (SlurmUser=root, munged --force)"
    local tool
    for tool in munged mungekey slurmctld slurmd sinfo; do
        command -v "$tool" >/dev/null ||
            die "$tool not found; apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge"
    done
    # Fresh directories; a previous run's logs and state are thrown away.
    rm -rf "$rundir" "$logdir" "$mungedir" "$statedir"
    mkdir -p "$rundir" "$logdir" "$mungedir" "$statedir/ctld" "$statedir/slurmd"
    chmod 755 "$dir"   # munged warns about the socket if the path is not searchable

    # --- hostname ------------------------------------------------------------
    # slurmd finds its NodeName from `hostname -s`, slurmctld recognises itself
    # by it too.  Both hosts are given an explicit address (127.0.0.1), so name
    # resolution is not strictly needed, but some paths still resolve the name:
    # make sure it resolves, appending to /etc/hosts only if it does not.
    local host
    host=$(hostname -s)
    [[ -n $host ]] || die "hostname -s is empty"
    if ! getent hosts "$host" >/dev/null; then
        log "'$host' does not resolve; adding '127.0.0.1 $host' to /etc/hosts"
        echo "127.0.0.1 $host" >>/etc/hosts
    fi

    # Another Slurm (or another cluster of this script) on the same ports would
    # answer our clients instead of our daemons: refuse to start.
    local port
    for port in "$SLURMCTLD_PORT" "$SLURMD_PORT"; do
        if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
            die "port $port is in use (another Slurm running?); stop it or set SLURMCTLD_PORT/SLURMD_PORT"
        fi
    done

    # --- munge ---------------------------------------------------------------
    if [[ ! -s $MUNGE_KEY ]]; then
        log "creating munge key $MUNGE_KEY"
        mkdir -p "$(dirname "$MUNGE_KEY")"
        if ! mungekey --create --keyfile="$MUNGE_KEY" 2>/dev/null; then
            dd if=/dev/urandom of="$MUNGE_KEY" bs=1 count=1024 status=none
        fi
        if getent passwd munge >/dev/null; then
            chown munge:munge "$MUNGE_KEY"
        fi
        chmod 400 "$MUNGE_KEY"
    fi
    # A private munged, running as root: --force is needed because the Debian
    # key belongs to the munge user, and munged refuses a key not owned by the
    # user it runs as.  Its socket is in DIR, and slurm.conf points at it
    # (AuthInfo=socket=...), so a system munged, if any, is not involved.
    local socket=$mungedir/munge.socket
    ((${#socket} < 100)) || die "munge socket path too long for a unix socket: $socket (use a shorter DIR)"
    munged --force \
        --key-file="$MUNGE_KEY" \
        --socket="$socket" \
        --pid-file="$rundir/munged.pid" \
        --log-file="$logdir/munged.log" \
        --seed-file="$mungedir/munged.seed" ||
        die "munged failed to start; see $logdir/munged.log"
    wait_pid munged 10 || die "munged did not write $rundir/munged.pid"
    wait_for 10 test -S "$socket" || die "munged socket $socket did not appear"
    munge -n -S "$socket" | unmunge -S "$socket" >/dev/null ||
        die "munge round trip failed; see $logdir/munged.log"

    # --- slurm.conf ----------------------------------------------------------
    local cpus mem
    cpus=$(nproc)
    mem=$(real_memory)
    cat >"$conf" <<EOF
# Written by $0 on $(date -u +%FT%TZ) -- a single-node test cluster in $dir
ClusterName=local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$SLURMCTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root

AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket

# Everything on disk stays inside $dir
StateSaveLocation=$statedir/ctld
SlurmdSpoolDir=$statedir/slurmd
SlurmctldPidFile=$rundir/slurmctld.pid
SlurmdPidFile=$rundir/slurmd.pid
SlurmctldLogFile=$logdir/slurmctld.log
SlurmdLogFile=$logdir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf

# No cgroups (containers often cannot use them), no accounting database
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
# A text record of each finished job (state and exit code), kept after
# slurmctld forgets the job; MinJobAge keeps finished jobs in scontrol for 1 h.
JobCompType=jobcomp/filetxt
JobCompLoc=$logdir/jobcomp.log
MinJobAge=3600
MpiDefault=none
MailProg=/bin/true

# One job step per CPU, so an array runs one task per CPU at the same time
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# Trust the CPU/memory numbers below even if slurmd counts the hardware
# differently (threads vs cores, cgroup limits) instead of draining the node
SlurmdParameters=config_overrides
# A node that was DOWN comes back as soon as its slurmd registers
ReturnToService=2
SlurmdTimeout=300
InactiveLimit=0
KillWait=10

NodeName=$host NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    # An empty SPANK plugin list, so /etc/slurm/plugstack.conf is not used.
    : >"$dir/plugstack.conf"

    cat >"$dir/env" <<EOF
# source this file to use the cluster in $dir
export SLURM_CONF=$conf
EOF
    export SLURM_CONF=$conf

    # --- daemons ---------------------------------------------------------------
    # Both daemonize by themselves and write their pid files into $rundir
    # (no -D). -c on slurmctld: start from empty job state.
    slurmctld -c -f "$conf" || die "slurmctld failed to start; see $logdir/slurmctld.log"
    wait_pid slurmctld 20 || { tail -n 30 "$logdir/slurmctld.log" >&2 || true; die "slurmctld did not start"; }
    # Wait until the controller answers before starting slurmd, so slurmd
    # registers at once instead of retrying.
    wait_for 20 scontrol ping >/dev/null 2>&1 ||
        { tail -n 30 "$logdir/slurmctld.log" >&2 || true; die "slurmctld does not answer"; }
    pid_of slurmctld >/dev/null || { tail -n 30 "$logdir/slurmctld.log" >&2 || true; die "slurmctld died"; }

    slurmd -f "$conf" || die "slurmd failed to start; see $logdir/slurmd.log"
    wait_pid slurmd 20 || { tail -n 30 "$logdir/slurmd.log" >&2 || true; die "slurmd did not start"; }

    # The node is usable once sinfo reports it idle (mixed/allocated would mean
    # someone already submits; also fine).
    local state=""
    node_ready() {
        state=$(sinfo -h -n "$host" -o %T 2>/dev/null | head -n1)
        [[ $state == idle || $state == mixed || $state == allocated ]]
    }
    if ! wait_for "$START_TIMEOUT" node_ready; then
        log "node $host is '${state:-unknown}' after ${START_TIMEOUT}s"
        sinfo -N -l >&2 || true
        scontrol show node "$host" >&2 || true
        tail -n 30 "$logdir/slurmctld.log" "$logdir/slurmd.log" >&2 || true
        die "the node did not become idle"
    fi

    log "cluster up: node $host, $cpus CPUs, ${mem} MiB; pids: munged $(pid_of munged), slurmctld $(pid_of slurmctld), slurmd $(pid_of slurmd)"
    echo "export SLURM_CONF=$conf"
}

case $cmd in
    start)
        # Checked before the trap below is set: that trap would stop them.
        for name in "${daemons[@]}"; do
            if pid=$(pid_of "$name"); then
                die "$name already running for $dir (pid $pid); run: $0 stop $dir"
            fi
        done
        # If anything fails half way, do not leave daemons behind.  (Not
        # `if ! start_cluster`: set -e is switched off inside an if condition.)
        trap 'rc=$?; if ((rc != 0)); then stop_cluster || true; fi' EXIT
        start_cluster
        trap - EXIT
        ;;
    stop) stop_cluster ;;
    status) status_cluster ;;
    *) usage ;;
esac
