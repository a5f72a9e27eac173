#!/usr/bin/env python3
"""Doc tables generated from committed artefacts (issue 26: numbers anyone can reproduce).

A table in README.md or docs/*.md that reports figures sits between two markers:

    <!-- table from="results/paper/ade.md" section="## no_residual" columns="row,acc,lk"
         code="model,vector" -->
    ... generated: never edit by hand ...
    <!-- /table -->

The generator writes, between them, a provenance line (artefact, the vsd-sumo version and the
command that made it, from the manifest.json of the artefact's folder) and the table:

- from a Markdown artefact (an experiment's ade.md, mae.md): the first table after the line
  that starts with `section`, restricted to `columns` (header names, in the order given);
- from a CSV artefact: `columns` as `name` or `name:format` (Python format spec, e.g.
  `ade_m:.2f`), rows filtered by `where="column=value;column=value"`.

`code` names the project modules (src/<m>, include/vsd/<m>) whose code the figures describe.
If any of them changed since the commit the artefact's version names, the table is out of
date: --check fails unless the marker says so with `stale="why it is still shown"`, and the
provenance line then names the changed modules and that reason, so the doc says it too.

  tools/doc_tables.py --write   rewrite every generated table from its artefact
  tools/doc_tables.py --check   exit 1, one line per problem, if a table differs from what its
                                artefact generates or its artefact is older than its code
                                (ctest: DocTables.MatchTheirArtefacts)
"""

import argparse
import csv
import json
import pathlib
import re
import subprocess
import sys

# A marker's attributes may span lines but never hold "-->": a mention of the marker in running
# text ("`<!-- table from=... -->` and") is not one and must not swallow the next real marker.
MARKER = re.compile(r"<!-- table (?P<args>(?:(?!-->).)*?)-->\n(?P<body>.*?)<!-- /table -->", re.S)
ATTRIBUTE = re.compile(r'(\w+)="([^"]*)"')
KNOWN_ATTRIBUTES = {"from", "section", "columns", "where", "code", "stale"}


class TableError(Exception):
    """A marker or artefact that cannot produce its table: one line naming both."""


class HistoryMissing(Exception):
    """The clone lacks the artefact's commit (a shallow clone): its age cannot be judged here."""


def parse_marker(where, text):
    attributes = dict(ATTRIBUTE.findall(text))
    unknown = set(attributes) - KNOWN_ATTRIBUTES
    if unknown:
        raise TableError(f"{where}: unknown marker attribute(s) {', '.join(sorted(unknown))} "
                         f"(known: {', '.join(sorted(KNOWN_ATTRIBUTES))})")
    for required in ("from", "columns", "code"):
        if not attributes.get(required):
            raise TableError(f"{where}: the marker needs {required}=\"...\"")
    return attributes


def markdown_rows(line):
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def table_from_markdown(path, section, where):
    lines = path.read_text(encoding="utf-8").splitlines()
    start = 0
    if section:
        matches = [i for i, line in enumerate(lines) if line.startswith(section)]
        if not matches:
            raise TableError(f"{where}: {path} has no line starting with '{section}'")
        start = matches[0]
    table = []
    for line in lines[start:]:
        if line.startswith("|"):
            table.append(line)
        elif table:
            break
    if len(table) < 2:
        raise TableError(f"{where}: {path} has no table after '{section}'")
    header = markdown_rows(table[0])
    return header, [markdown_rows(line) for line in table[2:]]


def table_from_csv(path, columns, where_filter, where):
    with path.open(newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        rows = list(reader)
        fields = reader.fieldnames or []
    conditions = [c.split("=", 1) for c in where_filter.split(";") if c] if where_filter else []
    for condition in conditions:
        if len(condition) != 2 or condition[0] not in fields:
            raise TableError(f"{where}: where=\"{where_filter}\": expected column=value with a column of {path}")
    header, body = [], []
    specs = []
    for column in columns:
        name, _, spec = column.partition(":")
        if name not in fields:
            raise TableError(f"{where}: {path} has no column '{name}' (columns: {', '.join(fields)})")
        specs.append((name, spec))
        header.append(name)
    for row in rows:
        if all(row[key] == value for key, value in conditions):
            body.append([format(float(row[name]), spec) if spec and row[name] != "" else row[name]
                         for name, spec in specs])
    if not body:
        raise TableError(f"{where}: no row of {path} satisfies where=\"{where_filter}\"")
    return header, body


def select_columns(header, rows, columns, path, where):
    indices = []
    for column in columns:
        if column not in header:
            raise TableError(f"{where}: {path}'s table has no column '{column}' (columns: {', '.join(header)})")
        indices.append(header.index(column))
    return [header[i] for i in indices], [[row[i] if i < len(row) else "" for i in indices] for row in rows]


def manifest_of(artefact, root, where):
    """The manifest.json of the artefact's folder or the nearest folder above it in results/."""
    folder = artefact.parent
    while True:
        manifest = folder / "manifest.json"
        if manifest.is_file():
            return json.loads(manifest.read_text(encoding="utf-8"))
        if folder == root / "results" or folder == folder.parent:
            raise TableError(f"{where}: no manifest.json in {artefact.parent} or above it in results/")
        folder = folder.parent


def version_and_command(manifest, where):
    version = manifest.get("tool_version") or manifest.get("version")
    command = manifest.get("command_line") or manifest.get("command")
    if not version or not command:
        raise TableError(f"{where}: its artefact's manifest names no tool version or command")
    if version.endswith("-dirty") or "+" not in version:
        raise TableError(f"{where}: its artefact was made by '{version}', not by a build of a clean commit")
    return version, command


def changed_modules(root, commit, modules, where):
    known = subprocess.run(["git", "-C", str(root), "cat-file", "-e", f"{commit}^{{commit}}"], capture_output=True)
    if known.returncode != 0:
        shallow = subprocess.run(["git", "-C", str(root), "rev-parse", "--is-shallow-repository"],
                                 capture_output=True, text=True)
        if shallow.stdout.strip() == "true":
            raise HistoryMissing(f"{where}: not checked, this shallow clone lacks commit {commit}")
        raise TableError(f"{where}: its artefact names commit {commit}, which this repository does not have")
    changed = []
    for module in modules:
        paths = [p for p in (f"src/{module}", f"include/vsd/{module}") if (root / p).exists()]
        if not paths:
            raise TableError(f"{where}: code=\"...\" names '{module}', which is no module (src/{module})")
        result = subprocess.run(["git", "-C", str(root), "diff", "--quiet", commit, "HEAD", "--", *paths],
                                capture_output=True, text=True)
        if result.returncode == 1:
            changed.append(module)
        elif result.returncode != 0:
            raise TableError(f"{where}: git cannot compare commit {commit} with HEAD: {result.stderr.strip()}")
    return changed


def render(attributes, root, where):
    artefact = root / attributes["from"]
    if not artefact.is_file():
        raise TableError(f"{where}: the artefact {attributes['from']} does not exist")
    columns = [c.strip() for c in attributes["columns"].split(",")]
    if artefact.suffix == ".csv":
        header, rows = table_from_csv(artefact, columns, attributes.get("where", ""), where)
    else:
        header, rows = table_from_markdown(artefact, attributes.get("section", ""), where)
        header, rows = select_columns(header, rows, columns, attributes["from"], where)
    version, command = version_and_command(manifest_of(artefact, root, where), where)
    commit = version.split("+", 1)[1]
    modules = [m.strip() for m in attributes["code"].split(",")]
    changed = changed_modules(root, commit, modules, where)
    provenance = f"From `{attributes['from']}`, made by vsd-sumo {version}: `{command}`."
    problems = []
    if changed:
        if attributes.get("stale"):
            reason = attributes["stale"].rstrip(".")
            provenance += f" **Out of date:** {', '.join(changed)} changed since; {reason}."

        else:
            problems.append(f"{where}: {attributes['from']} was made at {commit}, and the code it describes has "
                            f"changed since ({', '.join(changed)}): re-run `{command}` or say why it is still "
                            f"shown with stale=\"...\"")
    elif attributes.get("stale"):
        problems.append(f"{where}: stale=\"...\" but none of {', '.join(modules)} changed since {commit}: remove it")
    lines = [provenance, "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines) + "\n", problems


def documents(root):
    yield root / "README.md"
    yield from sorted((root / "docs").glob("*.md"))


def process(path, root, write):
    text = path.read_text(encoding="utf-8")
    problems = []
    pieces = []
    last = 0
    for match in MARKER.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        where = f"{path.relative_to(root)}:{line}"
        try:
            body, found = render(parse_marker(where, match.group("args")), root, where)
        except TableError as error:
            problems.append(str(error))
            continue
        except HistoryMissing as note:
            print(note, file=sys.stderr)
            continue
        problems += found
        if body == match.group("body"):
            continue
        if write:
            pieces.append(text[last:match.start("body")] + body)
            last = match.end("body")
        else:
            source = dict(ATTRIBUTE.findall(match.group("args")))["from"]
            problems.append(f"{where}: the table differs from what {source} generates: run tools/doc_tables.py --write")
    if write and pieces:
        path.write_text("".join(pieces) + text[last:], encoding="utf-8")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="rewrite the generated tables")
    mode.add_argument("--check", action="store_true", help="fail if a table or its artefact is out of date")
    parser.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent, type=pathlib.Path,
                        help="the repository (default: this script's)")
    parser.add_argument("files", nargs="*", type=pathlib.Path, help="documents (default: README.md, docs/*.md)")
    args = parser.parse_args()
    root = args.root.resolve()
    files = [f.resolve() for f in args.files] or list(documents(root))
    problems = []
    tables = 0
    for path in files:
        tables += len(MARKER.findall(path.read_text(encoding="utf-8")))
        problems += process(path, root, args.write)
    for problem in problems:
        print(problem, file=sys.stderr)
    print(f"{tables} generated table(s) in {len(files)} document(s); {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
