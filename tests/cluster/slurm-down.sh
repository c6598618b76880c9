#!/usr/bin/env bash
# Stop the one-node SLURM cluster of tests/cluster/slurm-up.sh: cancels its jobs, then stops slurmd,
# slurmctld and (only when slurm-up.sh started it) munged, by the pid files in STATE_DIR, and removes
# the /etc/slurm/slurm.conf link slurm-up.sh made.
# Succeeds when some or all of them are not running; safe to run twice.
#
#   tests/cluster/slurm-down.sh [STATE_DIR]    # default: $POSEFIX_SLURM_DIR or /tmp/posefix-slurm
set -uo pipefail

STATE=${1:-${POSEFIX_SLURM_DIR:-/tmp/posefix-slurm}}
say() { echo "slurm-down: $*"; }

if [ ! -d "$STATE" ]; then
    say "no state folder $STATE: nothing to stop"
    exit 0
fi
STATE=$(cd "$STATE" && pwd)
export SLURM_CONF=$STATE/slurm.conf

pid_of() { [ -s "$1" ] && cat "$1"; }
alive() { local p; p=$(pid_of "$1") && kill -0 "$p" 2>/dev/null; }

stop() {  # stop NAME PIDFILE: TERM, wait up to 15 s, then KILL
    local name=$1 file=$2 pid
    if ! alive "$file"; then
        say "$name not running"
        rm -f "$file"
        return 0
    fi
    pid=$(pid_of "$file")
    say "stopping $name (pid $pid)"
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 150); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    if kill -0 "$pid" 2>/dev/null; then
        say "$name (pid $pid) ignored TERM: killing it"
        kill -KILL "$pid" 2>/dev/null || true
        sleep 0.2
    fi
    rm -f "$file"
}

# Jobs first, while slurmctld and slurmd can still clean them up.
if alive "$STATE/slurmctld.pid" && [ -f "$SLURM_CONF" ]; then
    jobs=$(squeue -h -o '%i' 2>/dev/null | tr '\n' ' ')
    if [ -n "${jobs// /}" ]; then
        say "cancelling jobs: $jobs"
        # shellcheck disable=SC2086
        scancel $jobs 2>/dev/null || true
        for _ in $(seq 100); do
            [ -z "$(squeue -h -t running,completing,pending -o '%i' 2>/dev/null)" ] && break
            sleep 0.1
        done
    fi
    if alive "$STATE/slurmd.pid"; then   # job processes slurmd still knows about
        pids=$(scontrol listpids 2>/dev/null | awk 'NR > 1 && $1 ~ /^[0-9]+$/ {print $1}' | tr '\n' ' ')
        if [ -n "${pids// /}" ]; then
            say "killing leftover job processes: $pids"
            # shellcheck disable=SC2086
            kill -KILL $pids 2>/dev/null || true
        fi
    fi
fi

stop slurmd "$STATE/slurmd.pid"
stop slurmctld "$STATE/slurmctld.pid"
if [ -f "$STATE/munged.pid" ]; then
    stop munged "$STATE/munged.pid"
    rm -f /run/munge/munged.pid
else
    say "munged: not started by slurm-up.sh (or already stopped): leaving it alone"
fi
if [ -f "$STATE/etc-link" ]; then
    if [ -L /etc/slurm/slurm.conf ] && [ "$(readlink /etc/slurm/slurm.conf)" = "$STATE/slurm.conf" ]; then
        say "removing the link /etc/slurm/slurm.conf"
        rm -f /etc/slurm/slurm.conf
    fi
    rm -f "$STATE/etc-link"
fi
say "stopped (logs and state kept in $STATE)"
exit 0
