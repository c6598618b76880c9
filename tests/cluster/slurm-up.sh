#!/usr/bin/env bash
# Start a throw-away one-node SLURM cluster on this machine (root on Debian/Ubuntu with apt).
#
#   tests/cluster/slurm-up.sh [STATE_DIR]      # default: $POSEFIX_SLURM_DIR or /tmp/posefix-slurm
#   export SLURM_CONF=STATE_DIR/slurm.conf     # then sbatch/squeue/snakemake talk to it
#   tests/cluster/slurm-down.sh [STATE_DIR]    # stops what this script started
#
# Installs slurm-wlm and munge with apt when missing, creates the munge key and /run/munge, writes
# STATE_DIR/slurm.conf (controller and node on 127.0.0.1, node line from `slurmd -C`, no accounting
# daemon), starts munged (unless one already answers), slurmctld and slurmd with that configuration,
# links /etc/slurm/slurm.conf to it (the jobs' srun reads only that one), and waits until the node
# is idle. Refuses (exit 3) when /etc/slurm/slurm.conf is another configuration.
# Idempotent: daemons already running from STATE_DIR are kept.
# Ports: $POSEFIX_SLURMCTLD_PORT (6817) and $POSEFIX_SLURMD_PORT (6818).
# POSEFIX_SLURM_ETC_LINK=0 leaves /etc/slurm/slurm.conf alone, for a second cluster beside the first
# (other ports and STATE_DIR): its daemons run and take jobs, but a job's own `srun` reads /etc's.
# Exit status: 0 ready, 3 cannot run here (not root, no apt-get, install failed), 1 anything else.
set -euo pipefail

STATE=${1:-${POSEFIX_SLURM_DIR:-/tmp/posefix-slurm}}
CTLD_PORT=${POSEFIX_SLURMCTLD_PORT:-6817}
SLURMD_PORT=${POSEFIX_SLURMD_PORT:-6818}
ETC_LINK=${POSEFIX_SLURM_ETC_LINK:-1}
READY_TIMEOUT=${POSEFIX_SLURM_READY_TIMEOUT:-60}

say() { echo "slurm-up: $*"; }
die() { echo "slurm-up: error: $*" >&2; exit 1; }
cannot() { echo "slurm-up: cannot run here: $*" >&2; exit 3; }
alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }  # pid file names a live process

[ "$(id -u)" = 0 ] || cannot "must run as root (installs packages, starts munged/slurmctld/slurmd)"

# 1. Packages.
missing=()
for cmd in slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
    command -v "$cmd" >/dev/null 2>&1 || { missing+=(slurm-wlm); break; }
done
for cmd in munged munge unmunge; do
    command -v "$cmd" >/dev/null 2>&1 || { missing+=(munge); break; }
done
if [ ${#missing[@]} -gt 0 ]; then
    command -v apt-get >/dev/null 2>&1 || cannot "no apt-get to install ${missing[*]}"
    say "installing ${missing[*]} with apt-get (a minute or two)"
    export DEBIAN_FRONTEND=noninteractive
    { apt-get update -qq && apt-get install -y -qq --no-install-recommends "${missing[@]}"; } \
        >"/tmp/posefix-slurm-apt.$$.log" 2>&1 \
        || { tail -n 20 "/tmp/posefix-slurm-apt.$$.log" >&2; cannot "apt-get install ${missing[*]} failed"; }
    rm -f "/tmp/posefix-slurm-apt.$$.log"
    for cmd in slurmctld slurmd sbatch munged; do
        command -v "$cmd" >/dev/null 2>&1 || cannot "$cmd still missing after installing ${missing[*]}"
    done
fi
say "slurm $(slurmctld -V 2>/dev/null | awk '{print $2}'), munge $(munged -V 2>/dev/null | awk '{print $1}' | sed 's/^munge-//')"

mkdir -p "$STATE"/{state,spool,log}
STATE=$(cd "$STATE" && pwd)
CONF=$STATE/slurm.conf
export SLURM_CONF=$CONF

ETC_CONF=/etc/slurm/slurm.conf   # see step 3; checked before anything starts
if [ "$ETC_LINK" != 0 ] && [ -e "$ETC_CONF" ] && ! { [ -L "$ETC_CONF" ] && [ "$(readlink "$ETC_CONF")" = "$CONF" ]; }; then
    cannot "$ETC_CONF exists (another SLURM configuration on this machine); not replacing it"
fi

# 2. munge: key, runtime directories, daemon (one that already answers is reused and left running).
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    if alive "$STATE/munged.pid"; then
        say "munged already running (pid $(cat "$STATE/munged.pid"), started by slurm-up.sh)"
    else
        say "munged already answers on /run/munge: using it (slurm-down.sh leaves it running)"
    fi
else
    id munge >/dev/null 2>&1 || die "no user 'munge' (the munge package creates it)"
    install -d -m 0700 -o munge -g munge /etc/munge
    if [ ! -s /etc/munge/munge.key ]; then
        say "creating /etc/munge/munge.key"
        if command -v mungekey >/dev/null 2>&1; then
            mungekey --create --keyfile=/etc/munge/munge.key --force
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
    fi
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
    install -d -m 0755 -o munge -g munge /run/munge   # nothing creates it without systemd
    install -d -m 0700 -o munge -g munge /var/lib/munge
    install -d -m 0700 -o munge -g munge /var/log/munge
    if [ -S /run/munge/munge.socket.2 ] && ! alive /run/munge/munged.pid; then
        rm -f /run/munge/munge.socket.2 /run/munge/munge.socket.2.lock  # left by a killed munged
    fi
    say "starting munged"
    if command -v runuser >/dev/null 2>&1; then
        runuser -u munge -- munged
    else
        su -s /bin/sh munge -c munged
    fi
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.1
    done
    munge -n | unmunge >/dev/null || die "munged does not answer (see /var/log/munge/munged.log)"
    cp /run/munge/munged.pid "$STATE/munged.pid"   # ours: slurm-down.sh stops it
fi

# 3. slurm.conf (kept as it is while its daemons run).
if alive "$STATE/slurmctld.pid" || alive "$STATE/slurmd.pid"; then
    say "daemons from $STATE are running: keeping $CONF"
else
    NODE=$(slurmd -C | head -n 1)   # NodeName=<host> CPUs=... RealMemory=...
    case $NODE in NodeName=*) ;; *) die "unexpected 'slurmd -C' output: $NODE";; esac
    HOST=${NODE%% *}; HOST=${HOST#NodeName=}
    say "node: $NODE"
    cat >"$CONF" <<CONF
# One-node test cluster written by tests/cluster/slurm-up.sh; no slurmdbd (no accounting).
ClusterName=posefix
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$STATE/state
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups in a container: track processes through /proc, no task binding.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1000
# Finished jobs stay visible to squeue/scontrol for 5 minutes (status checks without sacct).
MinJobAge=300
ReturnToService=2
InactiveLimit=0
KillWait=5
Waittime=0
SlurmctldTimeout=30
SlurmdTimeout=60
$NODE NodeAddr=127.0.0.1 NodeHostname=$HOST State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
fi

# The jobs' own `srun` (snakemake-executor-plugin-slurm-jobstep) runs with every SLURM_* variable
# but the job's id removed, SLURM_CONF included: it finds the configuration only at the default
# /etc/slurm/slurm.conf, so that becomes a link to ours (removed again by slurm-down.sh).
if [ "$ETC_LINK" = 0 ]; then
    say "leaving $ETC_CONF alone (POSEFIX_SLURM_ETC_LINK=0)"
elif [ -L "$ETC_CONF" ] && [ "$(readlink "$ETC_CONF")" = "$CONF" ]; then
    :
elif [ -L "$ETC_CONF" ] && [ ! -e "$ETC_CONF" ]; then
    say "replacing the dangling link $ETC_CONF -> $(readlink "$ETC_CONF")"
    ln -sfn "$CONF" "$ETC_CONF"
    touch "$STATE/etc-link"
elif [ -e "$ETC_CONF" ] || [ -L "$ETC_CONF" ]; then
    cannot "$ETC_CONF exists (another SLURM configuration on this machine); not replacing it"
else
    say "linking $ETC_CONF -> $CONF"
    mkdir -p /etc/slurm
    ln -s "$CONF" "$ETC_CONF"
    touch "$STATE/etc-link"
fi

# 4. Daemons (they fork and write their pid files into STATE_DIR).
if alive "$STATE/slurmctld.pid"; then
    say "slurmctld already running (pid $(cat "$STATE/slurmctld.pid"))"
else
    say "starting slurmctld (log: $STATE/log/slurmctld.log)"
    rm -f "$STATE/slurmctld.pid"
    slurmctld -f "$CONF" -c || die "slurmctld did not start: $(tail -n 5 "$STATE/log/slurmctld.log" 2>/dev/null)"
fi
if alive "$STATE/slurmd.pid"; then
    say "slurmd already running (pid $(cat "$STATE/slurmd.pid"))"
else
    say "starting slurmd (log: $STATE/log/slurmd.log)"
    rm -f "$STATE/slurmd.pid"
    slurmd -f "$CONF" || die "slurmd did not start: $(tail -n 5 "$STATE/log/slurmd.log" 2>/dev/null)"
fi

# 5. Wait for the node to be idle.
state=""
for _ in $(seq $((READY_TIMEOUT * 2))); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -n 1 || true)
    case $state in
        idle|mixed|allocated) break;;
        down*|drain*) scontrol update nodename="$(sinfo -h -N -o '%N' | head -n 1)" state=resume 2>/dev/null || true;;
    esac
    sleep 0.5
done
case $state in
    idle|mixed|allocated) ;;
    *) echo "slurm-up: node state '${state:-none}' after ${READY_TIMEOUT}s; last log lines:" >&2
       tail -n 8 "$STATE/log/slurmctld.log" "$STATE/log/slurmd.log" >&2 || true
       exit 1;;
esac
sinfo -N -o '%N %P %T %c %m' | sed 's/^/slurm-up:   /'
say "ready: export SLURM_CONF=$CONF"
