"""method = "python": a Python class fitted and rolled out by the harness (issue 42, item 5).

The example integrator (experiments/examples/python_integrator/linear_map.py) runs through
`fit`, `rollout` and a whole suite, whose tables and CSVs carry its row; the classes of
bad_integrators.py break the interface and must each get an error naming the class, while
the suite's other methods still finish."""
import csv
import pathlib

import h5py
import numpy as np
import pytest

from conftest import REPO, cli_error_line, run_cli

EXAMPLE = REPO / "experiments" / "examples" / "python_integrator"
HERE = pathlib.Path(__file__).resolve().parent


def python_set(module, cls, path):
    return ["--set", f"module={module}", "--set", f"class={cls}", "--set", f"path={path}"]


def test_example_fits_by_least_squares_and_rolls_out(cloth, tmp_path):
    art = tmp_path / "linear.h5"
    run_cli("-q", "fit", cloth["data"], "--method", "python", "--ae", cloth["ae"],
            *python_set("linear_map", "LinearLatentMap", EXAMPLE), "-o", art)
    with h5py.File(art, "r") as f:
        W = f["python/W"][()]
        assert f.attrs["method"] in ("python", b"python")
    # 2 latents of 3, the small cloth's boundary parameters twice, and a bias.
    assert W.shape[1] == 3 and np.all(np.isfinite(W))
    roll = tmp_path / "roll.h5"
    run_cli("-q", "rollout", cloth["data"], "--integrator", art, "--ae", cloth["ae"], "--sequences", "all", "-o", roll)
    import latentbench
    (r,) = latentbench.load_rollouts(str(roll))
    assert r.positions.shape[0] > 2 and np.all(np.isfinite(r.positions))
    # The same artefact twice: the fit is deterministic, bit for bit.
    again = tmp_path / "again.h5"
    run_cli("-q", "fit", cloth["data"], "--method", "python", "--ae", cloth["ae"],
            *python_set("linear_map", "LinearLatentMap", EXAMPLE), "-o", again)
    with h5py.File(again, "r") as f:
        assert np.array_equal(f["python/W"][()], W)


@pytest.mark.parametrize("cls, expected", [
    ("RaisesInStep", "step (frame 2): ZeroDivisionError: division by zero (at bad_integrators.py:"),
    ("WrongShape", "step (frame 2): returned a latent of shape (5,); the latent has 3 entries"),
    ("ReturnsNaN", "step (frame 2): returned a non-finite latent from finite inputs"),
    ("ExitsTheProcess", "step (frame 2): the Python process exited (status 3) without replying"),
])
def test_a_broken_step_is_an_error_naming_the_class(cloth, tmp_path, cls, expected):
    art = tmp_path / f"{cls}.h5"
    run_cli("-q", "fit", cloth["data"], "--method", "python", "--ae", cloth["ae"],
            *python_set("bad_integrators", cls, HERE), "-o", art)
    roll = tmp_path / f"{cls}_roll.h5"
    line = cli_error_line("-q", "rollout", cloth["data"], "--integrator", art, "--ae", cloth["ae"],
                          "--sequences", "all", "-o", roll)
    assert f"python integrator 'bad_integrators.{cls}'" in line, line
    assert expected in line, line
    assert not roll.exists(), "a failed rollout left a file"


@pytest.mark.parametrize("cls, expected", [
    ("RaisesInFit", "fit: RuntimeError: no training data I like (at bad_integrators.py:"),
    ("NotADict", "fit: TypeError: fit must return a dict of NumPy arrays (got list)"),
    ("NoSuchClass", "init: AttributeError: module 'bad_integrators'"),
])
def test_a_broken_fit_is_an_error_naming_the_class(cloth, tmp_path, cls, expected):
    art = tmp_path / f"{cls}.h5"
    line = cli_error_line("-q", "fit", cloth["data"], "--method", "python", "--ae", cloth["ae"],
                          *python_set("bad_integrators", cls, HERE), "-o", art)
    assert f"python integrator 'bad_integrators.{cls}'" in line, line
    assert expected in line, line
    assert not art.exists(), "a failed fit left an artefact"


SUITE = """
name = "python_methods"
output_dir = "runs/python_methods"
[autoencoder]
hidden = [16, 16]
pca = 6
epochs = 20
[training]
epochs = 20
[[integrators]]
name = "ours"
loss = "self_supervised"
[[integrators]]
name = "linear_map"
method = "python"
module = "linear_map"
class = "LinearLatentMap"
path = "{example}"
[[integrators]]
name = "raises"
method = "python"
module = "bad_integrators"
class = "RaisesInStep"
path = "{here}"
[[integrators]]
name = "bad_fit"
method = "python"
module = "bad_integrators"
class = "RaisesInFit"
path = "{here}"
[[scenes]]
scene = "{cloth}"
variant = "small"
[evaluation]
sequences = "test"
[outputs]
plots = false
diagnose = true
"""


def test_suite_keeps_the_python_row_and_contains_the_failures(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(SUITE.format(example=EXAMPLE, here=HERE, cloth=REPO / "experiments/scenes/cloth.toml"))
    status, _, err = run_cli("-q", "-j", "1", "run", suite, "-o", tmp_path / "run", check=False)
    assert status == 1, err
    assert "3 work unit(s)" in err and "the other methods finished" in err, err
    tables = tmp_path / "run" / "tables"
    with open(tables / "methods_cloth_small.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    methods = {r["method"] for r in rows}
    assert methods == {"ours", "linear_map", "full_space"}, methods
    assert all(r["n_seeds"] == "1" for r in rows)
    md = (tables / "methods_cloth_small.md").read_text()
    assert "FAILED, no row: raises: eval.cloth_small.raises" in md
    assert "bad_integrators.RaisesInStep" in md and "ZeroDivisionError" in md
    assert "FAILED, no row: bad_fit: fit.cloth_small.bad_fit" in md
    failed_notes = [line for line in md.splitlines() if "FAILED" in line]
    assert failed_notes and not any(str(tmp_path) in line for line in failed_notes), failed_notes
    assert "(log: units/eval.cloth_small.raises.log)" in md
    tidy = (tables / "rollouts_cloth_small.csv").read_text()
    assert "linear_map" in tidy and "raises" not in tidy
    # The error decomposition covers the Python row too, and leaves the failed ones out.
    diagnose = (tables / "diagnose_cloth_small.md").read_text()
    assert "| linear_map" in diagnose and "| ours" in diagnose and "raises" not in diagnose
    assert (tmp_path / "run" / "index.html").exists()


def test_work_units_then_merge_contain_the_failures_as_a_slurm_array_does(tmp_path):
    """Every unit run on its own (`run --unit ID`, what each Slurm array task runs), then
    `run --merge`: the Python rows that failed are left out, the others merged."""
    import json
    suite = tmp_path / "suite.toml"
    suite.write_text(SUITE.format(example=EXAMPLE, here=HERE, cloth=REPO / "experiments/scenes/cloth.toml"))
    run_dir = tmp_path / "run"
    run_cli("-q", "plan", suite, "-o", run_dir)
    statuses = {}
    for line in (run_dir / "manifest.jsonl").read_text().splitlines():
        unit = json.loads(line)["id"]
        statuses[unit] = run_cli("-q", "-j", "1", "run", suite, "-o", run_dir, "--unit", unit, check=False)[0]
    assert {u for u, s in statuses.items() if s != 0} == {
        "fit.cloth_small.bad_fit", "eval.cloth_small.bad_fit", "eval.cloth_small.raises"}, statuses
    status, _, err = run_cli("-q", "run", suite, "-o", run_dir, "--merge", check=False)
    assert status == 1 and "3 work unit(s)" in err, err
    md = (run_dir / "tables" / "methods_cloth_small.md").read_text()
    assert "| linear_map" in md and "FAILED, no row: bad_fit" in md and "FAILED, no row: raises" in md
