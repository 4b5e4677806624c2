"""Files as NumPy: datasets, autoencoders, artefacts, rollouts and tables read, written and
read again unchanged; arrays are views into the C++ objects (no copies); values agree with
h5py's independent reading of the same files; bad files raise latentbench.Error naming them."""
import h5py
import numpy as np
import pytest

import latentbench as lb
from conftest import same


def test_dataset_round_trip_and_views(cloth, tmp_path):
    data = lb.Dataset.load(str(cloth["data"]))
    assert data.scene_name == "cloth" and data.variant == "small"
    seq = data.sequences[0]
    n = data.rest_positions.shape[0]
    assert seq.positions.shape == (seq.num_frames, 3 * n)
    with h5py.File(cloth["data"], "r") as f:  # the file's own T × N × 3 layout
        stored = np.asarray(f["sequences/0/positions"]).reshape(seq.num_frames, 3 * n)
    assert np.array_equal(seq.positions, stored)
    # A view, not a copy: two reads share the memory and a write is seen by the next read.
    a, b = seq.positions, data.sequences[0].positions
    assert np.shares_memory(a, b)
    a[5, 7] += 0.25
    assert data.sequences[0].positions[5, 7] == stored[5, 7] + 0.25
    data.save(str(tmp_path / "copy.h5"))
    again = lb.Dataset.load(str(tmp_path / "copy.h5"))
    assert again.scene_toml == data.scene_toml and again.dt == data.dt and again.bc_indices == data.bc_indices
    assert np.array_equal(again.rest_positions, data.rest_positions)
    assert np.array_equal(again.elements, data.elements)
    for s, t in zip(data.sequences, again.sequences):
        assert (s.name, s.train_frames) == (t.name, t.train_frames)
        for field in ("positions", "bc_positions", "bc_params", "newton"):
            assert np.array_equal(getattr(s, field), getattr(t, field)), field
    assert again.sequences[0].positions[5, 7] == stored[5, 7] + 0.25


def test_autoencoder_round_trip(cloth, tmp_path):
    data = lb.Dataset.load(str(cloth["data"]))
    physics = lb.Physics(data)
    ae = lb.Autoencoder.load(str(cloth["ae"]), physics)
    assert ae.latent_dim == 3 and ae.scene_name == "cloth"
    ae.save(str(tmp_path / "ae.h5"))
    again = lb.Autoencoder.load(str(tmp_path / "ae.h5"), physics)
    assert again.content_hash() == ae.content_hash()
    X = data.sequences[0].positions.T  # one state per column
    assert np.array_equal(again.encode(X), ae.encode(X))
    # One state (1-D) and a batch (2-D) agree (to round-off: a matrix-vector product).
    z = ae.encode(X)
    assert z.shape == (3, X.shape[1])
    assert np.allclose(ae.encode(X[:, 4]), z[:, 4], rtol=1e-12, atol=1e-13)


def test_artefact_matches_h5py(cloth):
    art = lb.load_artefact(str(cloth["pca"]))
    assert art["method"] == "linear_pca" and art["scene"] == "cloth"
    assert "dim = 3" in art["options"]
    assert art["arrays"], "an artefact with no arrays"
    with h5py.File(cloth["pca"], "r") as f:
        names = []
        f.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset) else None)
        assert sorted(names) == sorted(art["arrays"])
        for name in names:
            if f[name].dtype.kind in "fiu":
                assert np.array_equal(np.asarray(f[name], dtype=float), art["arrays"][name]), name


def test_rollouts_round_trip(cloth, tmp_path):
    rollouts = lb.load_rollouts(str(cloth["roll"]))
    assert len(rollouts) == 1
    r = rollouts[0]
    assert r.method == "pca" and r.sequence == "corners_line"
    assert r.metrics.shape[1] == len(lb.metric_columns())
    assert r.positions.shape == (r.metrics.shape[0], lb.Dataset.load(str(cloth["data"])).rest_positions.size)
    assert np.shares_memory(r.metrics, r.metrics)
    assert r.summary["frames"] == r.metrics.shape[0] and "mean_rmse" in r.summary["train"]
    lb.save_rollouts(rollouts, str(tmp_path / "roll.h5"), "made by test_data.py")
    again = lb.load_rollouts(str(tmp_path / "roll.h5"))[0]
    assert (again.method, again.sequence) == (r.method, r.sequence)
    assert np.array_equal(again.metrics, r.metrics, equal_nan=True)
    assert np.array_equal(again.positions, r.positions)
    assert same(again.summary, r.summary)
    # A rollout built in Python is written like the command line's.
    made = lb.Rollout("mine", "corners_line", r.metrics.copy(), r.summary)
    lb.save_rollouts([made], str(tmp_path / "mine.h5"))
    back = lb.load_rollouts(str(tmp_path / "mine.h5"))[0]
    assert back.method == "mine" and back.positions is None
    assert lb.load_rollout_summaries(str(tmp_path / "mine.h5"))[0]["method"] == "mine"


def test_table_round_trip(tmp_path):
    t = lb.Table()
    t.title, t.caption, t.columns = "Errors", "A caption, with a comma", ["method", "rmse"]
    t.add_row([lb.TableCell("ours"), lb.TableCell("0.0104", 0.0104)])
    t.add_row([lb.TableCell("pca, linear"), lb.TableCell("—")])
    t.notes = ["one note"]
    t.write_csv(str(tmp_path / "t.csv"))
    again = lb.read_table(str(tmp_path / "t.csv"))
    assert (again.title, again.caption, again.columns, again.notes) == (t.title, t.caption, t.columns, t.notes)
    assert again.values() == [["ours", 0.0104], ["pca, linear", "—"]]
    assert again.to_csv() == t.to_csv()


def test_bad_files_raise_naming_the_file(tmp_path):
    garbage = tmp_path / "garbage.h5"
    garbage.write_text("not HDF5")
    for load in (lb.Dataset.load, lb.load_artefact, lb.load_rollouts):
        with pytest.raises(lb.Error, match="garbage.h5"):
            load(str(garbage))
    with pytest.raises(lb.Error, match="missing.csv"):
        lb.read_table(str(tmp_path / "missing.csv"))
