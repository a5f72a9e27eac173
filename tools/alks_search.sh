#!/bin/sh
# results/alks_search: search on UN R157's pass criterion (issue 25 item 2).
#
# 1. regulation_failures.txt: 5,000 runs (seed 7) of every scenario of scenarios/alks/ with
#    --reference r157_reference_driver — where does the built-in system under test (`alks`)
#    collide where the reference driver does not? (free_driving has no other road user, so no
#    collision metric, and is left out.)
# 2. For the scenarios where it does (the two cut-ins): random sampling against extra trees,
#    ten searches each on the sealed test seeds 1001-1010, budget 2,000 simulations = 1,000
#    executions (each runs the system and the reference driver). The extra-trees settings were
#    chosen on validation seeds 1-3 (docs/search.md "On the regulation's criterion"); the true
#    rate is plain Monte Carlo over 200,000 scenarios of seed 1,000,000.
#
#   tools/alks_search.sh [VSD_SUMO]      # from the repository root; about 30 min on 2 cores
set -eu
vsd=${1:-build/vsd-sumo}
out=results/alks_search
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
{
  echo "# $("$vsd" --version): $vsd run SCENARIO --samples 5000 --seed 7 --reference r157_reference_driver -j 2"
  for file in scenarios/alks/*.yaml; do
    [ "$(basename "$file")" = free_driving.yaml ] && continue
    "$vsd" run "$file" --samples 5000 --seed 7 --reference r157_reference_driver -j 2 --out "$work/run" \
      | grep -E "concrete scenarios|completed|reference driver"
    rm -rf "$work/run"
  done
} > "$work/regulation_failures.txt"
mv "$work/regulation_failures.txt" "$out/regulation_failures.txt"
for scenario in cut_in cut_in_unavoidable; do
  "$vsd" bench search "scenarios/alks/$scenario.yaml" --reference r157_reference_driver \
    --criterion reference_avoids_sut_collides --surrogates random,extra-trees --budget 2000 \
    --probability tail --diversity 0.3 --initial 100 --estimate-share 0.2 \
    --seeds 10 --first-seed 1001 --true-rate-samples 200000 --jobs 2 --out "$out/$scenario"
done
