#!/usr/bin/env bash
# Submits a benchmark whose converged references render as an N-task array, then the
# benchmark itself after all succeed. Usage: submit_bench.sh N SCENARIO CACHE_DIR
# [bench flags…] (e.g. -o REPORT_DIR). Prints "ARRAY_JOB BENCH_JOB". Needs ILLUME.
set -euo pipefail
n=$1 scenario=$2 cache=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)
scenario=$(cd "$(dirname "$scenario")" && pwd)/$(basename "$scenario")
array=$(sbatch --parsable --array=0-$((n - 1)) --chdir="$cache" \
    --export=ALL,ILLUME="$ILLUME",SCENARIO="$scenario",CACHE="$cache" "$here/bench_refs.sbatch")
bench=$(sbatch --parsable --dependency=afterok:"$array" --chdir="$cache" \
    --export=ALL,MODE=bench,ILLUME="$ILLUME",SCENARIO="$scenario",CACHE="$cache",ARGS="$*" \
    "$here/bench_refs.sbatch")
echo "$array $bench"
