#!/bin/sh
# Instructions executed (valgrind's callgrind, every process of the run, the forked workers
# included) per concrete scenario and per simulated vehicle-step of
#   BIN run SCENARIO --samples SAMPLES --seed 3
# for each build given. Unlike CPU time, which varies by up to 2x from run to run on the
# shared VM (docs/alks-scenarios.md), the count changes only with the work done, so it tells
# whether a change made the run cheaper. It is not the issue's measure (CPU time, `bench run`).
# A forked child inherits callgrind's counters (valgrind's manual, "Forking Programs"), so each
# process dumps and zeroes its counters before every fork: every instruction is counted once.
# usage: tools/instruction_count.sh SCENARIO SAMPLES BIN [BIN ...]
set -eu
scenario=$1; samples=$2; shift 2
command -v valgrind >/dev/null ||
  { echo "instruction_count.sh: needs valgrind (apt-get install valgrind)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# tools/instruction_count.sh $scenario $samples: callgrind, all processes, run --samples $samples --seed 3"
for bin in "$@"; do
  rm -rf "$work/out" "$work"/cg.*
  valgrind --tool=callgrind --trace-children=yes --dump-before='*fork' --callgrind-out-file="$work/cg.%p" \
    "$bin" --quiet run "$scenario" --samples "$samples" --seed 3 --out "$work/out" >/dev/null 2>"$work/log" ||
    { echo "instruction_count.sh: $bin failed:" >&2; tail -3 "$work/log" >&2; exit 1; }
  # A run of several processes whose parent never dumped at a fork would count them twice.
  processes=$(ls "$work" | sed -n 's/^cg\.\([0-9]*\).*/\1/p' | sort -u | wc -l)
  if [ "$processes" -gt 1 ] && ! ls "$work" | grep -q '^cg\.[0-9]*\.[0-9]*$'; then
    echo "instruction_count.sh: $processes processes but no dump at a fork: counts would repeat inherited ones" >&2
    exit 1
  fi
  # Per dump (cg.PID and cg.PID.N): its "totals:" line, else its "summary:" line.
  total=$(awk '$1 == "totals:" {t[FILENAME] = $2} $1 == "summary:" {s[FILENAME] = $2}
    END {for (f in s) if (!(f in t)) t[f] = s[f]; for (f in t) sum += t[f]; printf "%.0f", sum}' "$work"/cg.*)
  # Road users x steps of every scenario that ran, from the traces.
  vehicle_steps=$(/usr/bin/python3 -c "
import h5py, sys
f = h5py.File(sys.argv[1])
n, users, instants, _ = f['states'].shape
print(n * users * (instants - 1), n)" "$work/out/traces.h5")
  echo "$($bin --version) $vehicle_steps" | awk -v total="$total" '{
    printf "%s: %.1f M instructions, %.2f M per scenario, %.0f per vehicle-step (%d scenarios, %d vehicle-steps)\n",
      $1, total / 1e6, total / 1e6 / $3, total / $2, $3, $2 }'
done
