#!/usr/bin/python3
"""Compare a Google Benchmark JSON run with a committed baseline (report only).

    /usr/bin/python3 scripts/compare_bench.py BASELINE.json NOW.json

For every benchmark of either file: the median real time over its repetitions in each,
the ratio now / baseline (and that of the median CPU times: on a shared machine the CPU
time of one-thread code is the steadier of the two), and a verdict on the real times. The verdict uses the repetitions' own spread:
"slower" when every repetition of the run is slower than every repetition of the baseline
(the two [min, max] ranges do not overlap), "faster" the other way round, "within spread"
otherwise; a benchmark in one file only is "new" or "missing". Machines are noisy, so this
reports and exits 0 whatever the ratios; it exits 1 only when a file cannot be read.
`scripts/run bench --compare BASELINE.json` runs the benchmarks with repetitions and calls it.
"""
import json
import statistics
import sys

UNIT_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}


def load(path):
    """{benchmark: [(real, cpu) time per repetition in ns]} and the file's context."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit(f"compare_bench: cannot read {path}: {e}")
    if not isinstance(data, dict) or not isinstance(data.get("benchmarks"), list):
        raise SystemExit(f"compare_bench: {path}: not Google Benchmark JSON (no 'benchmarks' list)")
    times = {}
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration" or b.get("error_occurred"):
            continue  # aggregates (mean, median, stddev) are recomputed from the repetitions
        try:
            name = b.get("run_name", b["name"])
            unit = UNIT_NS[b.get("time_unit", "ns")]
            t = (float(b["real_time"]) * unit, float(b.get("cpu_time", b["real_time"])) * unit)
        except (KeyError, ValueError, TypeError) as e:
            raise SystemExit(f"compare_bench: {path}: malformed benchmark entry {b.get('name', '?')}: {e}")
        times.setdefault(name, []).append(t)
    return times, data.get("context", {})


def pretty(ns):
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{ns / scale:.4g} {unit}"
    return f"{ns:.4g} ns"


def context_line(label, c):
    return (f"{label}: {c.get('host_name', '?')}, {c.get('num_cpus', '?')} CPUs at {c.get('mhz_per_cpu', '?')} MHz, "
            f"{c.get('library_build_type', '?')} benchmark library, {c.get('date', '?')}")


def compare(baseline_path, now_path, out=sys.stdout):
    base, base_ctx = load(baseline_path)
    now, now_ctx = load(now_path)
    rows = []
    counts = {"slower": 0, "faster": 0, "within spread": 0, "new": 0, "missing": 0}
    for name in sorted(set(base) | set(now)):
        b, n = base.get(name), now.get(name)
        if b is None or n is None:
            verdict = "new" if b is None else "missing"
            t = [r for r, _ in (n if b is None else b)]
            rows.append((name, "—" if b is None else pretty(statistics.median(t)),
                         "—" if n is None else pretty(statistics.median(t)), "—", "—", verdict, len(b or []), len(n or [])))
            counts[verdict] += 1
            continue
        b_real, n_real = [r for r, _ in b], [r for r, _ in n]
        ratio = statistics.median(n_real) / statistics.median(b_real)
        cpu_ratio = statistics.median([c for _, c in n]) / statistics.median([c for _, c in b])
        if min(n_real) > max(b_real):
            verdict = "slower"
        elif max(n_real) < min(b_real):
            verdict = "faster"
        else:
            verdict = "within spread"
        counts[verdict] += 1
        rows.append((name, pretty(statistics.median(b_real)), pretty(statistics.median(n_real)), f"{ratio:.3f}",
                     f"{cpu_ratio:.3f}", verdict, len(b), len(n)))
    print(f"# Benchmarks: {now_path} against {baseline_path} (report only)\n", file=out)
    print(f"- {context_line('baseline', base_ctx)}", file=out)
    print(f"- {context_line('now', now_ctx)}\n", file=out)
    print(", ".join(f"{v} {k}" for k, v in counts.items()) + f" ({len(rows)} benchmarks). A slowdown is flagged only "
          "when every repetition of the run is slower than every repetition of the baseline.\n", file=out)
    print("| benchmark | baseline (median) | now (median) | now / baseline | CPU time now / baseline | verdict | "
          "reps (baseline, now) |", file=out)
    print("|---|--:|--:|--:|--:|---|--:|", file=out)
    for name, b, n, ratio, cpu_ratio, verdict, rb, rn in rows:
        flag = f"**{verdict}**" if verdict == "slower" else verdict
        print(f"| {name} | {b} | {n} | {ratio} | {cpu_ratio} | {flag} | {rb}, {rn} |", file=out)
    return counts


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    compare(argv[1], argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
