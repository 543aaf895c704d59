#!/bin/bash
# A dicesim run as a Slurm job array of SHARDS shards and a merge step that waits for all of them.
#   examples/slurm/submit.sh SCENE TOSSES SHARDS OUTDIR [SEED]
#   examples/slurm/submit.sh scenes/paper/die1.toml 10000000 16 $PWD/parts
# Prints the merge job's id; its result: OUTDIR/run.json (as `dicesim toss --json` of all TOSSES)
# and the table in dicesim-merge-JOBID.log. Set DICESIM to the binary's path if it is not on PATH.
set -euo pipefail
[ $# -ge 4 ] || { echo "usage: $0 SCENE TOSSES SHARDS OUTDIR [SEED]" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
export SCENE=$1 TOSSES=$2 OUTDIR=$4 SEED=${5:-1}
shards=$3
array=$(sbatch --parsable --array=0-$((shards - 1)) --export=ALL "$here/shards.sbatch")
sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes --export=ALL "$here/merge.sbatch"
