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
# 4. transfer/cold and transfer/prior (step `transfer`, not in the default): does data of the
#    other ALKS scenarios help a search of cut_in? The vectornet surrogate searches it with and
#    without --prior runs of the fourteen other ALKS scenarios (2,000 each, seed 11: data, not
#    a choice), five sealed test seeds 1001-1005, the test step's flags (but --probability,
#    which only extra trees read) plus the transfer benchmark's vectornet settings (--pool
#    2000 --threads 1, chosen on acc_lk's seeds 1-4, docs/search.md "Transfer"; nothing was
#    tuned on ALKS), the two benchmarks side by side; about two hours on 2 cores.
#   tools/alks_search.sh [VSD_SUMO] [STEPS]   # from the repository root; STEPS: any of
#                                             # failures selection test transfer (default:
#                                             # the first three, about 30 min on 2 cores)
set -eu
vsd=${1:-build/vsd-sumo}
steps=${2:-"failures selection test"}
for step in $steps; do
  case $step in
    failures|selection|test|transfer) ;;
    *) echo "alks_search.sh: step '$step': expected failures, selection, test or transfer" >&2; exit 1 ;;
  esac
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
    --criterion reference_avoids_sut_collides --budget 2000 --jobs "${jobs:-2}" --out "$folder" "$@"
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

case " $steps " in *" transfer "*)
  for file in scenarios/alks/*.yaml; do
    [ "$(basename "$file")" = cut_in.yaml ] && continue
    "$vsd" -q run "$file" --samples 2000 --seed 11 -j 2 --out "$work/priors/$(basename "$file" .yaml)"
  done
  # The test step's settings but --probability (extra trees only); one job and thread each.
  jobs=1
  set -- --seeds 5 --first-seed 1001 --pool 2000 --threads 1 \
    --initial 100 --estimate-share 0.2 --diversity 0.3
  # The true rate (the same scenario and criterion for both) once, in the cold folder.
  search cut_in "$out/transfer/cold" --surrogates vectornet --true-rate-samples 200000 "$@" > "$work/cold.log" 2>&1 &
  cold=$!
  # shellcheck disable=SC2046  # one prior folder per word
  search cut_in "$out/transfer/prior" --surrogates vectornet --prior $(ls -d "$work"/priors/*) "$@" \
    > "$work/prior.log" 2>&1 &
  prior=$!
  status=0
  wait "$cold" || { status=1; cat "$work/cold.log" >&2; }
  wait "$prior" || { status=1; cat "$work/prior.log" >&2; }
  [ "$status" -eq 0 ] || { echo "alks_search.sh: a transfer benchmark failed" >&2; exit 1; }
esac
