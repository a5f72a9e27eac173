#!/bin/sh
# results/alks_search: search on UN R157's pass criterion (issue 25 item 2).
#
# 1. regulation_failures.txt: 5,000 runs (seed 7) of every scenario of scenarios/alks/ with
#    --reference r157_reference_driver — where does the built-in system under test (`alks`)
#    collide where the reference driver does not? (free_driving has no other road user, so no
#    collision metric, and is left out.)
# 2. selection/SCENARIO/CONFIG: the extra-trees settings compared on validation seeds 1-3
#    (three searches per configuration, no true rate), for the scenarios where it does (the
#    two cut-ins). The last configuration is the one chosen.
# 3. SCENARIO: random sampling against extra trees with the chosen settings, ten searches each
#    on the sealed test seeds 1001-1010, budget 2,000 simulations = 1,000 executions (each
#    runs the system and the reference driver); the true rate is plain Monte Carlo over
#    200,000 scenarios of seed 1,000,000.
#
#   tools/alks_search.sh [VSD_SUMO] [STEPS]   # from the repository root; STEPS: any of
#                                             # failures selection test (default: all three);
#                                             # about 30 min on 2 cores
set -eu
vsd=${1:-build/vsd-sumo}
steps=${2:-"failures selection test"}
for step in $steps; do
  case $step in failures|selection|test) ;; *) echo "alks_search.sh: step '$step': expected failures, selection or test" >&2; exit 1 ;; esac
done
out=results/alks_search
scenarios="cut_in cut_in_unavoidable"
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

search() {  # search SCENARIO OUT [flags...]
  scenario=$1 folder=$2
  shift 2
  "$vsd" bench search "scenarios/alks/$scenario.yaml" --reference r157_reference_driver \
    --criterion reference_avoids_sut_collides --budget 2000 --jobs 2 --out "$folder" "$@"
}

case " $steps " in *" failures "*)
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
esac

chosen="--probability tail --diversity 0.3 --initial 100 --estimate-share 0.2"
case " $steps " in *" selection "*)
  for scenario in $scenarios; do
    for config in "defaults:" "tail:--probability tail" "tail_diversity0.3:--probability tail --diversity 0.3" \
                  "tail_initial100:--probability tail --initial 100" \
                  "tail_share0.2:--probability tail --estimate-share 0.2" \
                  "tail_initial100_share0.2:--probability tail --initial 100 --estimate-share 0.2" \
                  "chosen:$chosen"; do
      # shellcheck disable=SC2086  # the flags split into words on purpose
      search "$scenario" "$out/selection/$scenario/${config%%:*}" --surrogates extra-trees --seeds 3 --first-seed 1 \
        ${config#*:}
    done
  done
esac

case " $steps " in *" test "*)
  for scenario in $scenarios; do
    # shellcheck disable=SC2086
    search "$scenario" "$out/$scenario" --surrogates random,extra-trees --seeds 10 --first-seed 1001 \
      --true-rate-samples 200000 $chosen
  done
esac
