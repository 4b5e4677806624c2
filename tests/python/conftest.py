"""Shared fixtures of the Python tests (run by ctest, label python; tests/CMakeLists.txt):
the small cloth simulated and an autoencoder trained by the command line itself, so the
Python side is compared with files it did not write."""
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
CLOTH = REPO / "experiments" / "scenes" / "cloth.toml"
FRAMES = 24  # the small cloth's first frames: every test here stays within seconds


def cli_path():
    path = os.environ.get("LB_CLI")
    if not path:
        pytest.fail("LB_CLI (the latentbench executable) is not set; run these tests through ctest")
    return path


def run_cli(*args, check=True):
    """`latentbench ARGS...` as a subprocess: (exit status, stdout, stderr)."""
    p = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"latentbench {' '.join(map(str, args))} exited {p.returncode}:\n{p.stderr}")
    return p.returncode, p.stdout, p.stderr


def cli_error_line(*args):
    """The error line the command line prints for a failing command."""
    status, _, err = run_cli(*args, check=False)
    assert status == 1, f"expected exit 1, got {status}: {err}"
    lines = [l for l in err.splitlines() if l.startswith("latentbench: error:")]
    assert lines, err
    return lines[-1]


def same(a, b):
    """Equal, NaN equal to NaN, through dicts and lists (a window without frames has NaN
    metrics)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return a == b or (a != a and b != b)


@pytest.fixture(scope="session")
def cloth(tmp_path_factory):
    """The small cloth's first frames (`simulate`), an autoencoder (`train-ae`) and a
    linear PCA artefact with its rollout, all written by the command line."""
    d = tmp_path_factory.mktemp("cloth")
    files = {"dir": d, "data": d / "data.h5", "ae": d / "ae.h5", "pca": d / "pca.h5", "roll": d / "roll.h5"}
    run_cli("-q", "simulate", CLOTH, "--variant", "small", "--max-frames", FRAMES, "-o", files["data"])
    run_cli("-q", "train-ae", files["data"], "-o", files["ae"], "--epochs", 3, "--hidden", "16,16", "--pca", 6,
            "--latent", 3)
    run_cli("-q", "fit", files["data"], "--method", "linear_pca", "--set", "dim=3", "-o", files["pca"])
    run_cli("-q", "rollout", files["data"], "--integrator", files["pca"], "--sequences", "all", "-o", files["roll"])
    return files
