#!/bin/bash
# A dicesim fit sharded by point (docs/scaling-out.md, "Sweeps and fits by point"): PASSES job arrays
# of SHARDS tasks, each pass after the last (afterok), then the merge. A pass tosses each shard's
# block of the first stage not yet counted in OUTDIR; a pass with nothing left says so and ends.
#   FIT_ARGS="SCENE --data COUNTS --param KEY=LO:HI ..." examples/slurm/fit-submit.sh SHARDS OUTDIR [PASSES]
# PASSES: default rounds + 1 + 4 (the widenings a fit may take) = 8 for the default 3 rounds.
# Prints the merge job's id; its result: OUTDIR/fit.json (`dicesim fit ARGS --json`, exactly) and
# the table in dicesim-fit-merge-JOBID.log. Set DICESIM to the binary's path if it is not on PATH.
set -euo pipefail
[ $# -ge 2 ] && [ -n "${FIT_ARGS:-}" ] || { echo "usage: FIT_ARGS='SCENE --data ... --param ...' $0 SHARDS OUTDIR [PASSES]" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
shards=$1 passes=${3:-8}
export FIT_ARGS OUTDIR=$2
mkdir -p "$OUTDIR"
dep=()
for ((p = 1; p <= passes; p++)); do
  job=$(sbatch --parsable --array=0-$((shards - 1)) "${dep[@]}" --kill-on-invalid-dep=yes --export=ALL "$here/fit-pass.sbatch")
  dep=(--dependency=afterok:"$job")
done
sbatch --parsable "${dep[@]}" --kill-on-invalid-dep=yes --export=ALL "$here/fit-merge.sbatch"
