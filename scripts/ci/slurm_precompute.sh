#!/usr/bin/env bash
# CI (issue 12): the sharded precompute on a real one-node Slurm cluster. Installs
# Debian's slurm-wlm and munge, writes a one-node slurm.conf (this machine, 2 CPUs),
# starts munged, slurmctld and slurmd, submits a 3-task array for a tiny
# builtin:sun-room day plus the dependent merge job, waits, checks every job COMPLETED
# with exit 0 and that the merged file equals the unsharded one bit for bit, then stops
# the daemons. Needs root (CI is). Never skipped: any failure fails CI.
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
work=$(mktemp -d /tmp/illume-slurm.XXXXXX)
chmod 755 "$work"
log() { echo "slurm_precompute: $*"; }

export DEBIAN_FRONTEND=noninteractive
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    log "installing slurm-wlm and munge"
    apt-get install -y -q --no-install-recommends slurm-wlm munge >/dev/null 2>&1 ||
        { apt-get update -q >/dev/null && apt-get install -y -q --no-install-recommends slurm-wlm munge >/dev/null; }
fi

cargo build -q -p illume
target=${CARGO_TARGET_DIR:-$repo/target}
illume=$target/debug/illume
[[ -x $illume ]] || { log "no binary at $illume"; exit 1; }

host=$(hostname -s)
conf_dir=/etc/slurm
mkdir -p "$conf_dir" /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
cat >"$conf_dir/slurm.conf" <<CONF
ClusterName=illume-ci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MinJobAge=3600
DependencyParameters=kill_invalid_depend
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

munged_pid=""
stop() {
    log "stopping the daemons"
    scontrol shutdown >/dev/null 2>&1 || true
    for f in /run/slurmctld.pid /run/slurmd.pid; do
        if [[ -s $f ]]; then
            pid=$(cat "$f")
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
            kill "$pid" 2>/dev/null || true
        fi
    done
    if [[ -s /run/munge/munged.pid ]]; then
        kill "$(cat /run/munge/munged.pid)" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap stop EXIT

log "starting munged, slurmctld, slurmd"
mkdir -p /run/munge
chown munge:munge /run/munge
chmod 755 /run/munge
runuser -u munge -- /usr/sbin/munged
slurmctld
slurmd
for _ in $(seq 100); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
    [[ $state == idle ]] && break
    sleep 0.2
done
[[ $state == idle ]] || { log "node not idle: '$state'"; tail -20 /var/log/slurm/*.log; exit 1; }

# 3:00–15:00 every 2 h: dark keys before sunrise and sunlit ones.
args="--schedule uniform --from 3 --to 15 --step-min 120 --spp 4 --components 4 --width 24 --height 16"
log "submitting the 3-task array and the merge"
read -r array merge < <(ILLUME=$illume scripts/slurm/submit_precompute.sh 3 "$work" builtin:sun-room $args)
# sbatch --wait returns 0 for a job cancelled for a failed dependency: read the states.
for _ in $(seq 600); do
    states=$(squeue -h -t all -j "$array,$merge" -O JobArrayID,State,exit_code 2>/dev/null || true)
    if [[ -n $states ]] && ! grep -Eq 'PENDING|RUNNING|CONFIGURING|COMPLETING' <<<"$states"; then
        break
    fi
    sleep 0.5
done
echo "$states"
count=$(grep -c . <<<"$states")
done_ok=$(grep -Ec 'COMPLETED +0(:0)? *$' <<<"$states" || true)
if [[ $count -ne 4 || $done_ok -ne 4 ]]; then
    log "expected 4 jobs COMPLETED with exit code 0 (3 shards + merge)"
    cat "$work"/*.out 2>/dev/null || true
    exit 1
fi
log "rendering the same day unsharded"
# shellcheck disable=SC2086
"$illume" precompute builtin:sun-room $args --output "$work/whole.illumepc"
cmp "$work/whole.illumepc" "$work/merged.illumepc"
log "ok: the merged file equals the unsharded one bit for bit"
