#!/bin/sh
# results/deviations/bench_deviations.txt: the deviations finder on field data with known
# answers (issue 25 item 4; docs/deviations.md "Benchmark with known answers"), the
# benchmark's defaults: the recommended model trained on 10,000 clean acc_lk scenes (12,000
# steps), validation seeds 101 and 102 (where the settings were chosen) and sealed test
# seeds 201-203, each
# 2,900 field scenes of which 30 % carry the friction limit (max_decel 3 m/s^2), scored with
# the model's own calibration and ranked among 2,000 clean calibration runs (seed 301); and
# bench_deviations_braking.txt: the same field scored on a_min and the path only.
#
#   tools/deviations_results.sh [VSD_SUMO]      # from the repository root
set -eu
vsd=${1:-build/vsd-sumo}
out=results/deviations
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
# bench FILE ARGS...: one benchmark into $work/FILE (the model of the first is reused by the next).
bench() {
  file=$1
  shift
  set -- bench deviations --work "$work/bench" --test-seed 201 202 203 --jobs 2 "$@"
  {
    echo "# $("$vsd" --version): $vsd $* (work folder: a temporary one)"
    "$vsd" "$@"
  } > "$work/$file"
}
bench bench_deviations.txt
# A test aimed at braking factors: a_min and the path only (chosen on validation seeds 101 and
# 102 for this factor; the general default above scores d_min and lane_offset_max too).
bench bench_deviations_braking.txt --metrics a_min
mv "$work/bench_deviations.txt" "$work/bench_deviations_braking.txt" "$out/"
