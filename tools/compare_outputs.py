#!/usr/bin/python3
"""Compare two folders of vsd-sumo outputs by content (tools/outputs_of_each_command.sh makes
them): CSV cell by cell, JSON, HDF5 datasets and attributes (h5py), model archives entry by
entry, Markdown and HTML reports - ignoring only what records when, how long, by which build
and from where (timings, tool versions, command lines, checksums of files compared by
content, cache-key digests that include the code's identity).

  /usr/bin/python3 tools/compare_outputs.py BEFORE AFTER

Prints each file that differs and what differs; exits 1 if any does.
"""

import csv
import json
import pathlib
import re
import sys
import zipfile

import h5py
import numpy as np

# Keys (JSON, CSV columns, HDF5 attributes) that record when, how long, by which build, from where.
IGNORED_KEYS = {
    "tool_version", "version", "finished", "finished_utc", "started", "seconds", "command_line",
    "manifest_sha256", "sha256", "created", "key_sha256", "samples_per_second", "reused",
    "outputs",  # a manifest's checksums of files compared here by content
}
SHA256 = re.compile(r"[0-9a-f]{64}")


def ignored(name):
    return name in IGNORED_KEYS or name.endswith("_seconds") or name.endswith("_utc")


def without_ignored(value):
    if isinstance(value, dict):
        return {k: without_ignored(v) for k, v in value.items() if not ignored(k)}
    if isinstance(value, list):
        return [without_ignored(v) for v in value]
    if isinstance(value, str) and SHA256.fullmatch(value):
        return "<checksum of a file compared by content>"
    return value


def compare_csv(a, b):
    rows_a, rows_b = list(csv.DictReader(a.open())), list(csv.DictReader(b.open()))
    if len(rows_a) != len(rows_b):
        return f"{len(rows_a)} vs {len(rows_b)} rows"
    for row_a, row_b in zip(rows_a, rows_b):
        for column, value in row_a.items():
            if not ignored(column) and value != row_b.get(column):
                return f"column {column}: {value} vs {row_b.get(column)}"
    return None


def compare_json(a, b):
    return None if without_ignored(json.loads(a.read_text())) == without_ignored(json.loads(b.read_text())) else "json"


def compare_hdf5(a, b):
    file_a, file_b = h5py.File(a, "r"), h5py.File(b, "r")
    differences = []

    def visit(name, item):
        other = file_b.get(name)
        if other is None:
            differences.append(f"{name} missing")
            return
        for key, value in item.attrs.items():
            if not ignored(key) and (key not in other.attrs or
                                     not np.array_equal(np.asarray(value), np.asarray(other.attrs[key]))):
                differences.append(f"{name}@{key}")
        if isinstance(item, h5py.Dataset):
            if not np.array_equal(item[()], other[()], equal_nan=item.dtype.kind == "f"):
                differences.append(name)

    file_a.visititems(visit)
    visit("/", file_a["/"])
    return ", ".join(differences[:5]) or None


def model_metadata_without_version(data):
    # The model's JSON description sits in the pickle behind its length; drop the version and the length.
    data = re.sub(rb'"tool_version":"[^"]*"', b"", data)
    return re.sub(rb'X....(\{"architecture")', rb"X\1", data, flags=re.S)


def compare_model(a, b):
    zip_a, zip_b = zipfile.ZipFile(a), zipfile.ZipFile(b)
    if zip_a.namelist() != zip_b.namelist():
        return "entries"
    for name in zip_a.namelist():
        data_a, data_b = zip_a.read(name), zip_b.read(name)
        if data_a == data_b:
            continue
        if name.endswith("data.pkl") and model_metadata_without_version(data_a) == model_metadata_without_version(data_b):
            continue
        return f"entry {name}"
    return None


def compare_key(a, b):
    # The code's identity and digests of other keys (which contain it) change with every build.
    def kept(text):
        return [line for line in text.splitlines()
                if not line.startswith(("code:", "tool")) and not re.fullmatch(r"[\w ]+: [0-9a-f]{64}", line)]
    return None if kept(a.read_text()) == kept(b.read_text()) else "key"


def compare_markdown(a, b):
    # Tables end with a timing column (training time, fit time).
    def kept(text):
        return [line.rsplit("|", 2)[0] if line.startswith("|") else line for line in text.splitlines()]
    return None if kept(a.read_text()) == kept(b.read_text()) else "markdown"


def compare_html(a, b):
    # The provenance rows (version, command line, times) and the run time in the lead line.
    def kept(text):
        return [re.sub(r", [0-9.]+ s</p>", "</p>", line) for line in text.splitlines()
                if not re.search(r"<td>(vsd-sumo|command line|finished|started)</td>", line)]
    return None if kept(a.read_text()) == kept(b.read_text()) else "html"


COMPARISONS = {".csv": compare_csv, ".json": compare_json, ".h5": compare_hdf5, ".pt": compare_model,
               ".key": compare_key, ".md": compare_markdown, ".html": compare_html}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    before, after = map(pathlib.Path, sys.argv[1:])
    equal = differ = 0
    for file in sorted(p for p in before.rglob("*") if p.is_file()):
        relative = file.relative_to(before)
        other = after / relative
        if not other.exists():
            print("only in", before, relative)
            differ += 1
            continue
        if file.read_bytes() == other.read_bytes():
            equal += 1
            continue
        compare = COMPARISONS.get(file.suffix, lambda a, b: "bytes")
        difference = compare(file, other)
        if difference:
            print("DIFFERS", relative, difference)
            differ += 1
        else:
            equal += 1
    print(f"{equal} files equal (ignoring timings, versions, paths), {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
