#!/usr/bin/python3
"""Compare two latentbench table directories (the CSV files of `tables/`).

usage: compare_tables.py DIR_A DIR_B

Every CSV file must exist in both with the same header and rows, cell for cell, except
the timing columns (headers containing "(ms)"; in the tidy rollouts_*.csv the fields
ending in "_ms" and timing_threads, the thread count the rollout was timed with) and the '#'
comment lines (caption, notes, provenance with the date). Exits 0 if equal, 1 with every difference otherwise.
"""
import csv
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import training_table  # noqa: E402  (scripts/training_table.py)


def read_table(path, thinned=False):
    """Header and rows; `thinned`: a training table as its published copy keeps it (training_table.py)."""
    text = path.read_text()
    if thinned:
        text = training_table.thin(text)
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    rows = list(csv.reader(lines))
    if not rows:
        raise SystemExit(f"{path}: no header")
    return rows[0], rows[1:]


def is_timing(column):
    return ("(ms)" in column or column.endswith("_ms") or "_ms_" in column or column == "timing_threads"
            or column.endswith("_seconds"))


def compare(dir_a, dir_b):
    a_files = sorted(p.name for p in dir_a.glob("*.csv"))
    b_files = sorted(p.name for p in dir_b.glob("*.csv"))
    problems = []
    if not a_files:
        problems.append(f"{dir_a}: no CSV tables")
    if a_files != b_files:
        problems.append(f"different tables: {a_files} vs {b_files}")
    compared = 0
    for name in sorted(set(a_files) & set(b_files)):
        # A published training table keeps fewer epochs: thin the other one the same way.
        thinned = training_table.is_training_table(name) and any(
            training_table.is_thinned(d.joinpath(name).read_text()) for d in (dir_a, dir_b))
        head_a, rows_a = read_table(dir_a / name, thinned)
        head_b, rows_b = read_table(dir_b / name, thinned)
        if head_a != head_b:
            problems.append(f"{name}: different columns")
            continue
        if len(rows_a) != len(rows_b):
            problems.append(f"{name}: {len(rows_a)} vs {len(rows_b)} rows")
            continue
        for r, (ra, rb) in enumerate(zip(rows_a, rows_b)):
            for c, column in enumerate(head_a):
                if is_timing(column):
                    continue
                compared += 1
                if ra[c] != rb[c]:
                    problems.append(f"{name} row {r + 1} '{column}': {ra[c]!r} vs {rb[c]!r}")
    return problems, compared, len(a_files)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    problems, compared, files = compare(pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]))
    for p in problems:
        print("differs:", p)
    if problems:
        return 1
    print(f"tables equal: {files} CSV files, {compared} cells compared (timing columns excluded)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
