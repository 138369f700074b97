#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, for the test suite.
#   bash scripts/slurm/local-cluster.sh start STATE_DIR   # installs slurm-wlm + munge if missing
#   bash scripts/slurm/local-cluster.sh stop  STATE_DIR
# Everything lives under STATE_DIR: its own munged (key, socket), slurm.conf, spool, state,
# logs and pid files; nothing in /etc or /run is used. `start` is idempotent (quick when up)
# and writes STATE_DIR/env.sh (`export SLURM_CONF=...`): source it before sbatch/squeue/scontrol.
# Ports: 6817/6818, or SLURM_LOCAL_CTLD_PORT / SLURM_LOCAL_SLURMD_PORT (two clusters at once).
# Sourcing this file only defines the functions (and leaves the shell's options alone).

lc_say() { echo "== local-cluster: $*" >&2; }
lc_fail() { echo "local-cluster: $*" >&2; return 1; }

# Alive = the pid file names a live process of that name: a pid file left from an earlier
# boot may name a reused pid, and a killed daemon stays a zombie until init reaps it.
lc_alive() { # NAME PIDFILE
    local pid
    pid=$(cat "$2" 2>/dev/null) || return 1
    [[ "$(ps -o comm=,stat= -p "$pid" 2>/dev/null)" =~ ^$1\ +[^Z] ]]
}

lc_install() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
        && command -v sbatch >/dev/null && command -v munged >/dev/null; then return 0; fi
    lc_say "installing Debian's slurm-wlm and munge"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    # The packages' postinst scripts try to start the system-wide daemons (through
    # invoke-rc.d); in a container without an init that is refused or fails harmlessly, and
    # they are not used anyway: this script runs its own under STATE_DIR.
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq slurm-wlm munge >/dev/null
}

lc_munge() { # S
    local m="$1/munge"
    # munged refuses a socket/key directory that others can write to; others need x on it
    # to reach the socket (a job or client run as another user).
    mkdir -p "$m" && chmod 755 "$m"
    # A sun_path holds 107 bytes: a deep STATE_DIR cannot hold the socket.
    [ ${#m} -le 90 ] || lc_fail "STATE_DIR too long for munge's socket path: $m"
    if [ ! -s "$m/munge.key" ]; then
        (umask 077; dd if=/dev/urandom of="$m/munge.key" bs=1024 count=1 status=none)
    fi
    lc_alive munged "$m/munged.pid" && return 0
    # --force: munged otherwise refuses to run as root.
    munged --force --socket="$m/munge.socket.2" --key-file="$m/munge.key" \
        --pid-file="$m/munged.pid" --log-file="$m/munged.log" --seed-file="$m/munged.seed" 9>&-
}

lc_conf() { # S -> slurm.conf on stdout
    local s="$1" host cpus mem_mb
    host=$(hostname -s)
    cpus=$(nproc)
    mem_mb=$(( $(awk '/^MemTotal:/ {print $2}' /proc/meminfo) / 1024 ))
    cat <<EOF
# Written by scripts/slurm/local-cluster.sh: a one-node cluster, all state under $s.
ClusterName=local
# The node and the controller are reached on 127.0.0.1: the host name need not resolve.
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=${SLURM_LOCAL_CTLD_PORT:-6817}
SlurmdPort=${SLURM_LOCAL_SLURMD_PORT:-6818}
AuthType=auth/munge
CredType=cred/munge
# Our own munged's socket, not /run/munge (clients read this too, through SLURM_CONF).
AuthInfo=socket=$s/munge/munge.socket.2
# Everything runs as root: no slurm user to create, and slurmd may start jobs as anyone.
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$s/ctld
SlurmdSpoolDir=$s/slurmd
SlurmctldPidFile=$s/run/slurmctld.pid
SlurmdPidFile=$s/run/slurmd.pid
SlurmctldLogFile=$s/log/slurmctld.log
SlurmdLogFile=$s/log/slurmd.log
# No slurmdbd, no accounting, no cgroups (a container usually cannot create cgroups):
# processes are tracked through /proc, and tasks are not bound to CPUs.
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
# Schedule as soon as a job is submitted or ends (the default waits up to 3 s between
# passes, which delays every array task and dependent job).
SchedulerParameters=batch_sched_delay=0
# A job whose dependency can never be met (afterok on a failed job) is cancelled, instead of
# pending forever with Reason=DependencyNeverSatisfied (a test would hang on it).
DependencyParameters=kill_invalid_depend
# Jobs share the node one CPU each (array tasks run side by side); memory is not
# a consumable, so a job never waits for memory.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# Trust the node line below even if slurmd sees other hardware (no DRAIN/INVAL).
SlurmdParameters=config_overrides
# A node DOWN for not answering (e.g. after stop/start) comes back by itself.
ReturnToService=2
# Finished jobs stay in slurmctld's memory for an hour: without slurmdbd, that is
# how \`scontrol show job\` and \`squeue --states=all\` still see their state and exit code.
MinJobAge=3600
# No mail on this machine (the default /bin/mail does not exist).
MailProg=/bin/true
# RealMemory leaves a margin below MemTotal for the OS and the daemons.
NodeName=$host NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus RealMemory=$(( mem_mb > 2048 ? mem_mb - 1024 : mem_mb / 2 )) State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
}

lc_start() { # STATE_DIR
    local s
    s=$(mkdir -p "$1" && cd "$1" && pwd)
    # slurm.conf cannot quote a path.
    [[ "$s" != *[[:space:]]* ]] || lc_fail "STATE_DIR must not contain spaces: $s"
    # Tests running in parallel may all call start: one at a time. The lock ends with this
    # process; the daemons must not inherit it (9>&- below).
    exec 9>"$s/.lock" && flock 9
    export SLURM_CONF="$s/slurm.conf"
    lc_install
    mkdir -p "$s/ctld" "$s/slurmd" "$s/run" "$s/log"
    lc_munge "$s"
    lc_conf "$s" >"$s/slurm.conf.new"
    if cmp -s "$s/slurm.conf.new" "$s/slurm.conf"; then
        rm "$s/slurm.conf.new"
    else # a new or changed configuration: daemons started with the old one restart
        mv "$s/slurm.conf.new" "$s/slurm.conf"
        lc_stop_slurm "$s"
    fi
    lc_alive slurmctld "$s/run/slurmctld.pid" || lc_daemon slurmctld "$s" -f "$SLURM_CONF"
    lc_alive slurmd "$s/run/slurmd.pid" || lc_daemon slurmd "$s" -f "$SLURM_CONF" -N "$(hostname -s)"
    echo "export SLURM_CONF=$SLURM_CONF" >"$s/env.sh"
    # Ready = our slurmd answers and the controller has the node up. After a restart the
    # controller shows the node's saved state (idle) at once, hence the slurmd check too.
    local i state=""
    for i in $(seq 120); do # 60 s
        # A daemon writes its pid file a moment after it returns; one gone after 5 s failed.
        if [ "$i" -gt 10 ] && ! { lc_alive slurmctld "$s/run/slurmctld.pid" \
            && lc_alive slurmd "$s/run/slurmd.pid"; }; then break; fi
        state=$(sinfo -h -N -o %t 2>/dev/null | head -1)
        case "$state" in idle | mix | alloc)
            scontrol show slurmd >/dev/null 2>&1 && { echo "export SLURM_CONF=$SLURM_CONF"; return 0; } ;;
        esac
        sleep 0.5
    done
    tail -n 20 "$s/log/slurmctld.log" "$s/log/slurmd.log" >&2 || true
    lc_fail "node not up (state: ${state:-no answer}); logs in $s/log"
}

lc_daemon() { # NAME S ARGS...: start a Slurm daemon (it forks into the background itself)
    local name="$1" s="$2" port
    shift 2
    port=$(sed -n "s/^$([ "$name" = slurmd ] && echo SlurmdPort || echo SlurmctldPort)=//p" "$s/slurm.conf")
    # A port held by another cluster (another STATE_DIR) would make our daemon exit, and the
    # clients would then talk to that other cluster.
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
        lc_fail "port $port is taken (another cluster? set SLURM_LOCAL_CTLD_PORT/SLURM_LOCAL_SLURMD_PORT)"
    fi
    "$name" "$@" 9>&-
}

lc_kill() { # NAME PIDFILE: TERM, then wait up to 10 s
    local pid i
    lc_alive "$1" "$2" || return 0
    pid=$(cat "$2")
    kill "$pid"
    for i in $(seq 50); do
        lc_alive "$1" "$2" || return 0
        sleep 0.2
    done
    kill -9 "$pid" 2>/dev/null || true
}

lc_stop_slurm() { # S
    lc_kill slurmd "$1/run/slurmd.pid"
    lc_kill slurmctld "$1/run/slurmctld.pid"
}

lc_stop() { # STATE_DIR
    local s
    s=$(cd "$1" 2>/dev/null && pwd) || return 0
    exec 9>"$s/.lock" && flock 9
    export SLURM_CONF="$s/slurm.conf"
    # Running jobs would outlive slurmd (their slurmstepd is a separate process): cancel
    # every job of the cluster (its one partition), whoever submitted it.
    if lc_alive slurmctld "$s/run/slurmctld.pid"; then
        scancel --partition=local 2>/dev/null || true
    fi
    lc_stop_slurm "$s"
    lc_kill munged "$s/munge/munged.pid"
}

main() {
    [ $# -eq 2 ] || lc_fail "usage: $0 start|stop STATE_DIR"
    # slurmd must be root to start jobs as their submitter; so must the daemons' files be.
    [ "$(id -u)" -eq 0 ] || exec sudo -E bash "$0" "$@"
    case "$1" in
        start) lc_start "$2" ;;
        stop) lc_stop "$2" ;;
        *) lc_fail "usage: $0 start|stop STATE_DIR" ;;
    esac
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    set -euo pipefail
    main "$@"
fi
