#!/usr/bin/env bash
# Drives a sharded adaptive precompute level by level (issue 12): for L = 0, 1, …
# submits an N-task array of level L (precompute.sbatch with LEVEL=L) and its merge
# with --dependency=afterok, waits for the merge, and stops when the merge wrote the
# final PCA file (a level that leaves no interval to split). Level L's keys depend on
# the images of the levels before, so the levels run one after another; the keys of a
# level run side by side. The result equals the unsharded `illume precompute` bit for
# bit. Run it where sbatch works (a login node; it only submits and waits).
#
# Usage: submit_precompute_adaptive.sh N OUT_DIR SCENE [precompute flags…]
# Needs ILLUME (the binary's path) in the environment; POLL_S (default 2) sets how often
# the queue is read. Writes OUT_DIR/level$L.illumepc per level and, at the end,
# OUT_DIR/merged.illumepc (the final file); prints "levels: L" and the merged path.
set -euo pipefail
n=$1 out=$2 scene=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
: "${ILLUME:?path of the illume binary}"
mkdir -p "$out"
out=$(cd "$out" && pwd)
poll=${POLL_S:-2}

# Waits until the jobs IDS (comma-separated) have left the queue's active states;
# fails (and cancels them) when any failed or was cancelled. `sbatch --wait` would
# return 0 for a job cancelled because its dependency failed: read the states instead.
wait_jobs() {
    local ids=$1 states
    while true; do
        states=$(squeue -h -t all -j "$ids" -o '%i %T' 2>/dev/null || true)
        if grep -Eq 'FAILED|CANCELLED|TIMEOUT|OUT_OF_MEMORY|NODE_FAIL|PREEMPTED|BOOT_FAIL|DEADLINE' <<<"$states"; then
            echo "$states" >&2
            scancel "${ids//,/ }" 2>/dev/null || true
            return 1
        fi
        if ! grep -Eq 'PENDING|RUNNING|CONFIGURING|COMPLETING|SUSPENDED|REQUEUED|RESIZING|STAGE_OUT' <<<"$states"; then
            return 0
        fi
        sleep "$poll"
    done
}

for ((level = 0; level < 64; level++)); do
    merged="$out/level$level.illumepc"
    rm -f "$merged" "$out"/level"$level".part*.illumepc
    array=$(sbatch --parsable --array=0-$((n - 1)) --chdir="$out" \
        --export=ALL,ILLUME="$ILLUME",SCENE="$scene",OUT="$out",LEVEL="$level",ARGS="$*" \
        "$here/precompute.sbatch")
    merge=$(sbatch --parsable --dependency=afterok:"$array" --chdir="$out" \
        --export=ALL,MODE=merge,ILLUME="$ILLUME",OUT="$out",N="$n",LEVEL="$level" \
        "$here/precompute.sbatch")
    echo "level $level: array $array, merge $merge" >&2
    if ! wait_jobs "$array,$merge" || [[ ! -s "$merged" ]]; then
        echo "level $level failed: see $out/illume-precompute-${array}_*.out and ${merge}" >&2
        exit 1
    fi
    info=$("$ILLUME" precompute info "$merged")
    if grep -Eq '^kind +pca' <<<"$info"; then
        cp "$merged" "$out/merged.illumepc.tmp"
        mv "$out/merged.illumepc.tmp" "$out/merged.illumepc"
        echo "levels: $level"
        echo "$out/merged.illumepc"
        exit 0
    fi
done
echo "no final file after 64 levels" >&2
exit 1
