#!/usr/bin/env bash
# One shard of an evaluation, for job arrays. The shard's index and count come from the
# scheduler: Slurm (SLURM_ARRAY_TASK_ID from SLURM_ARRAY_TASK_MIN, SLURM_ARRAY_TASK_COUNT) or a
# Kubernetes Indexed Job (JOB_COMPLETION_INDEX, and SHARDS set in the manifest).
#
#   deploy/run-shard.sh OUT_ROOT -- <autobio eval arguments, without --out, --shard, --resume>
#
# Writes OUT_ROOT/shard-I-of-N. Always passes --resume: a first attempt starts the run, a retried
# one (a preempted node, a pod restarted) continues it, never rerunning a finished episode and
# refusing if anything it was measured under changed. AUTOBIO names the binary (default: autobio).
set -euo pipefail
if [ $# -lt 2 ] || [ "$2" != "--" ]; then
  echo "usage: $0 OUT_ROOT -- <autobio eval arguments>" >&2
  exit 2
fi
out_root=$1
shift 2
if [ -n "${SLURM_ARRAY_TASK_ID:-}" ]; then
  index=$((SLURM_ARRAY_TASK_ID - ${SLURM_ARRAY_TASK_MIN:-0}))
  count=${SLURM_ARRAY_TASK_COUNT:?SLURM_ARRAY_TASK_COUNT is not set}
elif [ -n "${JOB_COMPLETION_INDEX:-}" ]; then
  index=$JOB_COMPLETION_INDEX
  count=${SHARDS:?set SHARDS to the number of completions of the Indexed Job}
else
  echo "$0: no shard index: run under a Slurm job array or a Kubernetes Indexed Job" >&2
  exit 2
fi
exec "${AUTOBIO:-autobio}" eval "$@" --shard "$index/$count" --out "$out_root/shard-$index-of-$count" --resume
