#!/usr/bin/python3
"""scripts/run_local.py: a suite's units run two at a time and merged give the same tables
as `latentbench run` in one process (every column but timings); running it again on the
finished run directory does no work; bad arguments and a failing unit exit 1 without
tables. Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_run_local.py --cli build/latentbench --tmp build/tests/tmp
"""
import pathlib
import shutil
import subprocess
import sys
import unittest

import script_test

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
RUN_LOCAL = REPO / "scripts" / "run_local.py"
COMPARE = REPO / "scripts" / "compare_tables.py"
SUITE = REPO / "tests" / "slurm" / "slurm_suite.toml"  # 10 units in 3 levels (ours_long: the requeue test's fit, ~10 s)
ARGS = None


def run(argv, expect=0):
    p = subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=REPO)
    if expect is not None and p.returncode != expect:
        raise AssertionError(f"{' '.join(map(str, argv))} exited {p.returncode}, expected "
                             f"{expect}:\n{p.stdout}\n{p.stderr}")
    return p


class RunLocal(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = pathlib.Path(ARGS.tmp) / "run_local"
        shutil.rmtree(cls.tmp, ignore_errors=True)
        cls.tmp.mkdir(parents=True)

    def test_parallel_units_equal_one_process_and_resume_as_cached(self):
        parallel, serial = self.tmp / "parallel", self.tmp / "serial"
        out = run(["/usr/bin/python3", RUN_LOCAL, SUITE, "-o", parallel, "--workers", "2",
                   "--cli", ARGS.cli]).stdout
        self.assertIn("done   scene.cantilever_small", out)
        self.assertEqual(out.count("done   "), 10, out)
        self.assertTrue((parallel / ".bin" / "latentbench").is_file())
        run([ARGS.cli, "-q", "-j", "1", "run", SUITE, "-o", serial])
        run(["/usr/bin/python3", COMPARE, parallel / "tables", serial / "tables"])
        # Every unit's status file says done; a second run finds them all cached.
        statuses = sorted((parallel / "units").glob("*.status"))
        self.assertEqual(len(statuses), 10)
        for status in statuses:
            self.assertTrue(status.read_text().startswith("done"), status)
        again = run(["/usr/bin/python3", RUN_LOCAL, SUITE, "-o", parallel, "--workers", "2",
                     "--cli", ARGS.cli, "--no-merge"]).stdout
        self.assertIn("all 10 units done", again)

    def test_bad_arguments_exit_1_naming_the_problem(self):
        p = run(["/usr/bin/python3", RUN_LOCAL, self.tmp / "missing.toml", "--cli", ARGS.cli], expect=1)
        self.assertIn("missing.toml: no such experiment file", p.stderr)
        p = run(["/usr/bin/python3", RUN_LOCAL, SUITE, "--cli", self.tmp / "nothing"], expect=1)
        self.assertIn("no latentbench binary", p.stderr)
        p = run(["/usr/bin/python3", RUN_LOCAL, SUITE, "--workers", "0", "--cli", ARGS.cli], expect=1)
        self.assertIn("--workers must be at least 1", p.stderr)
        bad = self.tmp / "bad.toml"
        bad.write_text("name = \"bad\"\n[[integrators]\n")
        p = run(["/usr/bin/python3", RUN_LOCAL, bad, "-o", self.tmp / "bad", "--cli", ARGS.cli], expect=1)
        self.assertIn("bad.toml", p.stderr)

    def test_a_failing_unit_stops_the_run_without_tables(self):
        # The scene unit fails: its mesh output directory is a file, so nothing can be written.
        run_dir = self.tmp / "failing"
        run_dir.mkdir()
        (run_dir / "cantilever_small").write_text("not a directory\n")
        p = run(["/usr/bin/python3", RUN_LOCAL, SUITE, "-o", run_dir, "--workers", "2",
                 "--cli", ARGS.cli], expect=1)
        # The unit's own error (exit 1, the path named) is repeated under the FAILED line.
        self.assertIn("FAILED scene.cantilever_small (exit 1 ", p.stdout)
        self.assertIn("latentbench: error: ", p.stdout)
        self.assertIn(str(run_dir / "cantilever_small"), p.stdout)
        self.assertIn("1 unit(s) failed: scene.cantilever_small; 9 not started", p.stderr)
        self.assertFalse((run_dir / "tables").exists())


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
