"""The verbs run the command line's own subcommands in-process: their files equal the
command line's bit for bit on the small cloth (simulate, train-ae, fit, rollout), and a
bad option or input raises latentbench.Error carrying exactly the line the command line
prints, leaving no output behind."""
import numpy as np
import pytest

import latentbench as lb
from conftest import CLOTH, FRAMES, cli_error_line, run_cli, same

TIMING = {"integrate_seconds", "decode_seconds"}  # wall-clock columns differ run to run
TIMING_SUMMARY = {"integrate_ms", "decode_ms", "total_ms", "timing_threads"}
MLP = {"epochs": 2, "hidden": [16, 16], "batch": 8, "seed": 3}


def test_simulate_and_train_autoencoder_equal_the_cli(cloth, tmp_path):
    data = lb.simulate(CLOTH, variant="small", max_frames=FRAMES, output=tmp_path / "data.h5", quiet=True)
    reference = lb.Dataset.load(str(cloth["data"]))
    for s, t in zip(data.sequences, reference.sequences):
        assert np.array_equal(s.positions, t.positions) and np.array_equal(s.bc_positions, t.bc_positions)
    ae = lb.train_autoencoder(tmp_path / "data.h5", output=tmp_path / "ae.h5", epochs=3, hidden="16,16", pca=6,
                              latent=3, quiet=True)
    assert ae.content_hash() == lb.Autoencoder.load(str(cloth["ae"]), lb.Physics(reference)).content_hash()


def test_fit_and_rollout_equal_the_cli_bit_for_bit(cloth, tmp_path):
    d = tmp_path
    sets = [f"--set=epochs={MLP['epochs']}", "--set=hidden=[16,16]", f"--set=batch={MLP['batch']}",
            f"--set=seed={MLP['seed']}"]
    run_cli("-q", "-j", 1, "fit", cloth["data"], "--method", "latent_mlp", "--ae", cloth["ae"], "-o", d / "cli.h5", *sets)
    art = lb.fit(cloth["data"], method="latent_mlp", ae=cloth["ae"], output=d / "py.h5", quiet=True, threads=1, **MLP)
    cli_art = lb.load_artefact(str(d / "cli.h5"))
    assert art["method"] == cli_art["method"] == "latent_mlp"
    assert art["options"] == cli_art["options"]
    assert art["arrays"].keys() == cli_art["arrays"].keys()
    for name, value in art["arrays"].items():
        if isinstance(value, str):
            assert value == cli_art["arrays"][name], name
        else:
            assert np.array_equal(value, cli_art["arrays"][name]), name

    run_cli("-q", "-j", 1, "rollout", cloth["data"], "--integrator", d / "cli.h5", "--ae", cloth["ae"], "--sequences",
            "all", "--frames", 16, "-o", d / "cli_roll.h5")
    mine = lb.rollout(cloth["data"], integrator=d / "py.h5", ae=cloth["ae"], sequences="all", frames=16,
                      output=d / "py_roll.h5", quiet=True, threads=1)
    theirs = lb.load_rollouts(str(d / "cli_roll.h5"))
    assert len(mine) == len(theirs) == 1
    keep = [k for k, c in enumerate(lb.metric_columns()) if c not in TIMING]
    assert mine[0].metrics.shape == (16, len(lb.metric_columns()))
    assert np.array_equal(mine[0].metrics[:, keep], theirs[0].metrics[:, keep], equal_nan=True)
    assert np.array_equal(mine[0].positions, theirs[0].positions)
    for key, value in mine[0].summary.items():
        if key not in TIMING_SUMMARY:
            assert same(value, theirs[0].summary[key]), key


def test_evaluate_and_diagnose(cloth, tmp_path):
    records = lb.evaluate(cloth["roll"], quiet=True)
    assert [r["method"] for r in records] == ["pca"]
    assert records[0]["summary"]["frames"] == FRAMES
    table = lb.diagnose(cloth["data"], ae=cloth["ae"], rollouts=[cloth["roll"]], output=tmp_path / "diag", quiet=True)
    run_cli("-q", "diagnose", cloth["data"], "--ae", cloth["ae"], "--rollouts", cloth["roll"], "-o", tmp_path / "cli")
    cli_table = lb.read_table(str(tmp_path / "cli.csv"))
    assert table.columns == cli_table.columns and len(table.rows) > 0
    assert same(table.values(), cli_table.values())


def test_run_check(tmp_path):
    suite = CLOTH.parent.parent / "quickstart.toml"
    assert lb.run(suite, check=True, output=tmp_path / "run", quiet=True) == 0
    assert not (tmp_path / "run").exists()


def test_errors_carry_the_cli_message(cloth, tmp_path):
    out = tmp_path / "bad.h5"
    cases = [
        # an unknown method option (through --set), then a bad value of a known one
        (lambda: lb.fit(cloth["data"], method="linear_pca", output=out, dimm=2),
         ["fit", cloth["data"], "--method", "linear_pca", "--output", out, "--set", "dimm=2"]),
        (lambda: lb.fit(cloth["data"], method="linear_pca", output=out, dim=-1),
         ["fit", cloth["data"], "--method", "linear_pca", "--output", out, "--set", "dim=-1"]),
        # a latent method without its autoencoder
        (lambda: lb.fit(cloth["data"], method="latent_mlp", output=out),
         ["fit", cloth["data"], "--method", "latent_mlp", "--output", out]),
        # a usage error (CLI11's own message), an out-of-range value, a missing file
        (lambda: lb.rollout(cloth["data"], output=out, bogus=3),
         ["rollout", cloth["data"], "--output", out, "--bogus", "3"]),
        (lambda: lb.rollout(cloth["data"], output=out, integrator=cloth["pca"], frames=1),
         ["rollout", cloth["data"], "--output", out, "--integrator", cloth["pca"], "--frames", "1"]),
        (lambda: lb.train_autoencoder(tmp_path / "missing.h5", output=out),
         ["train-ae", tmp_path / "missing.h5", "--output", out]),
        (lambda: lb.run(tmp_path / "missing.toml"), ["run", tmp_path / "missing.toml"]),
    ]
    for call, argv in cases:
        expected = cli_error_line(*argv)
        with pytest.raises(lb.Error) as e:
            call()
        assert str(e.value) == expected
        assert not out.exists()


def test_status_lists_every_unit_with_its_state(tmp_path):
    suite = CLOTH.parent.parent / "quickstart.toml"
    units = lb.status(suite, output=tmp_path / "run")
    assert units and units[0]["kind"] == "scene" and {u["kind"] for u in units} == {"scene", "fit", "eval"}
    assert all(u["state"] == "not started" and u["epoch"] is None for u in units)
    # A unit's status file is what status reads: a made-up stop, and a made-up failure.
    (tmp_path / "run" / "units").mkdir(parents=True)
    fit = next(u["id"] for u in units if u["kind"] == "fit")
    (tmp_path / "run" / "units" / f"{fit}.status").write_text("stopped\nnode pid 7 2026-12-07 10:00:00 UTC\nby SIGTERM\n")
    scene = units[0]["id"]
    (tmp_path / "run" / "units" / f"{scene}.status").write_text("failed\nnode pid 7 2026-12-07 10:00:00 UTC\nbad mesh\n")
    again = {u["id"]: u for u in lb.status(suite, output=tmp_path / "run")}
    assert again[fit]["state"] == "stopped" and again[fit]["detail"] == "by SIGTERM"
    assert again[scene]["state"] == "failed" and again[scene]["where"].startswith("node pid 7")
    with pytest.raises(lb.Error):
        lb.status(tmp_path / "missing.toml")
