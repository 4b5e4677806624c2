#!/usr/bin/python3
"""scripts/export_rollout.py on a small cloth and a small cantilever (20 frames each),
read back with meshio: points, cells, cell types, time steps, fields; the ground
truth's error field is zero. Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_export_rollout.py --cli build/latentbench --tmp build/tests/tmp

Exits 77 (ctest's SKIP_RETURN_CODE) with a message if meshio is not installed.
"""
import os
import shutil
import subprocess
import sys
import unittest

import script_test
import xml.etree.ElementTree as ET

SKIP = 77
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXPORT = os.path.join(REPO, "scripts", "export_rollout.py")
FRAMES = 20

try:
    import meshio
    import numpy as np
    import h5py
except ImportError as exc:
    print(f"SKIPPED: {exc}; install Debian's python3-meshio (scripts/run setup)")
    sys.exit(SKIP)

ARGS = None  # command-line options, set in main


def run(argv):
    """Run a command (never through a shell); fail the test with its output if it fails."""
    p = subprocess.run(argv, capture_output=True, text=True)
    if p.returncode != 0:
        raise AssertionError(f"{' '.join(argv)} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def make_rollout(work, scene, sequence):
    """data.h5 (FRAMES frames of the small variant) and the full_space rollout of one sequence."""
    data = os.path.join(work, f"{scene}_data.h5")
    rollout = os.path.join(work, f"{scene}_rollout.h5")
    run([ARGS.cli, "-q", "simulate", os.path.join(REPO, "experiments", "scenes", f"{scene}.toml"), "--variant",
         "small", "-o", data, "--max-frames", str(FRAMES)])
    run([ARGS.cli, "-q", "rollout", data, "--method", "full_space", "--sequences", sequence, "-o", rollout])
    return data, rollout


def read_pvd(path):
    """(time, absolute file) of every DataSet of a .pvd."""
    root = ET.parse(path).getroot()
    base = os.path.dirname(path)
    return [(float(d.get("timestep")), os.path.join(base, d.get("file"))) for d in root.iter("DataSet")]


class ExportTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = os.path.join(ARGS.tmp, f"export_rollout_{os.getpid()}")
        shutil.rmtree(cls.work, ignore_errors=True)
        os.makedirs(cls.work)
        cls.scenes = {}
        # (scene, cell type, --sequences, the group of that sequence in data.h5)
        for scene, cell_type, sequence, key in (("cloth", "triangle", "all", 0), ("cantilever", "tetra", "all", 0),
                                                ("rods_translate", "line", "test_fast_then_slow", 12)):
            data, rollout = make_rollout(cls.work, scene, sequence)
            with h5py.File(data, "r") as f:
                g = f[f"sequences/{key}"]
                name = g.attrs["name"]
                info = dict(points=f["rest_positions"].shape[0], cells=f["elements"].shape[0],
                            dt=float(f.attrs["dt"]), sequence=name.decode() if isinstance(name, bytes) else name,
                            bc=np.asarray(f["bc/indices"][...]), gt=np.asarray(g["positions"][...]),
                            rest=np.asarray(f["rest_positions"][...]))
            cls.scenes[scene] = (data, rollout, cell_type, info)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def export(self, scene, fmt, every):
        data, rollout, _, _ = self.scenes[scene]
        out = os.path.join(self.work, f"{scene}_{fmt}_{every}")
        written = run(["/usr/bin/python3", EXPORT, rollout, "--data", data, "-o", out, "--format", fmt, "--every",
                       str(every), "--ground-truth"]).split()
        return written

    def check_frame(self, points, cells, point_data, scene, t, truth):
        _, _, cell_type, info = self.scenes[scene]
        self.assertEqual(len(points), info["points"])
        self.assertEqual([c.type for c in cells], [cell_type])
        self.assertEqual(len(cells[0].data), info["cells"])
        for name, width in (("displacement", 3), ("error", 3)):
            self.assertIn(name, point_data)
            self.assertEqual(point_data[name].shape, (info["points"], width))
        self.assertEqual(int(np.sum(point_data["dirichlet"])), len(info["bc"]))
        x = info["rest"] + point_data["displacement"]
        # The full_space rollout reproduces the dataset's Newton solve to its tolerance.
        np.testing.assert_allclose(x, info["gt"][t], atol=1e-6)
        if truth:
            self.assertEqual(float(np.max(np.abs(point_data["error"]))), 0.0)

    def check_vtu(self, scene, every):
        written = self.export(scene, "vtu", every)
        _, _, _, info = self.scenes[scene]
        names = sorted(os.path.basename(p) for p in written)
        self.assertEqual(names, sorted([f"full_space_{info['sequence']}.pvd", f"ground_truth_{info['sequence']}.pvd"]))
        expected_frames = list(range(0, FRAMES, every))
        for path in written:
            truth = os.path.basename(path).startswith("ground_truth")
            entries = read_pvd(path)
            self.assertEqual(len(entries), len(expected_frames))
            for (time, file), t in zip(entries, expected_frames):
                self.assertAlmostEqual(time, t * info["dt"], places=12)
                m = meshio.read(file)
                self.check_frame(m.points, m.cells, m.point_data, scene, t, truth)
                # VTU points are the deformed positions themselves.
                np.testing.assert_allclose(m.points, info["rest"] + m.point_data["displacement"], atol=1e-12)

    def check_xdmf(self, scene, every):
        written = self.export(scene, "xdmf", every)
        _, _, _, info = self.scenes[scene]
        expected_frames = list(range(0, FRAMES, every))
        self.assertEqual(len(written), 2)
        for path in written:
            self.assertTrue(path.endswith(".xdmf"))
            self.assertTrue(os.path.exists(path[:-5] + ".h5"))
            truth = os.path.basename(path).startswith("ground_truth")
            with meshio.xdmf.TimeSeriesReader(path) as reader:
                points, cells = reader.read_points_cells()
                self.assertEqual(reader.num_steps, len(expected_frames))
                np.testing.assert_allclose(points, info["rest"])
                for k, t in enumerate(expected_frames):
                    time, point_data, _ = reader.read_data(k)
                    self.assertAlmostEqual(time, t * info["dt"], places=12)
                    self.check_frame(points, cells, point_data, scene, t, truth)

    def test_cloth_vtu(self):
        self.check_vtu("cloth", 1)

    def test_cantilever_vtu_every_3(self):
        self.check_vtu("cantilever", 3)

    def test_cloth_xdmf_every_4(self):
        self.check_xdmf("cloth", 4)

    def test_cantilever_xdmf(self):
        self.check_xdmf("cantilever", 1)

    def test_rods_vtu_and_xdmf_as_lines(self):
        self.check_vtu("rods_translate", 5)
        self.check_xdmf("rods_translate", 5)

    def test_diverged_rollout_stops_at_last_finite_frame(self):
        data, rollout, _, info = self.scenes["cloth"]
        broken = os.path.join(self.work, "cloth_diverged.h5")
        shutil.copy(rollout, broken)
        with h5py.File(broken, "r+") as f:
            f["rollouts/0/positions"][12:] = np.nan
        out = os.path.join(self.work, "diverged")
        p = subprocess.run(["/usr/bin/python3", EXPORT, broken, "--data", data, "-o", out], capture_output=True,
                           text=True)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("non-finite from frame 12", p.stderr)
        self.assertEqual(len(read_pvd(p.stdout.split()[0])), 12)

    def test_bad_input_exits_1_and_leaves_nothing(self):
        data, _, _, _ = self.scenes["cloth"]
        out = os.path.join(self.work, "bad")
        p = subprocess.run(["/usr/bin/python3", EXPORT, data, "--data", data, "-o", out], capture_output=True,
                           text=True)
        self.assertEqual(p.returncode, 1)
        self.assertIn("export_rollout.py: error:", p.stderr)
        self.assertFalse(os.path.exists(out) and os.listdir(out))


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
