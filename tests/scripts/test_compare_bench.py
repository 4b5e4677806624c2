#!/usr/bin/python3
"""scripts/compare_bench.py: every benchmark's ratio against the baseline, a slowdown
flagged only beyond the repetitions' spread, new and missing benchmarks named, exit 0
whatever the ratios (report only), exit 1 on an unreadable file. Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_compare_bench.py --cli build/latentbench --tmp build/tests/tmp
"""
import json
import pathlib
import shutil
import subprocess
import sys
import unittest

import script_test

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
COMPARE = REPO / "scripts" / "compare_bench.py"
ARGS = None


def bench_json(path, times, unit="ms"):
    """Google Benchmark JSON with repetitions: iteration entries plus the aggregates it adds."""
    entries = []
    for name, reps in times.items():
        for i, t in enumerate(reps):
            entries.append({"name": name, "run_name": name, "run_type": "iteration", "repetitions": len(reps),
                            "repetition_index": i, "iterations": 10, "real_time": t, "cpu_time": t,
                            "time_unit": unit})
        entries.append({"name": name + "_mean", "run_name": name, "run_type": "aggregate", "aggregate_name": "mean",
                        "real_time": 1e9, "cpu_time": 1e9, "time_unit": unit})
    path.write_text(json.dumps({"context": {"host_name": "test", "num_cpus": 2}, "benchmarks": entries}))
    return path


def run(*argv):
    return subprocess.run(["/usr/bin/python3", str(COMPARE), *map(str, argv)], capture_output=True, text=True)


class CompareBench(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = pathlib.Path(ARGS.tmp) / "compare_bench"
        shutil.rmtree(cls.tmp, ignore_errors=True)
        cls.tmp.mkdir(parents=True)

    def row(self, out, name):
        lines = [l for l in out.splitlines() if l.startswith(f"| {name} |")]
        self.assertEqual(len(lines), 1, out)
        return [c.strip() for c in lines[0].strip("|").split("|")]

    def test_ratios_and_verdicts(self):
        base = bench_json(self.tmp / "base.json", {
            "steady": [10.0, 10.5, 11.0], "slow": [10.0, 10.2, 10.4], "fast": [10.0, 10.2, 10.4],
            "noisy": [10.0, 14.0, 18.0], "gone": [1.0, 1.0, 1.0]})
        # "slow" in microseconds in the run: units are converted (12,000 us = 12 ms)
        now = bench_json(self.tmp / "now.json", {
            "steady": [10.4, 10.5, 10.6], "fast": [5.0, 5.1, 5.2], "noisy": [15.0, 16.0, 17.0], "added": [2.0, 2.0, 2.0]})
        now_json = json.loads(now.read_text())
        now_json["benchmarks"] += [{"name": "slow", "run_name": "slow", "run_type": "iteration", "real_time": t,
                                    "cpu_time": t, "time_unit": "us"} for t in (12000.0, 12500.0, 13000.0)]
        # waiting on a busy machine: twice the wall-clock time, the same CPU time
        now_json["benchmarks"] += [{"name": "waited", "run_type": "iteration", "real_time": 2.0 * t, "cpu_time": t,
                                    "time_unit": "ms"} for t in (3.0, 3.0, 3.0)]
        base_json = json.loads(base.read_text())
        base_json["benchmarks"] += [{"name": "waited", "run_type": "iteration", "real_time": t, "cpu_time": t,
                                     "time_unit": "ms"} for t in (3.0, 3.0, 3.0)]
        base.write_text(json.dumps(base_json))
        now.write_text(json.dumps(now_json))
        p = run(base, now)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(self.row(p.stdout, "steady")[3:6], ["1.000", "1.000", "within spread"])
        self.assertEqual(self.row(p.stdout, "slow")[1:6], ["10.2 ms", "12.5 ms", "1.225", "1.225", "**slower**"])
        self.assertEqual(self.row(p.stdout, "fast")[3:6], ["0.500", "0.500", "faster"])
        # 16 / 14 = 1.14 slower at the median, but inside the baseline's own spread: not flagged
        self.assertEqual(self.row(p.stdout, "noisy")[3:6], ["1.143", "1.143", "within spread"])
        self.assertEqual(self.row(p.stdout, "gone")[1:6], ["1 ms", "—", "—", "—", "missing"])
        self.assertEqual(self.row(p.stdout, "added")[1:6], ["—", "2 ms", "—", "—", "new"])
        self.assertEqual(self.row(p.stdout, "waited")[3:6], ["2.000", "1.000", "**slower**"])
        self.assertIn("2 slower, 1 faster, 2 within spread, 1 new, 1 missing (7 benchmarks)", p.stdout)
        self.assertNotIn("_mean", p.stdout)  # aggregates are not benchmarks

    def test_unreadable_input_exits_one_naming_the_file(self):
        bad = self.tmp / "bad.json"
        bad.write_text("{not json")
        good = bench_json(self.tmp / "good.json", {"a": [1.0]})
        p = run(good, bad)
        self.assertEqual(p.returncode, 1)
        self.assertIn(str(bad), p.stderr)
        p = run(good, self.tmp / "missing.json")
        self.assertEqual(p.returncode, 1)
        self.assertIn("missing.json", p.stderr)
        other = self.tmp / "other.json"
        other.write_text(json.dumps({"results": []}))
        p = run(other, good)
        self.assertEqual(p.returncode, 1)
        self.assertIn("not Google Benchmark JSON", p.stderr)


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
