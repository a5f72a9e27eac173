#!/bin/sh
# Whether two builds give the same outputs on the scenario library: `run --samples 300 --seed 5`
# of scenarios/acc.yaml, lk.yaml, acc_lk.yaml and the fifteen of scenarios/alks/ with OLD and
# NEW, compared by tools/compare_outputs.py (every file by content: CSV cell by cell, every array
# and attribute of the HDF5 files, ignoring only timings, versions and checksums of files it
# compares itself). The compressed bytes of the HDF5 files may differ; what they hold may not.
# usage: tools/same_outputs.sh OLD_VSD_SUMO NEW_VSD_SUMO
set -eu
old=$1; new=$2
here=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# tools/same_outputs.sh: old $($old --version), new $($new --version); run --samples 300 --seed 5 of:"
for yaml in "$here"/scenarios/acc.yaml "$here"/scenarios/lk.yaml "$here"/scenarios/acc_lk.yaml \
            "$here"/scenarios/alks/*.yaml; do
  name=$(basename "$yaml" .yaml)
  printf ' %s' "$name"
  "$old" -q run "$yaml" --samples 300 --seed 5 --out "$work/old/$name" >/dev/null
  "$new" -q run "$yaml" --samples 300 --seed 5 --out "$work/new/$name" >/dev/null
done
echo
/usr/bin/python3 "$here/tools/compare_outputs.py" "$work/old" "$work/new"
