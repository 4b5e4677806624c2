"""The PyTorch example integrator (experiments/examples/python_integrator/torch_mlp.py): an MLP
trained in PyTorch on latentbench's potential, run through its suite beside ours. Skipped, with
the reason, where python3-torch is not installed (torch is not a latentbench dependency)."""
import csv
import math

import pytest

from conftest import REPO, run_cli

torch = pytest.importorskip("torch", reason="python3-torch is not installed: the PyTorch example is skipped "
                                            "(torch is optional; apt-get install python3-torch to run it)")

SUITE = REPO / "experiments" / "examples" / "python_integrator" / "suite_torch.toml"


def test_torch_example_runs_through_its_suite(tmp_path):
    run_cli("-q", "-j", "1", "run", SUITE, "-o", tmp_path / "run")
    with open(tmp_path / "run" / "tables" / "methods_cloth_small.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    by_method = {}
    for r in rows:
        by_method.setdefault(r["method"], []).append(r)
    assert set(by_method) == {"ours", "linear_map", "torch_mlp", "full_space"}, set(by_method)
    for r in by_method["torch_mlp"]:
        assert r["n_seeds"] == "1"
        assert math.isfinite(float(r["mean_rmse_median"])), r
