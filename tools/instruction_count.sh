#!/bin/sh
# Instructions executed (valgrind's callgrind, every process of the run, the forked workers
# included) per concrete scenario and per simulated vehicle-step of
#   BIN run SCENARIO --samples SAMPLES --seed 3
# for each build given. Unlike CPU time, which varies by up to 2x from run to run on the
# shared VM (docs/alks-scenarios.md), the count changes only with the work done, so it tells
# whether a change made the run cheaper. It is not the issue's measure (CPU time, `bench run`).
# Each instruction is counted once (tools/callgrind_run.sh).
# usage: tools/instruction_count.sh SCENARIO SAMPLES BIN [BIN ...]
set -eu
scenario=$1; samples=$2; shift 2
. "$(dirname "$0")/callgrind_run.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# tools/instruction_count.sh $scenario $samples: callgrind, all processes, run --samples $samples --seed 3"
for bin in "$@"; do
  callgrind_run "$work" "$bin" "$scenario" "$samples"
  total=$(callgrind_total "$work")
  # Road users x steps of every scenario that ran, from the traces.
  vehicle_steps=$(/usr/bin/python3 -c "
import h5py, sys
f = h5py.File(sys.argv[1])
n, users, instants, _ = f['states'].shape
print(n * users * (instants - 1), n)" "$work/out/traces.h5")
  echo "$($bin --version) $vehicle_steps" | awk -v total="$total" '{
    printf "%s: %.1f M instructions, %.2f M per scenario, %.0f per vehicle-step (%d scenarios, %d vehicle-steps)\n",
      $1, total / 1e6, total / 1e6 / $3, total / $2, $3, $2 }'
done
