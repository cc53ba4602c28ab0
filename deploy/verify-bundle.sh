#!/usr/bin/env bash
# Verification of many submission bundles, one per array task: bundle I of the sorted
# `*.tar`/`*.tar.zst` files in BUNDLES, its index from the scheduler (Slurm's
# SLURM_ARRAY_TASK_ID from SLURM_ARRAY_TASK_MIN, or a Kubernetes Indexed Job's
# JOB_COMPLETION_INDEX). Each task re-enacts its bundle's episodes on the node's cores
# (--workers, default the CPUs Slurm gave it, else 2) and leaves the verification record beside
# the bundle, which `autobio leaderboard build BUNDLES --out SITE` then reads. Verification is
# embarrassingly parallel: bundles never share state, and a retried task simply verifies again.
#
#   deploy/verify-bundle.sh BUNDLES [--suites DIR]
#
# Exit 0 whether the bundle was accepted or refused (its record says which); non-zero only when
# the verifier could not run. AUTOBIO names the binary (default: autobio).
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: $0 BUNDLES [--suites DIR]" >&2
  exit 2
fi
bundles=$1
shift
if [ -n "${SLURM_ARRAY_TASK_ID:-}" ]; then
  index=$((SLURM_ARRAY_TASK_ID - ${SLURM_ARRAY_TASK_MIN:-0}))
elif [ -n "${JOB_COMPLETION_INDEX:-}" ]; then
  index=$JOB_COMPLETION_INDEX
else
  echo "$0: no index: run under a Slurm job array or a Kubernetes Indexed Job" >&2
  exit 2
fi
mapfile -t files < <(find "$bundles" -maxdepth 1 -type f \( -name '*.tar' -o -name '*.tar.zst' \) | LC_ALL=C sort)
if [ "$index" -ge "${#files[@]}" ]; then
  echo "$0: index $index, but $bundles holds ${#files[@]} bundles" >&2
  exit 2
fi
set +e
"${AUTOBIO:-autobio}" leaderboard verify "${files[$index]}" --workers "${SLURM_CPUS_PER_TASK:-2}" "$@"
code=$?
set -e
# 1 is a refused bundle (recorded), not a failed task.
[ "$code" -le 1 ] || exit "$code"
