#!/bin/sh
# Where the instructions of `BIN run SCENARIO --samples SAMPLES --seed 3` go: callgrind over
# every process (each instruction counted once: tools/callgrind_run.sh), then the inclusive
# count of each part below summed over all processes, per scenario and as a share of the run.
# Inclusive: an indented part is inside the one above it. Counts, unlike CPU times, do not move
# with the shared VM's load.
# usage: tools/instruction_profile.sh SCENARIO SAMPLES BIN
set -eu
scenario=$1; samples=$2; bin=$3
. "$(dirname "$0")/callgrind_run.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
callgrind_run "$work" "$bin" "$scenario" "$samples"
# One listing per dump, each line "count (share)  file:function [object]"; no source annotation.
for dump in "$work"/cg.*; do
  echo "== $dump"
  callgrind_annotate --inclusive=yes --threshold=100 --auto=no "$dump" 2>>"$work/log" ||
    { echo "instruction_profile.sh: callgrind_annotate $dump failed:" >&2; tail -3 "$work/log" >&2; exit 1; }
done >"$work/inclusive"
total=$(callgrind_total "$work")
echo "# tools/instruction_profile.sh $scenario $samples: $($bin --version), callgrind inclusive counts, all processes"
printf '%-62s %12s %14s %7s\n' "part (function)" "M instr" "K per scenario" "share"
# label|pattern: the start of the function's name in callgrind_annotate's "file:function" column.
# Per dump the largest matching entry counts (a function split into clones or, with debug
# information, listed once per file it was inlined from holds its whole cost in its own entry).
while IFS='|' read -r label pattern; do
  count=$(awk -v p="$pattern" '
    $1 == "==" { dump = $2; next }
    $1 ~ /^[0-9,]+$/ && $0 !~ /\[clone / {
      count = $1; gsub(",", "", count)
      entry = $0; sub(/^ *[0-9,]+ +\([ 0-9.]+%\) +/, "", entry)  # "file:function [object]"
      name = entry; sub(/^[^:]*:/, "", name)
      if (index(name, p) == 1 && count + 0 > best[dump]) best[dump] = count + 0
    }
    END { for (d in best) sum += best[d]; printf "%.0f", sum }' "$work/inclusive")
  echo "$label $count" | awk -v total="$total" -v n="$samples" -v label="$label" '{
    printf "%-62s %12.1f %14.1f %6.1f%%\n", label, $NF / 1e6, $NF / 1e3 / n, 100 * $NF / total }'
done <<'PARTS'
loading the shared libraries (dynamic linker; once per run)|_dl_sysdep_start
running the libraries' initialisers (once per run)|_dl_init
simulating the batches (worker)|vsd::sim::simulateBatch(
  SUMO: loading each batch's network|libsumo::Simulation::load(
  SUMO: adding the road users|libsumo::Vehicle::add(
    of which building SUMO's vehicle devices|MSDevice::buildVehicleDevices(
  SUMO: placing the road users each step|libsumo::Vehicle::moveToXY(
  SUMO: the road users' speeds each step|libsumo::Vehicle::setSpeed(
  SUMO: stepping|libsumo::Simulation::step(
  the Ego's observation (incl. SUMO's leader and lane)|vsd::sim::EgoDriver::observe(
  the scripted road users|vsd::sim::ScriptedTraffic::step(
sampling and writing each batch's network (worker)|vsd::pipeline::(anonymous namespace)::BatchProcessor::prepare(
metrics (worker)|vsd::metrics::MetricSet::evaluate(
writing concrete.csv, dataset.h5, traces.h5 rows (main)|vsd::pipeline::OutcomeFiles::write(
  of which compressing whole chunks (libdeflate)|libdeflate_zlib_compress
closing the HDF5 files (main)|vsd::pipeline::OutcomeFiles::close(
HDF5's own deflate filter (zlib), wherever it runs (main)|compress2
checksums of the outputs for the manifest (main)|vsd::OutputFolder::commit(
PARTS
echo "$total $samples" | awk '{ printf "%-62s %12.1f %14.1f %6.1f%%\n", "the whole run", $1 / 1e6, $1 / 1e3 / $2, 100 }'
