#!/usr/bin/python3
"""Impossible motion among the valid instants of a dataset (issue 29's measure for map exports).

    tools/motion_check.py out/pasubio.h5 [--max-accel 15] [--tolerance 0.5] [--show 5]

For every vehicle and Ego polyline of every sample, and for each Ego's whole path (its
history vectors, its position at t0 and its valid targets), consecutive valid positions
p_{k-1}, p_k, p_{k+1} (one step dt apart) give
  - the acceleration |p_{k+1} - 2 p_k + p_{k-1}| / dt^2 (m/s^2), and
  - a jump: a step |p_k - p_{k-1}| longer than both neighbouring steps by more than the
    tolerance (0.5 m) plus what the largest possible acceleration adds in a step
    (max_accel * dt^2): farther than the vehicle's speed (its neighbouring steps) allows.
Prints the counts beyond the bounds and the worst cases; exit 1 if any instant breaks them.
"""
import argparse
import sys

import numpy as np

from vsd_dataset import Dataset, EGO, VEHICLE


def paths(ds, i):
    """(kind, positions [n, 2] with NaN where invalid) of sample i."""
    s = ds.sample(i)
    for p in s["polylines"]:
        vectors, valid = p["vectors"], p["valid"]
        kind = p["type"]
        if kind not in (VEHICLE, EGO):
            continue
        if kind == EGO:
            vectors, valid = vectors[:-1], valid[:-1]  # the last vector is the initial state, not a motion
        n = len(vectors)
        positions = np.full((n + 1, 2), np.nan)
        for k in range(n):
            if valid[k]:
                positions[k] = vectors[k, 0:2]
                positions[k + 1] = vectors[k, 2:4]
        if kind == EGO:
            # The whole path: history, t0 (the sample origin), the valid targets.
            target = np.where(s["target_valid"][:, None], s["target"], np.nan)
            t0 = ds.origin[i].reshape(1, 2)
            positions = np.vstack([positions[:-1], t0, target])
        yield ("ego" if kind == EGO else "vehicle"), positions


def check(positions, dt, max_accel, tolerance):
    """(accelerations [m], jumps [m]) at the interior instants with three valid positions."""
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=1)  # NaN where either end is invalid
    accel = np.linalg.norm(positions[2:] - 2 * positions[1:-1] + positions[:-2], axis=1) / dt**2
    prev_step, this_step, next_step = steps[:-2], steps[1:-1], steps[2:]
    jumps = this_step - np.fmax(prev_step, next_step) - max_accel * dt**2
    return accel[np.isfinite(accel)], jumps[np.isfinite(jumps)]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dataset")
    parser.add_argument("--max-accel", type=float, default=15.0)
    parser.add_argument("--tolerance", type=float, default=0.5)
    args = parser.parse_args()
    ds = Dataset(args.dataset)
    dt = ds.step
    counts = {"vehicle": [0, 0, 0], "ego": [0, 0, 0]}  # instants checked, accelerations beyond, jumps beyond
    worst = {"vehicle": [0.0, 0.0], "ego": [0.0, 0.0]}
    for i in range(len(ds)):
        for kind, positions in paths(ds, i):
            accel, jumps = check(positions, dt, args.max_accel, args.tolerance)
            counts[kind][0] += len(accel)
            counts[kind][1] += int(np.sum(accel > args.max_accel))
            counts[kind][2] += int(np.sum(jumps > args.tolerance))
            if len(accel):
                worst[kind][0] = max(worst[kind][0], float(accel.max()))
            if len(jumps):
                worst[kind][1] = max(worst[kind][1], float(jumps.max()))
    bad = 0
    print("%s: %d samples, step %g s" % (args.dataset, len(ds), dt))
    for kind in ("ego", "vehicle"):
        checked, over_accel, over_jump = counts[kind]
        bad += over_accel + over_jump
        print("  %-7s valid instants checked %8d; |a| > %g m/s^2: %d (max %.1f); jumps > %g m beyond the "
              "neighbouring steps (+ max_accel dt^2): %d (max %.2f m)" % (kind, checked, args.max_accel, over_accel, worst[kind][0],
                                                       args.tolerance, over_jump, worst[kind][1]))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
