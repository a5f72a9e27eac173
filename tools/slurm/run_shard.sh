#!/bin/bash
# One shard of a vsd-sumo sweep per Slurm array task, without MPI:
#
#   sbatch --array=0-99 tools/slurm/run_shard.sh scenarios/acc_lk.yaml /scratch/sweep [run options...]
#   vsd-sumo merge /scratch/sweep          # after the array finished: one run folder
#
# Task K of an array of N tasks runs `vsd-sumo run --shard K/N` into
# <out>/shards/shard-K-of-N. N is the array's task count (SLURM_ARRAY_TASK_COUNT),
# so the array must be 0..N-1 (`--array=0-99`, optionally `%limit`). The same seed
# and options must be given to every task (this script passes the same command
# line); merge refuses shards of other sweeps, gaps and overlaps. A task that is
# re-submitted skips its shard if it already finished, so re-running the whole array
# after a failure only runs what is missing.
#SBATCH --job-name=vsd-sumo-shard
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --output=vsd-sumo-shard-%A_%a.log
set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: sbatch --array=0-<N-1> $0 SCENARIO.yaml OUT_DIR [vsd-sumo run options...]" >&2
  exit 2
fi
if [ -z "${SLURM_ARRAY_TASK_ID:-}" ] || [ -z "${SLURM_ARRAY_TASK_COUNT:-}" ]; then
  echo "$0: not a Slurm array task (SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT unset); submit with sbatch --array" >&2
  exit 2
fi
if [ "${SLURM_ARRAY_TASK_MIN:-0}" != 0 ] ||
   [ "${SLURM_ARRAY_TASK_MAX:-$((SLURM_ARRAY_TASK_COUNT - 1))}" != $((SLURM_ARRAY_TASK_COUNT - 1)) ]; then
  echo "$0: the array must be 0-<N-1> without steps (got ${SLURM_ARRAY_TASK_MIN:-?}-${SLURM_ARRAY_TASK_MAX:-?}" \
       "with ${SLURM_ARRAY_TASK_COUNT} tasks)" >&2
  exit 2
fi

scenario=$1
out=$2
shift 2
exec "${VSD_SUMO:-vsd-sumo}" run "$scenario" --out "$out" \
  --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}" "$@"
