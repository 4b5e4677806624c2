#!/usr/bin/python3
"""Every number in paper/REPORT.md is generated, quoted or defined, and the generated files are
current. paper/REPORT.md is `scripts/make_report.py report`'s output from paper/REPORT.src.md; in
the source a measured number is markup ({{cell ...}}, {{ratio ...}}, {{bench ...}}), a number quoted
from the paper is {{paper ...}} and a setting or definition {{def ...}}. This test fails when

- paper/REPORT.md or paper/performance.md differs from what the script generates today (a table
  under results/ changed, or someone edited the output by hand);
- the source's literal text (what is copied to the output as written) holds a number that is
  none of those: not an identifier (`L2`, `float32`), a citation ("Fig. 5", "Table 2", "§4.6"),
  an ISO date, a commit hash, nor inside inline code or a link target;
- and, on a temporary copy of results/ and paper/, changing one referenced table cell makes
  `make_report.py report --check` fail, and regenerating makes it pass again.

Passages in {{unconverted}} ... {{/unconverted}} are not generated yet (the output shows a note over
each): their numbers are listed and fail the test, unless --allow-unconverted is given (for work
in progress, never in ctest).

  /usr/bin/python3 tests/scripts/test_report_numbers.py [--allow-unconverted] [--tmp DIR]
"""
import json
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import script_test

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
SCRIPT = REPO / "scripts" / "make_report.py"
sys.path.insert(0, str(REPO / "scripts"))
import make_report  # noqa: E402

ARGS = None
# A number as prose writes it: 1,500 / 0.0692 / 8.32e-05 / 2.3e5 / −0.1.
NUMBER = re.compile(r"(?<![\d.,])[−-]?\d+(?:,\d{3})*(?:\.\d+)?(?:[eE][-+]?\d+)?")
CITATION = re.compile(r"(?:\b(?:Figs?\.|Tables?|Eqs?\.|Sections?|issues?|Issue|commits?|stages?|generation|et al\.,?)|§)\s*"
                      r"\d+(?:\.\d+)*(?:\s*(?:–|-|,|and|/)\s*\d+(?:\.\d+)*)*")
DATE = re.compile(r"\b\d{4}-\d{2}-\d{2}\b")
HASH = re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b")
CODE = re.compile(r"`[^`\n]*`")
LINK_TARGET = re.compile(r"\]\([^)\s]*\)")
SHORT_MARKUP = 40  # a {{paper}} or {{def}} wraps a number and its unit, not a sentence


def mask(pattern, text):
    return pattern.sub(lambda m: " " * len(m.group(0)), text)


def bare_numbers(text):
    """The numbers of literal Markdown text that are not identifiers, citations, dates, commit
    hashes, inline code or link targets, as (offset, number)."""
    text = mask(CODE, text)
    text = mask(LINK_TARGET, text)
    text = mask(DATE, text)
    text = mask(HASH, text)
    text = mask(CITATION, text)
    found = []
    for m in NUMBER.finditer(text):
        before = text[m.start() - 1] if m.start() else " "
        after = text[m.end()] if m.end() < len(text) else " "
        if before.isalpha() or before == "_" or after.isalpha() or after == "_":
            continue  # part of a name: L2, float32, x86_64, 10th, p_t
        found.append((m.start(), m.group(0)))
    return found


def literal_numbers(segments, kind):
    """(line, number, context) for every bare number in the source's literal text of `kind`."""
    out = []
    for seg_kind, text, _, line in segments:
        if seg_kind != kind:
            continue
        for offset, number in bare_numbers(text):
            at = line + text.count("\n", 0, offset)
            start = text.rfind("\n", 0, offset) + 1
            end = text.find("\n", offset)
            context = text[start:end if end >= 0 else len(text)].strip()
            out.append((at, number, context[:100]))
    return out


def run(*argv):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, argv)], capture_output=True, text=True)


class BareNumbers(unittest.TestCase):
    """The detector itself: what counts as a number that needs markup."""

    def test_measurements_are_found(self):
        found = [n for _, n in bare_numbers("test RMSE 0.0402 against 1.9e5, 17× slower, 3/3 seeds, 1,500 frames")]
        self.assertEqual(found, ["0.0402", "1.9e5", "17", "3", "3", "1,500"])

    def test_names_citations_dates_and_code_are_not(self):
        text = ("Fig. 5 and Figs. 10–11, Table 2, §4.6, issue 39, supervised L2, float32, the 10th "
                "frame, 2026-12-03, commit d720926, `ours_2000_epochs`, [v](../results/x_1.mp4)")
        self.assertEqual(bare_numbers(text), [])


TINY_TABLE = """## Methods on tiny

| method        | configuration      | window               |                 stable (blow-up) |            mean RMSE |
|:--------------|:-------------------|:---------------------|---------------------------------:|---------------------:|
| ours          | self_supervised    | train (frames 2-9)   | 90 [80, 100] (1/3 diverged, earliest @80) |  0.5 [0.25, 1] |
| ours          | self_supervised    | test (frames >= 10)  | 90 [80, 100] (1/3 diverged, earliest @80) | 0.04 [0.02, 0.08] (1/3 diverged, earliest @80) |
| supervised_l2 | supervised_l2      | test (frames >= 10)  |                      diverged @7 |  0.2 (diverged @7) |
| ours_wide     | ours wide          | test (frames >= 10)  |                        100 / 100 |               0.0125 |
"""
TINY_BENCH = {"context": {"date": "2026-12-05T01:00:00+00:00", "num_cpus": 2},
              "benchmarks": [
                  {"name": "fam/a", "run_name": "fam/a", "run_type": "iteration", "real_time": 2000.0,
                   "cpu_time": 1000.0, "time_unit": "us"},
                  {"name": "fam/b", "run_name": "fam/b", "run_type": "iteration", "real_time": 0.0,
                   "cpu_time": 0.0, "time_unit": "ms", "error_occurred": True, "error_message": "no mesh"}]}


class Markup(unittest.TestCase):
    """Each kind of markup on a tiny table and benchmark file."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(dir=ARGS.tmp)
        self.root = pathlib.Path(self.tmp.name)
        (self.root / "results" / "tiny" / "tables").mkdir(parents=True)
        (self.root / "results" / "tiny" / "tables" / "methods_tiny.md").write_text(TINY_TABLE, encoding="utf-8")
        (self.root / "results" / "bench").mkdir()
        (self.root / "results" / "bench" / "2026-12-05-abc1234.json").write_text(json.dumps(TINY_BENCH), encoding="utf-8")

    def tearDown(self):
        self.tmp.cleanup()

    def expand(self, source):
        return "".join(s[2] for s in make_report.segments(source, str(self.root)))

    def test_cells_and_parts(self):
        t = 'tiny/methods_tiny row="ours|test" col="mean RMSE"'
        self.assertEqual(self.expand("{{cell %s}}" % t), "0.04 [0.02, 0.08] (1/3 diverged, earliest @80)")
        self.assertEqual(self.expand("{{cell %s part=value}}" % t), "0.04")
        self.assertEqual(self.expand("{{cell %s part=range}}" % t), "[0.02, 0.08]")
        self.assertEqual(self.expand("{{cell %s part=max}}" % t), "0.08")
        self.assertEqual(self.expand("{{cell %s part=note}}" % t), "1/3 diverged, earliest @80")
        self.assertEqual(self.expand('{{table tiny/methods_tiny}}{{cell row="supervised_l2|test" col="stable (blow-up)" part=value}}'), "7")
        # "ours" is not the start of "ours_wide", and a bare "ours" matches two windows.
        self.assertEqual(self.expand('{{cell tiny/methods_tiny row="ours_wide" col="mean RMSE"}}'), "0.0125")
        with self.assertRaisesRegex(make_report.ReportError, "matches 2 rows"):
            self.expand('{{cell tiny/methods_tiny row="ours" col="mean RMSE"}}')
        with self.assertRaisesRegex(make_report.ReportError, "no column 'median RMSE'"):
            self.expand('{{cell tiny/methods_tiny row="ours|test" col="median RMSE"}}')
        with self.assertRaisesRegex(make_report.ReportError, "REPORT.src.md:2: .*no row matching 'linear_pca"):
            self.expand('\n{{cell tiny/methods_tiny row="linear_pca|test" col="mean RMSE"}}')

    def test_derived_numbers(self):
        a = '[tiny/methods_tiny row="ours|train" col="mean RMSE"]'
        b = '[tiny/methods_tiny row="ours|test" col="mean RMSE"]'
        self.assertEqual(self.expand("{{ratio %s %s digits=2}}" % (a, b)), "12")
        self.assertEqual(self.expand("{{orders %s %s digits=2}}" % (a, b)), "1.10")
        self.assertEqual(self.expand("{{sum %s %s digits=3}}" % (a, b)), "0.54")

    def test_quotes_definitions_and_benchmarks(self):
        self.assertEqual(self.expand("{{paper 136.8}} and {{def 10,000}}"), "136.8 and 10,000")
        self.assertEqual(self.expand("{{bench latest fam/a unit=ms}}"), "2")
        self.assertEqual(self.expand("{{bench 2026-12-05-abc1234.json fam/a field=cpu_time}}"), "1e+03")
        self.assertEqual(self.expand("{{benchfile latest}}"), "results/bench/2026-12-05-abc1234.json")
        with self.assertRaisesRegex(make_report.ReportError, "did not run: no mesh"):
            self.expand("{{bench latest fam/b}}")
        text = make_report.render_performance(str(self.root))
        self.assertIn("commit: abc1234", text)
        self.assertIn("| `fam/a` | 2000 | 1000 | us | 1 |", text)
        self.assertIn("did not run: no mesh", text)

    def test_table1_sets_the_step_and_the_networks_beside_the_paper(self):
        bench = {"context": {"date": "2026-12-07T00:00:00+00:00"}, "benchmarks": [
            {"name": "sim_step/cloth/min_time:3.000", "run_name": "sim_step/cloth/min_time:3.000",
             "run_type": "iteration", "real_time": 9.415, "cpu_time": 9.0, "time_unit": "ms", "dofs": 576},
            {"name": "nn/frame/float/cloth", "run_name": "nn/frame/float/cloth", "run_type": "iteration",
             "real_time": 34.0, "cpu_time": 34.0, "time_unit": "us"},
            {"name": "sim_step/armadillo", "run_name": "sim_step/armadillo", "run_type": "iteration",
             "real_time": 0, "cpu_time": 0, "time_unit": "ms", "error_occurred": True,
             "error_message": "/home/x/data/meshes/armadillo.1.node does not exist"}]}
        (self.root / "results" / "bench" / "2026-12-07-def5678.json").write_text(json.dumps(bench), encoding="utf-8")
        text = make_report.render_performance(str(self.root))
        # 18.83 ms / 9.415 ms = 2.00; 0.272 ms / 0.034 ms = 8.00
        self.assertIn("| Cloth (`cloth`) | 576 | 576 | 9.415 | 18.83 | 2× | not in this file | 0.109 | "
                      "not in this file | 0.163 | 0.034 | 0.272 | 8× |", text)
        self.assertIn("| Armadillo (`armadillo`) | – | 10,020 | did not run: armadillo.1.node does not exist |", text)
        self.assertNotIn("/home/x", text)
        # the file without any Table 1 benchmark gets no such table
        self.assertEqual(text.count("### Table 1 beside the paper's"), 1)

    def test_bad_benchmark_file_names_it_and_writes_nothing(self):
        (self.root / "results" / "bench" / "broken.json").write_text("{not json", encoding="utf-8")
        p = run("--root", self.root, "performance")
        self.assertEqual(p.returncode, 1)
        self.assertIn("broken.json is not JSON", p.stderr)
        self.assertFalse((self.root / "paper" / "performance.md").exists())


class ReportNumbers(unittest.TestCase):
    def setUp(self):
        source = (REPO / "paper" / "REPORT.src.md").read_text(encoding="utf-8")
        try:
            self.segments = make_report.segments(source, str(REPO))
        except make_report.ReportError as e:
            self.fail(str(e))

    def test_report_is_generated_from_its_source(self):
        p = run("report", "--check")
        self.assertEqual(p.returncode, 0, p.stderr + p.stdout)

    def test_performance_is_generated_from_the_benchmark_files(self):
        p = run("performance", "--check")
        self.assertEqual(p.returncode, 0, p.stderr + p.stdout)

    def test_every_number_is_a_reference_a_quotation_or_a_definition(self):
        bare = literal_numbers(self.segments, "text")
        listing = "\n".join(f"  paper/REPORT.src.md:{line}: {number!r} in: {context}" for line, number, context in bare)
        self.assertEqual(bare, [], f"{len(bare)} numbers are neither references nor marked {{{{paper}}}} "
                                   f"or {{{{def}}}}:\n{listing}")

    def test_quotations_and_definitions_are_short(self):
        for kind, text, _, line in self.segments:
            if kind in ("paper", "def"):
                self.assertLessEqual(len(text) - len(kind) - 5, SHORT_MARKUP,
                                     f"paper/REPORT.src.md:{line}: {text} wraps more than a number and its unit")
                self.assertTrue(re.search(r"\d", text), f"paper/REPORT.src.md:{line}: {text} holds no number")

    def test_unconverted_passages(self):
        pending = literal_numbers(self.segments, "unconverted")
        regions = sum(1 for s in self.segments if s[0] == "unconverted" and s[1].startswith("{{"))
        if pending:
            lines = sorted({line for line, _, _ in pending})
            print(f"NOT YET GENERATED: {len(pending)} numbers in {regions} {{{{unconverted}}}} passages of "
                  f"paper/REPORT.src.md (lines {lines[0]}–{lines[-1]}); the output marks each passage",
                  file=sys.stderr)
        if not ARGS.allow_unconverted:
            self.assertEqual(pending, [], "{{unconverted}} passages remain (--allow-unconverted lists them only)")


class StaleTable(unittest.TestCase):
    """On a copy of results/ (the Markdown tables, benchmark files and pages) and paper/: editing a cell
    that the report references makes the check fail; regenerating makes it pass."""

    def test_changed_cell_fails_then_regeneration_passes(self):
        with tempfile.TemporaryDirectory(dir=ARGS.tmp) as tmp:
            root = pathlib.Path(tmp)
            for path in (REPO / "results").rglob("*"):
                if path.suffix in (".md", ".json", ".html") and path.is_file():  # pages: the links
                    dst = root / path.relative_to(REPO)
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(path, dst)
            shutil.copytree(REPO / "paper", root / "paper")
            self.assertEqual(run("--root", root, "report", "--check").returncode, 0)

            # The first {{cell}} of the source: find its cell in the copy and change its text.
            source = (root / "paper" / "REPORT.src.md").read_text(encoding="utf-8")
            m = re.search(r"\{\{cell\s+([\w.-]+/[\w.-]+)(\s.*?)\}\}", source, re.S)
            self.assertIsNotNone(m, "the source has no {{cell}} reference")
            words, options = make_report.parse_args(m.group(1) + m.group(2), "test")
            table = pathlib.Path(make_report.table_path(str(root), words[0][1]))
            old = make_report.Tables(str(root)).cell(words[0][1], options["row"], options["col"])
            new = "9" + old if not old.startswith("9") else "8" + old[1:]
            lines = table.read_text(encoding="utf-8").splitlines(keepends=True)
            changed = 0
            for i, line in enumerate(lines):
                cells = make_report.split_row(line) if line.lstrip().startswith("|") else []
                if old in cells and all(any(make_report.cell_matches(p.strip(), c) for c in cells)
                                        for p in options["row"].split("|")):
                    lines[i] = line.replace(f" {old} ", f" {new} ", 1)
                    changed += 1
            self.assertEqual(changed, 1, f"could not change {old!r} in {table}")
            table.write_text("".join(lines), encoding="utf-8")

            p = run("--root", root, "report", "--check")
            self.assertEqual(p.returncode, 1, "a changed table cell must make the check fail")
            self.assertIn("REPORT.md", p.stderr)
            self.assertEqual(run("--root", root, "report").returncode, 0)
            self.assertIn(new, (root / "paper" / "REPORT.md").read_text(encoding="utf-8"))
            p = run("--root", root, "report", "--check")
            self.assertEqual(p.returncode, 0, p.stderr)

    def test_bad_reference_names_the_source_line(self):
        with tempfile.TemporaryDirectory(dir=ARGS.tmp) as tmp:
            root = pathlib.Path(tmp)
            (root / "paper").mkdir()
            (root / "paper" / "REPORT.src.md").write_text(
                "line one\nRMSE {{cell paper_cloth/methods_cloth row=\"ours|test\" col=\"mean RMSE\"}}\n", encoding="utf-8")
            p = run("--root", root, "report")
            self.assertEqual(p.returncode, 1)
            self.assertIn("REPORT.src.md:2", p.stderr)
            self.assertIn("paper_cloth/tables/methods_cloth.md", p.stderr)
            self.assertFalse((root / "paper" / "REPORT.md").exists(), "no half-written output")


def main():
    global ARGS
    ARGS, rest = script_test.arguments(
        description=__doc__.splitlines()[0], required=False,
        extra=lambda parser: parser.add_argument(
            "--allow-unconverted", action="store_true",
            help="list the numbers of {{unconverted}} passages instead of failing"))
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
