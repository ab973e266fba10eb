#!/usr/bin/env bash
# CI (issue 12): the sharded precompute on a real one-node Slurm cluster. Installs
# Debian's slurm-wlm and munge, writes a one-node slurm.conf (this machine, 2 CPUs),
# starts munged, slurmctld and slurmd, submits a 3-task array for a tiny
# builtin:sun-room day plus the dependent merge job, waits, checks every job COMPLETED
# with exit 0 and that the merged file equals the unsharded one bit for bit; then the
# same for the adaptive schedule level by level (scripts/slurm/submit_precompute_adaptive.sh),
# for `animate --shard` (array + collect) and for `bench --shard` (array of references +
# the benchmark); then stops the daemons. Needs root (CI is). Never skipped: any failure
# fails CI.
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

# .ci/run passes the binary its `cargo test` already built (ILLUME_BIN): building it
# again here under the dev profile cost CI about a minute and a half.
if [[ -n ${ILLUME_BIN:-} ]]; then
    illume=$ILLUME_BIN
else
    cargo build -q -p illume
    illume=${CARGO_TARGET_DIR:-$repo/target}/debug/illume
fi
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

# Waits for the jobs IDS (an array and its dependent job) and checks that all EXPECTED
# of them COMPLETED with exit code 0; prints the logs in DIR otherwise. sbatch --wait
# returns 0 for a job cancelled for a failed dependency: read the states.
wait_ok() {
    local ids=$1 expected=$2 dir=$3 states count done_ok
    for _ in $(seq 600); do
        states=$(squeue -h -t all -j "$ids" -O JobArrayID,State,exit_code 2>/dev/null || true)
        if [[ -n $states ]] && ! grep -Eq 'PENDING|RUNNING|CONFIGURING|COMPLETING' <<<"$states"; then
            break
        fi
        sleep 0.5
    done
    echo "$states"
    count=$(grep -c . <<<"$states")
    done_ok=$(grep -Ec 'COMPLETED +0(:0)? *$' <<<"$states" || true)
    if [[ $count -ne $expected || $done_ok -ne $expected ]]; then
        log "expected $expected jobs COMPLETED with exit code 0"
        cat "$dir"/*.out 2>/dev/null || true
        return 1
    fi
}

# 3:00–15:00 every 2 h: dark keys before sunrise and sunlit ones.
args="--schedule uniform --from 3 --to 15 --step-min 120 --spp 4 --components 4 --width 24 --height 16"
log "submitting the 3-task array and the merge"
read -r array merge < <(ILLUME=$illume scripts/slurm/submit_precompute.sh 3 "$work" builtin:sun-room $args)
wait_ok "$array,$merge" 4 "$work"
log "rendering the same day unsharded"
# shellcheck disable=SC2086
"$illume" precompute builtin:sun-room $args --output "$work/whole.illumepc"
cmp "$work/whole.illumepc" "$work/merged.illumepc"
log "ok: the merged file equals the unsharded one bit for bit"

# The adaptive schedule, level by level: 3 shards and a merge per level, in order
# (verify_midpoint splits this day into levels 0–2; Yee at exposure 64 needs ~32 spp).
aargs="--schedule adaptive --from 7 --to 19 --step-min 90 --spp 32 --components 3 --width 64 --height 48 --set precomputed.exposure=64 --set precomputed.verify_midpoint=true"
log "adaptive schedule level by level (driver script)"
# shellcheck disable=SC2086
driver=$(ILLUME=$illume POLL_S=0.5 scripts/slurm/submit_precompute_adaptive.sh 3 "$work/adaptive" \
    builtin:sun-room $aargs) || { cat "$work"/adaptive/*.out 2>/dev/null || true; exit 1; }
echo "$driver"
levels=$(sed -n 's/^levels: //p' <<<"$driver")
if [[ -z $levels || $levels -lt 1 ]]; then
    log "expected the adaptive day to take more than one level, got '$levels'"
    exit 1
fi
# shellcheck disable=SC2086
"$illume" precompute builtin:sun-room $aargs --output "$work/adaptive-whole.illumepc"
cmp "$work/adaptive-whole.illumepc" "$work/adaptive/merged.illumepc"
log "ok: levels 0–$levels in shards equal the unsharded adaptive file bit for bit"

# animate --shard: an array of frames, then the collect job.
margs="--animation move --technique reference --duration 0.5 --fps 10 --work-per-frame 2 --width 24 --height 16"
log "animate: 3-task array and the collect"
read -r array collect < <(ILLUME=$illume scripts/slurm/submit_animate.sh 3 "$work/frames" builtin:cornell-spot $margs)
wait_ok "$array,$collect" 4 "$work/frames.logs"
# shellcheck disable=SC2086
"$illume" animate builtin:cornell-spot $margs --output "$work/frames-whole" 2>/dev/null
for f in "$work"/frames-whole/frame_*.png; do
    cmp "$f" "$work/frames/$(basename "$f")"
done
log "ok: $(ls "$work"/frames-whole/frame_*.png | wc -l) collected frames equal the unsharded ones bit for bit"

# bench --shard: the converged references as an array, then the benchmark.
cat >"$work/tiny.toml" <<'TOML'
name = "tiny"
scene = "builtin:cornell-spot"
animation = "move_light"
width = 16
height = 12
times_s = [0.0, 0.5, 1.0, 1.5]
metrics = ["rmse"]

[reference]
spp = 4

[[technique]]
name = "reference"
work = 1
TOML
log "bench: references as a 3-task array, then the benchmark"
read -r array bench < <(ILLUME=$illume scripts/slurm/submit_bench.sh 3 "$work/tiny.toml" "$work/cache" -o "$work/report")
wait_ok "$array,$bench" 4 "$work/cache"
if ! grep -q '4 from the cache, 0 rendered' "$work"/cache/illume-bench-refs-"$bench"_*.out; then
    cat "$work"/cache/*.out
    log "the benchmark after the shards rendered references itself"
    exit 1
fi
log "ok: the benchmark found all 4 references the shards rendered"
