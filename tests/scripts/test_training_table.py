#!/usr/bin/python3
"""scripts/training_table.py and its use by compare_tables.py: a published training table keeps
epochs 1-10, every k-th, the last and the best-validation epoch of each run, cell for cell; a full
table compares equal with its thinned copy and unequal when a kept cell moved. Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_training_table.py --cli build/latentbench --tmp build/tests/tmp
"""
import csv
import io
import pathlib
import shutil
import subprocess
import sys
import unittest

import script_test

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
sys.path.insert(0, str(REPO / "scripts"))
import training_table  # noqa: E402

ARGS = None


def full_table(runs):
    """A training table as `latentbench run` writes it: runs maps (method, seed, stage) to (epochs, has validation)."""
    lines = ["# Training curves on test_scene", "# caption", "method,seed,stage,epoch,train_loss,validation_loss"]
    for (method, seed, stage), (epochs, validation) in runs.items():
        for e in range(1, epochs + 1):
            # The validation minimum sits at epoch 777 of a 3,000-epoch run: not a multiple of 10.
            val = f"{abs(e - 777) / 1000 + 0.5:.17g}" if validation else ""
            lines.append(f"{method},{seed},{stage},{e},{1.0 / e:.17g},{val}")
    return "\n".join(lines) + "\n"


def epochs_of(text, key):
    rows = csv.DictReader(io.StringIO("\n".join(l for l in text.splitlines() if not l.startswith("#"))))
    return [int(r["epoch"]) for r in rows if (r["method"], r["seed"], r["stage"]) == key]


class TrainingTable(unittest.TestCase):
    def test_stride_is_the_smallest_round_step_that_fits(self):
        self.assertEqual(training_table.stride(300), 1)
        self.assertEqual(training_table.stride(301), 2)
        self.assertEqual(training_table.stride(1500), 5)
        self.assertEqual(training_table.stride(3000), 10)
        self.assertEqual(training_table.stride(10000), 50)
        self.assertEqual(training_table.stride(20000), 100)

    def test_thinning_keeps_the_first_the_stride_the_last_and_the_best(self):
        text = full_table({("autoencoder", "0", "autoencoder"): (3000, True), ("ours", "1", "latent_mlp"): (1503, False),
                           ("pca", "", "fit"): (40, False)})
        thin = training_table.thin(text)
        self.assertTrue(training_table.is_thinned(thin))
        self.assertEqual(thin.splitlines()[:2], text.splitlines()[:2])  # caption kept
        ae = epochs_of(thin, ("autoencoder", "0", "autoencoder"))
        self.assertEqual(ae[:10], list(range(1, 11)))
        self.assertIn(777, ae)  # lowest validation loss
        self.assertEqual(ae[-1], 3000)
        self.assertEqual(len(ae), 10 + 299 + 1)  # 1-10, 20..3000 by 10, 777
        ours = epochs_of(thin, ("ours", "1", "latent_mlp"))
        self.assertEqual(ours[-1], 1503)  # the last epoch, not a multiple of 5
        self.assertTrue(all(e <= 10 or e % 5 == 0 or e == 1503 for e in ours))
        self.assertEqual(epochs_of(thin, ("pca", "", "fit")), list(range(1, 41)))  # short runs whole
        # Kept rows are the original lines, cell for cell; thinning twice changes nothing.
        original = set(text.splitlines())
        self.assertTrue(all(line in original for line in thin.splitlines() if not line.startswith("#")))
        self.assertEqual(training_table.thin(thin), thin)

    def test_a_short_table_is_left_as_the_run_wrote_it(self):
        text = full_table({("ours", "0", "latent_mlp"): (250, True)})
        self.assertEqual(training_table.thin(text), text)

    def test_compare_tables_compares_a_full_table_with_its_thinned_copy(self):
        tmp = pathlib.Path(ARGS.tmp) / "training_table"
        shutil.rmtree(tmp, ignore_errors=True)
        (tmp / "published").mkdir(parents=True)
        (tmp / "rerun").mkdir()
        text = full_table({("ours", "0", "latent_mlp"): (2000, True)})
        (tmp / "published" / "training_s.csv").write_text(training_table.thin(text))
        (tmp / "rerun" / "training_s.csv").write_text(text)
        compare = [sys.executable, str(REPO / "scripts" / "compare_tables.py"), str(tmp / "published"), str(tmp / "rerun")]
        p = subprocess.run(compare, capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("tables equal: 1 CSV files", p.stdout)
        # A kept epoch (epoch 40) that moved is found; a dropped one (epoch 41) is not compared.
        moved = text.replace("ours,0,latent_mlp,40,", "ours,0,latent_mlp,40,9")
        (tmp / "rerun" / "training_s.csv").write_text(moved)
        p = subprocess.run(compare, capture_output=True, text=True)
        self.assertEqual(p.returncode, 1, p.stdout)
        self.assertIn("training_s.csv row", p.stdout)


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
