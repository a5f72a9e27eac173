#!/bin/sh
# Paired CPU benchmark of two builds on one machine: runs `bench run SCENARIO` with OLD and NEW
# alternately PAIRS times and prints each run's CPU per scenario and per simulated vehicle-step,
# so that a change is judged against the same machine's drift (a shared VM's CPU time per run
# varies by up to 2x from run to run; docs/alks-scenarios.md).
# usage: tools/bench_pairs.sh OLD_BIN NEW_BIN SCENARIO PAIRS [SAMPLES]
set -eu
old=$1; new=$2; scenario=$3; pairs=$4; samples=${5:-4000}
echo "# tools/bench_pairs.sh: $scenario, $pairs pairs, --samples $samples"
echo "# old: $($old --version)  new: $($new --version)"
i=1
while [ "$i" -le "$pairs" ]; do
  for which in old new; do
    bin=$old; [ "$which" = new ] && bin=$new
    out=$($bin bench run "$scenario" --samples "$samples" --memory-samples 250 --mpi-samples 500)
    load=$(echo "$out" | sed -n 's/.*load average before: \([0-9.]*\).*/\1/p' | head -1)
    ms=$(echo "$out" | awk '$1 == "batch" && $2 == "250" && $3 != "," {print $NF; exit}')
    us=$(echo "$out" | awk '/CPU us per simulated vehicle-step/ {print $6; exit}')
    echo "pair $i $which: CPU $ms ms/scenario, $us us/vehicle-step (load before $load)"
  done
  i=$((i + 1))
done
