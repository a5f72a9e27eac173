#!/bin/sh
# results/transfer: does data of other functional scenarios help a search? The vectornet
# surrogate searches acc_lk for `d_min < 2` with and without priors of acc and lk
# (docs/search.md "Transfer"), five sealed test seeds (1001-1005; the method was chosen on
# seeds 1-4), one libtorch thread each, the two benchmarks side by side.
#
#   tools/transfer_results.sh [VSD_SUMO] [PRIOR_FOLDER]     # from the repository root
#
# Writes results/transfer/cold (random and vectornet without priors) and
# results/transfer/prior (vectornet with --prior), each a `bench search --out` folder.
set -eu
vsd=${1:-build/vsd-sumo}
mkdir -p results/transfer
priors=${2:-out/transfer_priors}
# The priors: 2,000 scenarios each of acc and lk, seed 11 (data, not a choice).
"$vsd" run scenarios/acc.yaml --samples 2000 --seed 11 --out "$priors/acc"
"$vsd" run scenarios/lk.yaml --samples 2000 --seed 11 --out "$priors/lk"
set -- scenarios/acc_lk.yaml --criterion "d_min < 2" --budget 500 --initial 50 --round 50 --pool 2000 \
  --estimate-share 0.2 --threads 1 --seeds 5 --first-seed 1001
"$vsd" bench search "$@" --surrogates random,vectornet --out results/transfer/cold > results/transfer/cold.log 2>&1 &
cold=$!
"$vsd" bench search "$@" --surrogates vectornet --prior "$priors/acc" "$priors/lk" --out results/transfer/prior \
  > results/transfer/prior.log 2>&1 &
prior=$!
status=0
wait "$cold" || status=1
wait "$prior" || status=1
[ "$status" -eq 0 ] || { echo "transfer_results.sh: a benchmark failed; see results/transfer/*.log" >&2; exit 1; }
rm -f results/transfer/cold.log results/transfer/prior.log
