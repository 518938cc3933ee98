#!/usr/bin/env bash
# Converts a batch on a Slurm cluster: a job array of TASKS tombuild shards, then a merge job
# that waits for all of them.
#   scripts/slurm/submit.sh TASKS OUTDIR INPUT... [tombuild options]
# e.g. scripts/slurm/submit.sh 16 /shared/out /shared/assets --report-json /shared/reports
# OUTDIR, the inputs and the reports must be on a file system every node sees. TOMBUILD names
# the tombuild to run (default: tombuild on the nodes' PATH). Extra sbatch options go in
# SBATCH_ARGS (e.g. SBATCH_ARGS="--partition=cpu --time=2:00:00"). Prints the two job ids.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 TASKS OUTDIR INPUT... [tombuild options]" >&2
  exit 2
fi
tasks="$1"; outdir="$2"; shift 2
here="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$outdir"
logs="$outdir/slurm-logs"; mkdir -p "$logs"
# shellcheck disable=SC2086
array=$(sbatch --parsable ${SBATCH_ARGS:-} --array="0-$((tasks - 1))" --output="$logs/convert-%A_%a.out" \
        --export=ALL "$here/convert.sbatch" "$outdir" "$@")
array="${array%%;*}"
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_ARGS:-} --dependency="afterany:$array" --output="$logs/merge-%j.out" \
        --export=ALL "$here/merge.sbatch" "$outdir")
merge="${merge%%;*}"
echo "$array $merge"
