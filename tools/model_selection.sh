#!/bin/sh
# results/model_selection: the kinematic model's configuration choices re-measured on the
# validation seed (issue 26 item 2; core/seeds.hpp): the recommended preset against one
# change each - the acceleration loss weight, the frame, the decoder, the lane smoothing.
# `vsd-sumo bench model` trains on seed 1 and measures on 2,000 fresh scenarios of the
# validation seed 2 per functional scenario; nothing here sees a test seed.
#
#   tools/model_selection.sh [VSD_SUMO] [WORK]      # from the repository root
#
# One file per configuration, results/model_selection/<name>.txt, its first line naming the
# version and the command; two benchmarks at a time, one libtorch thread each.
set -eu
vsd=${1:-build/vsd-sumo}
work=${2:-out/model_selection}
out=results/model_selection
mkdir -p "$out" "$work"
version=$("$vsd" --version)
case "$version" in *-dirty) echo "model_selection.sh: $vsd was built from uncommitted changes ($version)" >&2; exit 1 ;; esac

measure() {  # name, bench model flags...
  name=$1; shift
  {
    echo "# vsd-sumo $version: vsd-sumo bench model --threads 1 --work $work/$name $*"
    "$vsd" bench model --threads 1 --work "$work/$name" "$@"
  } > "$out/$name.txt.partial" 2>&1 && mv "$out/$name.txt.partial" "$out/$name.txt"
}

first() {
  measure recommended --row4
  measure accel_weight_1 --decoder-option accel_weight=1
  measure lane_smoothing_2m --lane-smoothing 2
}
second() {
  measure ego_frame --frame ego --row4
  measure offsets_decoder --decoder offsets
  measure lane_smoothing_4m --lane-smoothing 4
}
first & a=$!
second & b=$!
status=0
wait "$a" || status=1
wait "$b" || status=1
[ "$status" -eq 0 ] || { echo "model_selection.sh: a benchmark failed; see $out/*.partial" >&2; exit 1; }
