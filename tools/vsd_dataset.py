#!/usr/bin/python3
"""Read vsd-sumo datasets (schema vsd-dataset/3, and /2, /1) with h5py and numpy.

    from vsd_dataset import Dataset
    ds = Dataset("out/acc_lk/dataset.h5")
    s = ds.sample(17)
    s["polylines"][0]["vectors"]   # (n, 7): x_start, y_start, x_end, y_end, object_type, polyline_id, timestamp
    s["target"]                    # (25, 2): the Ego's future centre positions
    s["polylines"][i]["length"]    # m, vehicle and Ego polylines (lane boundaries: 0)
    s["polylines"][i]["road_user"] # kind: 0 car, 1 van, 2 truck, 3 bus, 4 motorbike, 5 pedestrian,
                                   # 6 stationary object (lane boundaries: -1)

Command line (used by the tests):
    tools/vsd_dataset.py info out/acc_lk/dataset.h5
    tools/vsd_dataset.py validate out/acc_lk/dataset.h5
    tools/vsd_dataset.py dump out/acc_lk/dataset.h5 --sample 17     # one sample as JSON
"""
import argparse
import json
import os
import sys

import h5py
import numpy as np

SCHEMA = "vsd-dataset/3"
SCHEMA_V2 = "vsd-dataset/2"  # no road-user kinds: every vehicle is a car
SCHEMA_V1 = "vsd-dataset/1"  # no vehicle sizes either: ASSUMED_SIZE is used for every vehicle
ASSUMED_SIZE = (5.0, 1.8)
FEATURES = ["x_start", "y_start", "x_end", "y_end", "object_type", "polyline_id", "timestamp"]
LANE, VEHICLE, EGO = 1, 2, 3


class Dataset:
    def __init__(self, path):
        if os.path.isdir(path):
            path = os.path.join(path, "dataset.h5")
        self.path = path
        self.file = h5py.File(path, "r")
        schema = self.file.attrs.get("schema")
        if schema not in (SCHEMA, SCHEMA_V2, SCHEMA_V1):
            raise ValueError("%s: schema %r is not %r, %r or %r" % (path, schema, SCHEMA, SCHEMA_V2, SCHEMA_V1))
        self.schema = schema
        f = self.file
        self.step = float(f.attrs["step"])
        self.horizon = int(f.attrs["horizon"])
        self.history = int(f.attrs["history"])
        self.kind = f.attrs["kind"]
        self.labels = list(f["labels"].asstr()[:])
        self.input_names = list(f["input_names"].asstr()[:])
        self.metric_names = list(f["metric_names"].asstr()[:])
        self.sources = list(f["sources"].asstr()[:])
        self.ego_ids = list(f["ego_ids"].asstr()[:])
        # Index arrays are small: read them once.
        self.polyline_start = f["sample_polyline_start"][:]
        self.polyline_count = f["sample_polyline_count"][:]
        self.ego_polyline = f["sample_ego_polyline"][:]
        self.origin = f["sample_origin"][:]
        self.label_index = f["sample_label"][:]
        self.polyline_type = f["polyline_type"][:]
        self.polyline_shared = f["polyline_shared"][:]
        self.polyline_vector_start = f["polyline_vector_start"][:]
        self.polyline_vector_count = f["polyline_vector_count"][:]
        self.shared_vectors = f["shared_vectors"][:]
        vehicle = self.polyline_type != LANE
        if schema != SCHEMA_V1:
            self.polyline_length = f["polyline_length"][:].astype(np.float64)
            self.polyline_width = f["polyline_width"][:].astype(np.float64)
        else:
            self.polyline_length = np.where(vehicle, ASSUMED_SIZE[0], 0.0)
            self.polyline_width = np.where(vehicle, ASSUMED_SIZE[1], 0.0)
        if schema == SCHEMA:
            self.polyline_road_user = f["polyline_road_user"][:].astype(np.int64)
        else:
            self.polyline_road_user = np.where(vehicle, 0, -1)

    def __len__(self):
        return len(self.label_index)

    def sample(self, i):
        f = self.file
        origin = self.origin[i]
        shift = np.array([origin[0], origin[1], origin[0], origin[1], 0, 0, 0])
        polylines = []
        first = self.polyline_start[i]
        for p in range(self.polyline_count[i]):
            row = first + p
            start, count = int(self.polyline_vector_start[row]), int(self.polyline_vector_count[row])
            if self.polyline_shared[row]:
                vectors = self.shared_vectors[start:start + count].copy()
                vectors[:, 5] = p
                valid = np.ones(count, dtype=bool)
            else:
                vectors = f["vectors"][start:start + count].astype(np.float64) + shift
                valid = f["vector_valid"][start:start + count].astype(bool)
            polylines.append({"type": int(self.polyline_type[row]), "vectors": vectors, "valid": valid,
                              "length": float(self.polyline_length[row]), "width": float(self.polyline_width[row]),
                              "road_user": int(self.polyline_road_user[row])})
        sample = {
            "label": self.labels[self.label_index[i]],
            "sample_index": int(f["sample_index"][i]),
            "polylines": polylines,
            "ego_polyline": int(self.ego_polyline[i]),
            "target": f["targets"][i].astype(np.float64) + origin,
            "target_valid": f["target_valid"][i].astype(bool),
            "source": self.sources[f["sample_source"][i]],
            "ego_id": self.ego_ids[f["sample_ego"][i]],
            "t0": float(f["sample_t0"][i]),
        }
        if "inputs" in f:
            sample["inputs"] = dict(zip(self.input_names, f["inputs"][i].tolist()))
        if "metrics" in f:
            sample["metrics"] = dict(zip(self.metric_names, f["metrics"][i].tolist()))
        return sample

    def validate(self):
        """The same invariants as `vsd-sumo dataset validate`; returns a list of problems."""
        problems = []
        max_t = self.horizon * self.step + 1e-4
        min_t = -self.history * self.step - 1e-4
        for i in range(len(self)):
            s = self.sample(i)
            types = [p["type"] for p in s["polylines"]]
            if types.count(EGO) != 1 or types[s["ego_polyline"]] != EGO:
                problems.append("sample %d: expected exactly one Ego polyline at index %d" % (i, s["ego_polyline"]))
            for p, poly in enumerate(s["polylines"]):
                v = poly["vectors"]
                if len(v) == 0:
                    problems.append("sample %d polyline %d: no vectors" % (i, p))
                    continue
                if not np.all(v[:, 4] == poly["type"]) or not np.all(v[:, 5] == p):
                    problems.append("sample %d polyline %d: object type or polyline id inconsistent" % (i, p))
                good = v[poly["valid"]]
                if not np.all(np.isfinite(good[:, :4])):
                    problems.append("sample %d polyline %d: non-finite coordinates" % (i, p))
                if np.any(good[:, 6] < min_t) or np.any(good[:, 6] > max_t):
                    problems.append("sample %d polyline %d: timestamp out of range" % (i, p))
                if poly["type"] != LANE and not (0 < poly["length"] < 100 and 0 < poly["width"] < 20):
                    problems.append("sample %d polyline %d: vehicle size %g x %g m" % (i, p, poly["length"], poly["width"]))
                if poly["type"] == LANE and np.any(v[:, 6] != 0):
                    problems.append("sample %d polyline %d: lane vector with timestamp != 0" % (i, p))
            if s["target"].shape != (self.horizon, 2):
                problems.append("sample %d: target shape %s" % (i, s["target"].shape))
            if len(problems) > 50:
                break
        return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=["info", "validate", "dump"])
    parser.add_argument("dataset")
    parser.add_argument("--sample", type=int, default=0)
    args = parser.parse_args()
    ds = Dataset(args.dataset)
    if args.command == "info":
        counts = {}
        for index in ds.label_index:
            counts[ds.labels[index]] = counts.get(ds.labels[index], 0) + 1
        print(json.dumps({"samples": len(ds), "schema": ds.schema, "kind": ds.kind, "step": ds.step, "horizon": ds.horizon,
                          "history": ds.history, "labels": counts, "inputs": ds.input_names,
                          "metrics": ds.metric_names, "sources": ds.sources}, indent=2))
        return 0
    if args.command == "validate":
        problems = ds.validate()
        for problem in problems:
            print(problem)
        print("%s: %s (%d samples)" % (ds.path, "valid" if not problems else "INVALID", len(ds)))
        return 0 if not problems else 1
    s = ds.sample(args.sample)
    s["polylines"] = [{"type": p["type"], "vectors": p["vectors"].tolist(), "valid": p["valid"].tolist(),
                       "length": p["length"], "width": p["width"]} for p in s["polylines"]]
    s["target"] = s["target"].tolist()
    s["target_valid"] = s["target_valid"].tolist()
    print(json.dumps(s))
    return 0


if __name__ == "__main__":
    sys.exit(main())
