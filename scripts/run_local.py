#!/usr/bin/python3
"""Run a suite's work units on this machine, K at a time, then merge them.

usage: run_local.py SUITE [-o RUN_DIR] [--workers K] [--cli PATH] [--no-merge] [--no-snapshot]

`latentbench run SUITE` runs every unit in order in one process; on a machine with several
cores the units of one level are independent, so this runs them as separate one-thread
processes (`latentbench -q -j 1 run SUITE -o RUN_DIR --unit ID`), each started as soon as
the units it depends on are done, then `latentbench -j K run SUITE -o RUN_DIR --merge`.
The tables are the same as a single-process run's except for timings (the units and the
merge are the commands a Slurm run uses: README, "Running on a cluster").

- Order: scene units first (everything waits on them), then the fits of the slowest
  methods (tan_physics_mlp, fulton_*, the self-supervised ones), then the rest; evals of a
  fitted method become ready when its fit is done.
- Snapshot: the binary is copied to RUN_DIR/.bin/ first, so rebuilding while the suite
  runs does not change the units still to start (--no-snapshot uses it in place).
- Resuming: a unit whose outputs are complete finishes at once as cached, and a killed fit
  resumes from its checkpoint, so running this again continues an interrupted run.
- Failure: a unit that exits non-zero stops new starts; the running ones finish, the last
  lines of its output (RUN_DIR/units/<id>.driver.out) are printed and this exits 1 without
  merging. Ctrl-C stops the
  children and exits 1.
Nothing is run through a shell.
"""
import argparse
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

# Rough relative cost of one fit, by method name prefix (first match): longest first.
COST = [("tan_physics_mlp", 5), ("fulton_cubature", 4), ("fulton", 3), ("ours", 3),
        ("supervised", 1), ("linear_pca", 1), ("full_space", 2)]


def cost(unit):
    kind_rank = {"scene": 100, "fit": 10, "eval": 0}[unit["kind"]]
    method = unit.get("method") or ""
    for prefix, value in COST:
        if method.startswith(prefix):
            return kind_rank + value
    return kind_rank + 2


def fail(message):
    print(f"run_local: {message}", file=sys.stderr)
    sys.exit(1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("suite")
    parser.add_argument("-o", "--output", help="run directory (default: the suite's output_dir)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="units at once, one thread each (default: the number of cores)")
    parser.add_argument("--cli", default=str(pathlib.Path(__file__).resolve().parent.parent
                                             / "build" / "latentbench"))
    parser.add_argument("--no-merge", action="store_true", help="run the units only")
    parser.add_argument("--no-snapshot", action="store_true",
                        help="run the binary in place instead of a copy in RUN_DIR/.bin")
    args = parser.parse_args(argv)
    if args.workers < 1:
        fail(f"--workers must be at least 1 (got {args.workers})")
    cli = pathlib.Path(args.cli)
    if not cli.is_file() or not os.access(cli, os.X_OK):
        fail(f"{cli}: no latentbench binary (build it first: scripts/run build)")
    suite = pathlib.Path(args.suite)
    if not suite.is_file():
        fail(f"{suite}: no such experiment file")

    out_args = ["-o", args.output] if args.output else []
    plan = subprocess.run([str(cli), "plan", str(suite), *out_args], capture_output=True, text=True)
    if plan.returncode != 0:
        sys.stderr.write(plan.stderr)
        fail(f"`latentbench plan {suite}` failed (exit {plan.returncode})")
    sys.stdout.write(plan.stdout)
    manifest = next((line.split(":", 1)[1].strip() for line in plan.stdout.splitlines()
                     if line.startswith("manifest:")), None)
    if manifest is None or not pathlib.Path(manifest).is_file():
        fail("`latentbench plan` printed no manifest it wrote")
    run_dir = pathlib.Path(manifest).parent
    units = [json.loads(line) for line in pathlib.Path(manifest).read_text().splitlines() if line]

    if not args.no_snapshot:
        snapshot = run_dir / ".bin" / "latentbench"
        snapshot.parent.mkdir(parents=True, exist_ok=True)
        partial = snapshot.with_suffix(".partial")
        shutil.copy2(cli, partial)
        os.replace(partial, snapshot)
        cli = snapshot

    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    pending = {u["id"]: u for u in units}
    done, running, failed = set(), {}, []
    started = time.monotonic()
    log_dir = run_dir / "units"
    log_dir.mkdir(parents=True, exist_ok=True)

    def driver_out(unit_id):
        return log_dir / f"{unit_id}.driver.out"

    def stamp():
        return f"[{time.monotonic() - started:7.0f} s]"

    def stop_children(signum, frame):
        for proc, _, _ in running.values():
            proc.terminate()
        for proc, _, _ in running.values():
            proc.wait()
        fail(f"interrupted (signal {signum}); run again to resume")

    signal.signal(signal.SIGINT, stop_children)
    signal.signal(signal.SIGTERM, stop_children)
    total = len(units)
    print(f"{stamp()} {total} units, {args.workers} workers, binary {cli}", flush=True)
    while pending or running:
        if not failed:
            ready = sorted((u for u in pending.values() if all(d in done for d in u["depends_on"])),
                           key=cost, reverse=True)
            for unit in ready[: max(0, args.workers - len(running))]:
                del pending[unit["id"]]
                out = open(driver_out(unit["id"]), "w")
                proc = subprocess.Popen([str(cli), "-q", "-j", "1", "run", str(suite), "-o",
                                         str(run_dir), "--unit", unit["id"]],
                                        stdout=out, stderr=subprocess.STDOUT, env=env)
                running[unit["id"]] = (proc, out, time.monotonic())
                print(f"{stamp()} start  {unit['id']}", flush=True)
        if not running:
            break
        time.sleep(0.5)
        for unit_id, (proc, out, t0) in list(running.items()):
            if proc.poll() is None:
                continue
            out.close()
            del running[unit_id]
            seconds = time.monotonic() - t0
            if proc.returncode == 0:
                done.add(unit_id)
                print(f"{stamp()} done   {unit_id} ({seconds:.0f} s; {len(done)}/{total})", flush=True)
            else:
                failed.append(unit_id)
                print(f"{stamp()} FAILED {unit_id} (exit {proc.returncode} after {seconds:.0f} s; "
                      f"see {driver_out(unit_id)}):", flush=True)
                tail = driver_out(unit_id).read_text(errors="replace").splitlines()[-3:]
                for line in tail:
                    print(f"         {line}", flush=True)
    if failed:
        fail(f"{len(failed)} unit(s) failed: {', '.join(failed)}; {len(pending)} not started; "
             "fix the cause and run again (completed units are cached)")
    if args.no_merge:
        print(f"{stamp()} all {total} units done; merge with: {cli} run {suite} -o {run_dir} --merge")
        return 0
    print(f"{stamp()} merging", flush=True)
    merge = subprocess.run([str(cli), "-j", str(args.workers), "run", str(suite), "-o",
                            str(run_dir), "--merge"])
    if merge.returncode != 0:
        fail(f"merge failed (exit {merge.returncode})")
    print(f"{stamp()} done: {run_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
