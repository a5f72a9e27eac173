#!/bin/sh
# The system side of a run's CPU time, which callgrind's instruction counts do not see: user
# and system seconds, minor page faults and peak RSS (GNU time, every process of the run) of
#   BIN -q run SCENARIO --samples SAMPLES --seed 3
# for each build given, ROUNDS times in turn (a shared VM's times drift; the fault counts do not).
# usage: tools/page_faults.sh SCENARIO SAMPLES ROUNDS BIN [BIN ...]
set -eu
scenario=$1; samples=$2; rounds=$3; shift 3
[ -x /usr/bin/time ] || { echo "page_faults.sh: needs GNU time (apt-get install time)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# tools/page_faults.sh $scenario $samples $rounds: GNU time over every process of run --samples $samples --seed 3"
round=1
while [ "$round" -le "$rounds" ]; do
  for bin in "$@"; do
    rm -rf "$work/out"
    /usr/bin/time -o "$work/time" -f "%U %S %R %M" "$bin" -q run "$scenario" --samples "$samples" --seed 3 \
      --out "$work/out" >/dev/null
    read -r user system faults rss <"$work/time"
    echo "round $round $($bin --version): user $user s, system $system s, minor page faults $faults," \
      "peak RSS $((rss / 1024)) MiB"
  done
  round=$((round + 1))
done
