#!/bin/sh
# The paper's scenarios give the same outputs as before issue 23: 200 samples of acc, lk and
# acc_lk, seeds 1 and 7, with a `vsd-sumo` of main ($1, e.g. /work/main/build/vsd-sumo) and of
# this branch ($2); concrete.csv compared byte for byte, dataset.h5 and traces.h5 value by value
# (every array of the old file equal in the new one; new arrays and the schema attribute listed).
# Usage: results/alks/paper_identity.sh OLD_VSD_SUMO NEW_VSD_SUMO > results/alks/paper_identity.txt
set -e
old=$1
new=$2
work=$(mktemp -d)
here=$(cd "$(dirname "$0")/../.." && pwd)
for s in acc lk acc_lk; do
  for seed in 1 7; do
    "$old" -q run "$here/scenarios/$s.yaml" --samples 200 --seed $seed --out "$work/old_${s}_$seed" > /dev/null
    "$new" -q run "$here/scenarios/$s.yaml" --samples 200 --seed $seed --out "$work/new_${s}_$seed" > /dev/null
    if cmp -s "$work/old_${s}_$seed/concrete.csv" "$work/new_${s}_$seed/concrete.csv"; then same=identical; else same=DIFFERENT; fi
    echo "$s seed $seed: concrete.csv $same"
    for f in dataset.h5 traces.h5; do
      /usr/bin/python3 - "$work/old_${s}_$seed/$f" "$work/new_${s}_$seed/$f" <<'PY'
import sys
import h5py
import numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
differ = []
def walk(name, obj):
    if isinstance(obj, h5py.Dataset):
        if name not in b:
            differ.append(name + " (missing)")
        elif not np.array_equal(obj[()], b[name][()], equal_nan=obj.dtype.kind == "f"):
            differ.append(name)
a.visititems(walk)
new = sorted(n for n in b if n not in a)
print("  %s: every array of the old file equal: %s; new arrays: %s; schema %s -> %s" % (
    sys.argv[1].split("/")[-1], "yes" if not differ else "NO " + ", ".join(differ), ", ".join(new) or "none",
    a.attrs["schema"], b.attrs["schema"]))
PY
    done
  done
done
rm -rf "$work"
