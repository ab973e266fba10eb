#!/usr/bin/env bash
# Submits a sharded precompute: an N-task array, then the merge after all succeed.
# Usage: submit_precompute.sh N OUT_DIR SCENE [precompute flags…]
# Prints "ARRAY_JOB MERGE_JOB". Needs ILLUME (the binary's path) in the environment.
set -euo pipefail
n=$1 out=$2 scene=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
array=$(sbatch --parsable --array=0-$((n - 1)) --chdir="$out" \
    --export=ALL,ILLUME="$ILLUME",SCENE="$scene",OUT="$out",ARGS="$*" "$here/precompute.sbatch")
merge=$(sbatch --parsable --dependency=afterok:"$array" --chdir="$out" \
    --export=ALL,MODE=merge,ILLUME="$ILLUME",OUT="$out",N="$n" "$here/precompute.sbatch")
echo "$array $merge"
