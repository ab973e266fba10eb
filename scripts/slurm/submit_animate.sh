#!/usr/bin/env bash
# Submits a sharded `illume animate`: an N-task array, then the collect job after all
# succeed. Usage: submit_animate.sh N OUT_DIR SCENE [animate flags…]
# Prints "ARRAY_JOB COLLECT_JOB". Needs ILLUME (the binary's path) in the environment.
# The jobs' logs go to LOGS (default OUT_DIR.logs): `illume animate` refuses an output
# folder holding files it did not write.
set -euo pipefail
n=$1 out=$2 scene=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
out=$(cd "$out" && pwd)
logs=${LOGS:-$out.logs}
mkdir -p "$logs"
array=$(sbatch --parsable --array=0-$((n - 1)) --chdir="$logs" \
    --export=ALL,ILLUME="$ILLUME",SCENE="$scene",OUT="$out",ARGS="$*" "$here/animate.sbatch")
collect=$(sbatch --parsable --dependency=afterok:"$array" --chdir="$logs" \
    --export=ALL,MODE=collect,ILLUME="$ILLUME",SCENE="$scene",OUT="$out",N="$n",ARGS="$*" \
    "$here/animate.sbatch")
echo "$array $collect"
