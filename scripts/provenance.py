#!/usr/bin/python3
"""Provenance of the published results (results/<suite>/provenance.json) and their reproduction.

  provenance.py check                 every results/<suite>/ folder: provenance.json present, its commit in
                                      this repository's history, its suite file in experiments/ and unchanged
                                      since publication (content hash). Lists each problem; exit 1 if any.
  provenance.py reproduce SUITE [--cli PATH] [--out DIR]
                                      rerun results/SUITE's suite file into runs/reproduce/SUITE (or DIR) with
                                      `latentbench run`, then compare every CSV table with results/SUITE/tables,
                                      timing columns excluded (scripts/compare_tables.py): prints what moved;
                                      exit 0 if nothing did, 1 otherwise.
  provenance.py retrofit SUITE...     write provenance.json for folders published before `latentbench run` wrote
                                      one: the commit is the publication commit (the one that added the folder's
                                      methods tables), the suite hash that of the suite file at that commit; the
                                      binary's commit, the command and the thread count are marked unrecorded.
                                      Also adds n_seeds, n_diverged and diverged_at to legacy methods_*.csv from
                                      the Markdown twin's 'stable (blow-up)' cells.

A suite file's hash is "fnv1a64:<16 hex>" of its bytes (as latentbench records it). Run with /usr/bin/python3.
"""
import csv
import io
import json
import os
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
RESULTS = ROOT / "results"
NOT_SUITES = {"bench"}  # results/bench holds benchmark JSON, not a suite


def fail(message):
    print(f"provenance.py: error: {message}", file=sys.stderr)
    sys.exit(1)


def fnv1a64(data):
    h = 1469598103934665603  # latentbench's offset basis (core/hash.hpp), not the textbook one
    for b in data:
        h ^= b
        h = (h * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"fnv1a64:{h:016x}"


def git(*args):
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True)


def suite_folders():
    return sorted(p for p in RESULTS.iterdir() if p.is_dir() and p.name not in NOT_SUITES)


def suite_name(folder):
    """The suite's `name` in the published experiment.toml (the folder name if none)."""
    toml = folder / "experiment.toml"
    if toml.exists():
        m = re.search(r"^name\s*=\s*['\"]([^'\"]+)['\"]", toml.read_text(), re.M)
        if m:
            return m.group(1)
    return folder.name


def check():
    problems = []
    folders = suite_folders()
    for folder in folders:
        where = f"results/{folder.name}"
        path = folder / "provenance.json"
        if not path.exists():
            problems.append(f"{where}: no provenance.json")
            continue
        try:
            prov = json.loads(path.read_text())
        except json.JSONDecodeError as e:
            problems.append(f"{where}/provenance.json: not JSON ({e})")
            continue
        commit = prov.get("commit", "")
        if git("cat-file", "-e", f"{commit}^{{commit}}").returncode != 0:
            problems.append(f"{where}: commit {commit!r} is not in this repository's history")
        suite_file = prov.get("suite_file", "")
        if not suite_file or not (ROOT / suite_file).is_file():
            problems.append(f"{where}: suite file {suite_file!r} does not exist")
            continue
        now = fnv1a64((ROOT / suite_file).read_bytes())
        if now != prov.get("suite_hash"):
            problems.append(f"{where}: {suite_file} changed since publication ({prov.get('suite_hash')} -> {now}); "
                            f"`scripts/run reproduce {folder.name}` shows what moves")
        text = path.read_text()
        if "/work/" in text or "/home/" in text or "/root/" in text:
            problems.append(f"{where}/provenance.json: holds an absolute path")
    for p in problems:
        print(p)
    print(f"{len(folders)} published suites checked, {len(problems)} problems")
    return 1 if problems else 0


def reproduce(name, cli, out):
    folder = RESULTS / name
    prov_path = folder / "provenance.json"
    if not prov_path.exists():
        fail(f"results/{name}/provenance.json: missing (not a published suite?)")
    prov = json.loads(prov_path.read_text())
    suite_file = ROOT / prov["suite_file"]
    if not suite_file.is_file():
        fail(f"results/{name}: suite file {prov['suite_file']} does not exist")
    out = pathlib.Path(out) if out else ROOT / "runs" / "reproduce" / name
    if fnv1a64(suite_file.read_bytes()) != prov.get("suite_hash"):
        print(f"note: {prov['suite_file']} changed since publication: differences may come from the suite file")
    # A subset run (`--scene`, `--integrator`) is reproduced as the same subset.
    subset, command = [], prov.get("command") or []
    for k, arg in enumerate(command[:-1]):
        if arg in ("--scene", "--integrator"):
            subset += [arg, command[k + 1]]
    if not command and (folder / "experiment.toml").exists() and \
            (folder / "experiment.toml").read_text().startswith("# subset run"):
        print(f"note: results/{name} was a subset run whose command was not recorded: the whole suite is rerun")
    print(f"reproducing results/{name}: {cli} run {prov['suite_file']} -o {out} {' '.join(subset)}", flush=True)
    rc = subprocess.run([cli, "run", str(suite_file), "-o", str(out), *subset]).returncode
    if rc != 0:
        fail(f"`latentbench run` exited {rc}; nothing compared")
    compare = subprocess.run(["/usr/bin/python3", str(ROOT / "scripts" / "compare_tables.py"), str(folder / "tables"),
                              str(out / "tables")], capture_output=True, text=True)
    sys.stdout.write(compare.stdout)
    sys.stderr.write(compare.stderr)
    print(f"results/{name}: {'nothing moved' if compare.returncode == 0 else 'tables moved (listed above)'}")
    return compare.returncode


STABLE = "stable (blow-up)"


def retrofit_methods_csv(csv_path, md_path):
    """Add n_seeds, n_diverged, diverged_at (from the Markdown's stable cells) to a legacy CSV."""
    text = csv_path.read_text()
    comments = [l for l in text.splitlines() if l.startswith("#")]
    body = [l for l in text.splitlines() if not l.startswith("#")]
    rows = list(csv.reader(body))
    header = rows[0]
    if "n_seeds" in header:
        return False
    md_rows = []
    for line in md_path.read_text().splitlines():
        if line.startswith("|") and not set(line) <= set("|-: "):
            md_rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    md_header, md_body = md_rows[0], md_rows[1:]
    if STABLE not in md_header or len(md_body) != len(rows) - 1:
        raise SystemExit(f"{md_path}: cannot pair its rows with {csv_path.name}")
    seeds_in_caption = re.search(r"\((\d+) seeds\)", md_path.read_text())
    seeds = int(seeds_in_caption.group(1)) if seeds_in_caption else 1
    s = md_header.index(STABLE)
    window = header.index("window")
    out_rows = [header[:window + 1] + ["n_seeds", "n_diverged", "diverged_at"] + header[window + 1:]]
    for row, md in zip(rows[1:], md_body):
        cell = md[s]
        m = re.search(r"\((\d+)/(\d+) diverged, earliest @(\d+)\)", cell)
        if m:
            k, n, at = int(m.group(1)), int(m.group(2)), m.group(3)
        elif cell.startswith("diverged @"):
            k, n, at = 1, 1, re.match(r"diverged @(\d+)", cell).group(1)
        else:
            n = seeds if "[" in cell or "±" in cell else 1
            k, at = 0, "nan"
        out_rows.append(row[:window + 1] + [str(n), str(k), at] + row[window + 1:])
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(out_rows)
    note = ("# n_seeds, n_diverged and diverged_at were added on 2026-12-05 by scripts/provenance.py retrofit from "
            "the Markdown twin's 'stable (blow-up)' cells (this folder predates them); every other cell is as "
            "published: one value per metric (the Markdown cell's centre), errors aggregated before the blow-up.")
    csv_path.write_text("\n".join(comments + [note]) + "\n" + buf.getvalue())
    return True


def retrofit(names):
    for name in names:
        folder = RESULTS / name
        if not folder.is_dir():
            fail(f"results/{name}: no such folder")
        tables = folder / "tables" if (folder / "tables").is_dir() else folder
        added = git("log", "--diff-filter=A", "--format=%H", "--", f"results/{name}").stdout.split()
        if not added:
            fail(f"results/{name}: not in git history (commit it first)")
        commit = added[-1]
        # The commit that last changed the methods tables' numbers: the latest commit touching them.
        last = git("log", "-1", "--format=%H", "--", f"results/{name}/tables/methods_*.md", f"results/{name}/methods_*.md")
        commit = last.stdout.strip() or commit
        suite = suite_name(folder)
        # The folder's own suite file if there is one (a subset run is named after its folder),
        # else the one its experiment.toml names (stability_baseline: stability).
        suite_file = f"experiments/{name}.toml" if (ROOT / "experiments" / f"{name}.toml").exists() else \
            f"experiments/{suite}.toml"
        if not (ROOT / suite_file).exists():
            fail(f"results/{name}: no suite file (tried experiments/{name}.toml and {suite_file})")
        old = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:{suite_file}"], capture_output=True)
        suite_hash = fnv1a64(old.stdout) if old.returncode == 0 else None
        seeds = re.search(r"^seeds\s*=\s*\[([^\]]*)\]", (folder / "experiment.toml").read_text(), re.M) \
            if (folder / "experiment.toml").exists() else None
        prov = {
            "format": "latentbench.provenance/1",
            "suite": pathlib.Path(suite_file).stem,
            "suite_file": suite_file,
            "suite_hash": suite_hash,
            "commit": commit,
            "commit_kind": "publication: the commit that last changed this folder's methods tables; the binary's "
                           "commit was not recorded before 2026-12-05",
            "dirty": None,
            "seeds": [int(x) for x in seeds.group(1).split(",") if x.strip()] if seeds else [],
            "threads": None,
            "fit_versions": None,
            "command": None,
            "retrofitted": "2026-12-05 by scripts/provenance.py retrofit",
        }
        if suite_hash is None:
            # The suite file was written after publication (from the published experiment.toml):
            # its hash today is the reference from now on.
            prov["suite_hash"] = fnv1a64((ROOT / suite_file).read_bytes())
            prov["suite_hash_note"] = (f"{suite_file} did not exist at the publication commit; it was written on "
                                       "2026-12-05 from the published experiment.toml, and this is its hash then")
        (folder / "provenance.json").write_text(json.dumps(prov, indent=2) + "\n")
        converted = 0
        for csv_path in sorted(tables.glob("methods_*.csv")) + sorted(tables.glob("ablation_*.csv")):
            md = csv_path.with_suffix(".md")
            if md.exists() and retrofit_methods_csv(csv_path, md):
                converted += 1
        print(f"results/{name}: provenance.json (commit {commit[:12]}), {converted} CSV tables gained seed counts")


def main(argv):
    if len(argv) >= 1 and argv[0] == "check" and len(argv) == 1:
        return check()
    if len(argv) >= 2 and argv[0] == "reproduce":
        cli, out, name = str(ROOT / "build" / "latentbench"), None, None
        rest = argv[1:]
        while rest:
            a = rest.pop(0)
            if a == "--cli" and rest:
                cli = rest.pop(0)
            elif a == "--out" and rest:
                out = rest.pop(0)
            elif name is None and not a.startswith("-"):
                name = a
            else:
                fail(f"reproduce: unexpected argument {a!r}")
        if name is None:
            fail("reproduce: which published suite? (a folder name under results/)")
        return reproduce(name, cli, out)
    if len(argv) >= 2 and argv[0] == "retrofit":
        retrofit(argv[1:])
        return 0
    print(__doc__.strip())
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
