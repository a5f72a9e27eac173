#!/bin/sh
# What a run's start costs before any scenario: the shared libraries a build loads (and how many
# of them bind every symbol at load, BIND_NOW), and the CPU time (GNU time: user + system, every
# process) of `BIN --version` and of `BIN run SCENARIO --samples 1`, ROUNDS times each.
# usage: tools/run_start.sh BIN SCENARIO ROUNDS
set -eu
bin=$1; scenario=$2; rounds=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
libraries=$(ldd "$bin" | awk '/=>/ {print $3}')
count=0; bind_now=0
for library in $libraries; do
  count=$((count + 1))
  if readelf -d "$library" | grep -q 'BIND_NOW\|FLAGS_1.*NOW'; then bind_now=$((bind_now + 1)); fi
done
echo "# tools/run_start.sh: $($bin --version)"
echo "shared libraries loaded: $count, of them BIND_NOW: $bind_now"
round=1
while [ "$round" -le "$rounds" ]; do
  /usr/bin/time -o "$work/time" -f "%U %S %R" "$bin" --version >/dev/null
  read -r user system faults <"$work/time"
  echo "round $round: --version: user $user s, system $system s, minor page faults $faults"
  rm -rf "$work/out"
  /usr/bin/time -o "$work/time" -f "%U %S %R" "$bin" -q run "$scenario" --samples 1 --out "$work/out" >/dev/null
  read -r user system faults <"$work/time"
  echo "round $round: run --samples 1: user $user s, system $system s, minor page faults $faults"
  round=$((round + 1))
done
