#!/usr/bin/env bash
# Submits an evaluation as a job array of SHARDS shards, and a merge job that runs once all of
# them succeeded.
#
#   deploy/slurm/submit.sh SHARDS OUT_ROOT <autobio eval arguments>
#   deploy/slurm/submit.sh 8 /shared/runs/pi0 --model ws://gpu01:8000 \
#       --protocol protocols/thermal_cycler/close_lid.toml --episodes 100 --seed 0 --runs 3
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SHARDS OUT_ROOT <autobio eval arguments>" >&2
  exit 2
fi
shards=$1
out_root=$2
shift 2
mkdir -p "$out_root"
array=$(OUT_ROOT=$out_root EVAL_ARGS="$*" sbatch --parsable --export=ALL \
  --array=0-$((shards - 1)) deploy/slurm/eval.sbatch)
sbatch --parsable --job-name=autobio-merge --dependency=afterok:"${array%%;*}" \
  --output="$out_root/merge-%j.log" --wrap "deploy/merge.sh '$out_root' $shards"
echo "array job $array; results in $out_root/merged once every shard succeeded"
