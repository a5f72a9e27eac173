#!/bin/bash
# One small sweep of each of run, export, train, search and experiment, made by the vsd-sumo
# binary $1 in folder $2: the before/after check of a refactor that must not change outputs
# (issue 28 item 6). Build the old and the new binary, run this with each, then
#   /usr/bin/python3 tools/compare_outputs.py BEFORE AFTER
# SKIP_EXPERIMENT=1 leaves out the experiment (its --quick run takes ~5 min on 2 cores).
set -euo pipefail
BIN=$(realpath "$1"); OUT=$2
SRC=$(cd "$(dirname "$0")/.." && pwd)
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
mkdir -p "$OUT"
cd "$OUT"
"$BIN" run "$SRC/scenarios/acc_lk.yaml" --samples 300 --seed 5 --out run_acc_lk -q
"$BIN" run "$SRC/scenarios/alks/cut_in.yaml" --samples 200 --seed 5 --out run_cut_in -q
"$BIN" export --opendrive "$SRC/sumo_nets/opendrive_curve/curve.xodr" --routes "$SRC/sumo_nets/opendrive_curve/curve.rou.xml" \
  --out export/curve.h5 --egos vtype:truck --closed-loop --controller-param time_gap=3 -q
"$BIN" train --data run_acc_lk --decoder kinematic --decoder-option accel_weight=10 --decoder-option calibrate=1 \
  --frame lane --steps 40 --threads 1 --out train/k.pt -q
"$BIN" train --data run_acc_lk --steps 40 --threads 1 --out train/o.pt -q
"$BIN" search "$SRC/scenarios/acc_lk.yaml" --criterion "d_min < 2" --budget 260 --initial 200 --pool 600 --seed 4 \
  --out search_et -q
if [ -z "${SKIP_EXPERIMENT:-}" ]; then
  "$BIN" experiment "$SRC/scenarios/experiments/paper.yaml" --quick --out experiment > experiment.log 2>&1
fi
echo "outputs of $BIN in $OUT"
