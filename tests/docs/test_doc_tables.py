"""tools/doc_tables.py on a small repository of its own: a doc table is what its artefact
generates, an edited table or an artefact older than its code fails --check, and a table
shown although out of date says so (issue 26)."""

import json
import pathlib
import subprocess
import sys
import tempfile
import unittest

TOOL = pathlib.Path(__file__).resolve().parents[2] / "tools" / "doc_tables.py"

ARTEFACT = """# ADE (m)

## model a

| row | mix | acc | seeds |
|---|---|---|---|
| 1 | acc 2000 | 0.26 | 1 |
| 2 | lk 2000 | 6.97 | 3 |

## model b

| row | mix | acc | seeds |
|---|---|---|---|
| 1 | acc 2000 | 0.15 | 1 |
"""


def git(root, *args):
    return subprocess.run(["git", "-C", str(root), "-c", "user.name=t", "-c", "user.email=t@t", *args],
                          check=True, capture_output=True, text=True).stdout.strip()


class DocTables(unittest.TestCase):
    def setUp(self):
        self.work = tempfile.TemporaryDirectory()
        self.root = pathlib.Path(self.work.name)
        git(self.root, "init", "-q")
        (self.root / "src" / "model").mkdir(parents=True)
        (self.root / "src" / "model" / "a.cpp").write_text("int a;\n")
        (self.root / "results" / "exp").mkdir(parents=True)
        (self.root / "results" / "exp" / "ade.md").write_text(ARTEFACT)
        (self.root / "results" / "exp" / "ade.csv").write_text("row,label,ade_m\n1,acc,0.25698\n1,lk,9.1282\n2,acc,6.9702\n")
        git(self.root, "add", "-A")
        git(self.root, "commit", "-qm", "code")
        self.commit = git(self.root, "rev-parse", "--short=12", "HEAD")
        (self.root / "results" / "exp" / "manifest.json").write_text(
            json.dumps({"tool_version": f"0.1.0+{self.commit}", "command_line": "vsd-sumo experiment x.yaml"}))
        (self.root / "docs").mkdir()
        self.doc = self.root / "docs" / "results.md"

    def tearDown(self):
        self.work.cleanup()

    def run_tool(self, mode, extra=()):
        return subprocess.run([sys.executable, str(TOOL), mode, "--root", str(self.root), *extra],
                              capture_output=True, text=True)

    def write_doc(self, marker_attributes, body=""):
        self.doc.write_text(f"Text before.\n\n<!-- table {marker_attributes} -->\n{body}<!-- /table -->\n\nText after.\n")
        (self.root / "README.md").write_text("# readme\n")

    def test_a_written_table_is_the_artefacts_and_passes_the_check(self):
        self.write_doc('from="results/exp/ade.md" section="## model b" columns="mix,acc" code="model"')
        self.assertEqual(self.run_tool("--write").returncode, 0)
        text = self.doc.read_text()
        self.assertIn(f"made by vsd-sumo 0.1.0+{self.commit}: `vsd-sumo experiment x.yaml`", text)
        self.assertIn("| mix | acc |\n|---|---|\n| acc 2000 | 0.15 |\n<!-- /table -->", text)
        self.assertTrue(text.startswith("Text before.") and text.endswith("Text after.\n"))
        self.assertEqual(self.run_tool("--check").returncode, 0)

    def test_a_table_edited_by_hand_fails_the_check(self):
        self.write_doc('from="results/exp/ade.md" section="## model a" columns="row,acc" code="model"')
        self.run_tool("--write")
        self.doc.write_text(self.doc.read_text().replace("| 2 | 6.97 |", "| 2 | 6.90 |"))
        result = self.run_tool("--check")
        self.assertEqual(result.returncode, 1)
        self.assertIn("docs/results.md:3: the table differs from what results/exp/ade.md generates", result.stderr)

    def test_a_marker_mentioned_in_running_text_is_not_one(self):
        # The explanation of the markers quotes one inline (with a stale="..." in the same
        # paragraph); it must not swallow the real marker below it and its attributes.
        self.doc.write_text('A table sits between `<!-- table from="results/..." -->` and `<!-- /table -->`, '
                            'unless stale="why".\n\n<!-- table from="results/exp/ade.md" section="## model b" '
                            'columns="mix,acc" code="model" -->\n<!-- /table -->\n')
        (self.root / "README.md").write_text("# readme\n")
        self.assertEqual(self.run_tool("--write").returncode, 0)
        self.assertEqual(self.run_tool("--check").returncode, 0)
        text = self.doc.read_text()
        self.assertTrue(text.startswith("A table sits between `<!-- table from=\"results/...\" -->` and"))
        self.assertIn("| mix | acc |\n|---|---|\n| acc 2000 | 0.15 |\n<!-- /table -->", text)

    def test_csv_columns_are_formatted_and_filtered(self):
        self.write_doc('from="results/exp/ade.csv" columns="row,ade_m:.2f" where="label=acc" code="model"')
        self.assertEqual(self.run_tool("--write").returncode, 0)
        self.assertIn("| row | ade_m |\n|---|---|\n| 1 | 0.26 |\n| 2 | 6.97 |\n", self.doc.read_text())

    def test_an_artefact_older_than_its_code_fails_unless_the_doc_says_why(self):
        self.write_doc('from="results/exp/ade.md" section="## model a" columns="row,acc" code="model"')
        self.run_tool("--write")
        (self.root / "src" / "model" / "a.cpp").write_text("int a = 1;\n")
        git(self.root, "commit", "-qam", "model changed")
        result = self.run_tool("--check")
        self.assertEqual(result.returncode, 1)
        self.assertIn(f"was made at {self.commit}, and the code it describes has changed since (model)", result.stderr)

        self.write_doc('from="results/exp/ade.md" section="## model a" columns="row,acc" code="model" '
                       'stale="kept until the re-run"')
        self.assertEqual(self.run_tool("--write").returncode, 0)
        self.assertIn("**Out of date:** model changed since; kept until the re-run.", self.doc.read_text())
        self.assertEqual(self.run_tool("--check").returncode, 0)

    def test_stale_on_a_current_artefact_and_bad_markers_are_refused(self):
        self.write_doc('from="results/exp/ade.md" columns="row" code="model" stale="old"')
        self.assertIn("stale=\"...\" but none of model changed", self.run_tool("--check").stderr)
        self.write_doc('from="results/exp/ade.md" columns="nope" code="model"')
        self.assertIn("has no column 'nope'", self.run_tool("--check").stderr)
        self.write_doc('from="results/exp/ade.md" columns="row" code="nomodule"')
        self.assertIn("names 'nomodule', which is no module", self.run_tool("--check").stderr)
        self.write_doc('from="results/exp/missing.md" columns="row" code="model"')
        self.assertIn("the artefact results/exp/missing.md does not exist", self.run_tool("--check").stderr)
        (self.root / "results" / "exp" / "manifest.json").write_text(
            json.dumps({"tool_version": f"0.1.0+{self.commit}-dirty", "command_line": "x"}))
        self.write_doc('from="results/exp/ade.md" columns="row" code="model"')
        self.assertIn("not by a build of a clean commit", self.run_tool("--check").stderr)


if __name__ == "__main__":
    unittest.main()
