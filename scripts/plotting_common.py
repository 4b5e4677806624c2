"""Shared helpers of latentbench's scripts (plot_rollouts.py, plot_filmstrip.py, plot_video.py, export_rollout.py).

Reads the HDF5 files written by ``latentbench rollout`` and ``latentbench simulate``
with h5py and sets up matplotlib with the non-interactive Agg backend. Run the
scripts with the Debian interpreter (/usr/bin/python3), which has numpy, h5py
and matplotlib.

Rollout file layout (src/eval/rollout.cpp, save_rollouts):
  root attrs   num_rollouts, metric_columns ("rmse,bc_violation,..."), config
  rollouts/<k> dataset metrics (T x columns), optional positions (T x N x 3);
               attrs method, sequence, frames, stable_horizon, ke_ratio, ...
Dataset file layout (src/sim/dataset.cpp):
  rest_positions (N x 3), elements (M x K: 2 rods, 3 triangles, 4 tets),
  bc/indices (B), rods (R x V, rods only), sequences/<k>/positions (T x N x 3),
  sequences/<k>/bc_positions (T x B x 3); attrs object, scene, dt; sequences/<k>
  attrs name, train_frames.
"""
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
import numpy as np  # noqa: E402

try:
    import h5py  # noqa: E402
except ImportError:  # pragma: no cover - reported by the scripts
    h5py = None

# Colours: one per method in order of first appearance (matplotlib's tab10),
# the ground truth always in grey/black.
METHOD_COLOURS = list(plt.get_cmap("tab10").colors)
GROUND_TRUTH_COLOUR = "0.25"
GHOST_COLOUR = "0.65"
BC_COLOUR = "red"


class InputError(Exception):
    """A missing, unreadable or malformed input file; the message names the file."""


def fail(message):
    """Print 'script: error: message' to stderr and exit with status 1."""
    print(f"{os.path.basename(sys.argv[0])}: error: {message}", file=sys.stderr)
    sys.exit(1)


def require_h5py():
    if h5py is None:
        fail("h5py is not importable; run with /usr/bin/python3 (Debian package python3-h5py)")


def as_str(value):
    """HDF5 string attributes come back as str, bytes or 0-d arrays depending on how they were written."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray):
        if value.shape == ():
            return as_str(value[()])
        if value.size == 1:
            return as_str(value.reshape(-1)[0])
    return str(value)


def open_h5(path):
    """Open an HDF5 file read-only, turning every failure into InputError."""
    if not os.path.exists(path):
        raise InputError(f"'{path}' does not exist")
    if not os.path.isfile(path):
        raise InputError(f"'{path}' is not a file")
    try:
        return h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise InputError(f"'{path}' is not a readable HDF5 file ({exc})") from None


def safe_name(text):
    """A file-name fragment: letters, digits, '-', '_' and '.' only."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("_")
    return name or "unnamed"


class Rollout:
    """One rollout group: method, sequence, per-frame metric columns, optional positions."""

    def __init__(self, path, key, method, sequence, columns, metrics, attrs, positions_ref):
        self.path = path
        self.key = key
        self.method = method
        self.sequence = sequence
        self.columns = columns
        self.metrics = metrics
        self.attrs = attrs
        self._positions_ref = positions_ref  # (path, dataset name) or None
        self.label = method

    def column(self, name):
        if name not in self.columns:
            raise InputError(f"'{self.path}': rollouts/{self.key} has no metric column '{name}' "
                             f"(columns: {', '.join(self.columns)})")
        return self.metrics[:, self.columns.index(name)]

    @property
    def num_frames(self):
        return self.metrics.shape[0]

    def has_positions(self):
        return self._positions_ref is not None

    def positions(self):
        """T x N x 3 predicted positions (read on demand: they can be large)."""
        if self._positions_ref is None:
            raise InputError(f"'{self.path}': rollouts/{self.key} ({self.method} on {self.sequence}) stores no "
                             "positions; rerun the rollout with positions kept")
        path, name = self._positions_ref
        with open_h5(path) as f:
            data = np.asarray(f[name][...], dtype=float)
        if data.ndim == 2 and data.shape[1] % 3 == 0:
            data = data.reshape(data.shape[0], -1, 3)
        if data.ndim != 3 or data.shape[2] != 3:
            raise InputError(f"'{path}': {name} has shape {data.shape}, expected T x N x 3")
        return data


def load_rollouts(path):
    """All rollouts of one file written by `latentbench rollout`; raises InputError."""
    with open_h5(path) as f:
        try:
            if "metric_columns" not in f.attrs:
                raise InputError(f"'{path}' is not a latentbench rollout file (no 'metric_columns' attribute)")
            columns = [c.strip() for c in as_str(f.attrs["metric_columns"]).split(",") if c.strip()]
            if "rollouts" not in f:
                raise InputError(f"'{path}' has no 'rollouts' group")
            group = f["rollouts"]
            keys = sorted(group.keys(), key=lambda k: (0, int(k)) if k.isdigit() else (1, k))
            expected = int(f.attrs["num_rollouts"]) if "num_rollouts" in f.attrs else len(keys)
            if expected != len(keys):
                raise InputError(f"'{path}': num_rollouts = {expected} but {len(keys)} groups under rollouts/")
            rollouts = []
            for key in keys:
                g = group[key]
                if "metrics" not in g:
                    raise InputError(f"'{path}': rollouts/{key} has no 'metrics' dataset")
                metrics = np.asarray(g["metrics"][...], dtype=float)
                if metrics.ndim != 2 or metrics.shape[1] != len(columns):
                    raise InputError(f"'{path}': rollouts/{key}/metrics has shape {metrics.shape}, expected "
                                     f"T x {len(columns)} (metric_columns)")
                attrs = {k: (as_str(v) if isinstance(v, (bytes, str)) else v) for k, v in g.attrs.items()}
                method = as_str(g.attrs.get("method", f"rollout {key}"))
                sequence = as_str(g.attrs.get("sequence", "sequence"))
                positions_ref = (path, f"rollouts/{key}/positions") if "positions" in g else None
                rollouts.append(Rollout(path, key, method, sequence, columns, metrics, attrs, positions_ref))
            return rollouts
        except InputError:
            raise
        except (KeyError, OSError, ValueError, TypeError) as exc:
            raise InputError(f"'{path}' is corrupt or not a latentbench rollout file ({exc})") from None


def load_all_rollouts(paths):
    """Rollouts of several files with unique labels: the method name, plus the file
    name when the same method and sequence appear in more than one file."""
    rollouts = []
    for path in paths:
        rollouts.extend(load_rollouts(path))
    counts = {}
    for r in rollouts:
        counts[(r.method, r.sequence)] = counts.get((r.method, r.sequence), 0) + 1
    for r in rollouts:
        if counts[(r.method, r.sequence)] > 1:
            r.label = f"{r.method} ({os.path.splitext(os.path.basename(r.path))[0]})"
    return rollouts


class Dataset:
    """A dataset written by `latentbench simulate`: the mesh, the Dirichlet set and the
    sequences' names; positions are read per sequence on demand."""

    def __init__(self, path):
        with open_h5(path) as f:
            for required in ("rest_positions", "elements", "sequences"):
                if required not in f:
                    raise InputError(f"'{path}' is not a latentbench dataset (no '{required}')")
            try:
                self.path = path
                self.rest = np.asarray(f["rest_positions"][...], dtype=float)
                self.elements = np.asarray(f["elements"][...], dtype=np.int64)
                self.object = as_str(f.attrs["object"]) if "object" in f.attrs else ""
                self.scene = as_str(f.attrs["scene"]) if "scene" in f.attrs else ""
                self.bc_indices = (np.asarray(f["bc/indices"][...], dtype=np.int64).reshape(-1)
                                   if "bc/indices" in f else np.zeros(0, dtype=np.int64))
                keys = sorted(f["sequences"].keys(), key=lambda k: (0, int(k)) if k.isdigit() else (1, k))
                self.sequences = [(k, as_str(f["sequences"][k].attrs.get("name", k))) for k in keys]
                self.train_frames = {k: int(f["sequences"][k].attrs.get("train_frames", 0)) for k in keys}
                self.dt = float(f.attrs["dt"]) if "dt" in f.attrs else 1.0 / 30.0
                self.rods = np.asarray(f["rods"][...], dtype=np.int64) if "rods" in f else None
            except (KeyError, OSError, ValueError, TypeError) as exc:
                raise InputError(f"'{path}' is corrupt or not a latentbench dataset ({exc})") from None
        if self.rest.ndim != 2 or self.rest.shape[1] != 3:
            raise InputError(f"'{path}': rest_positions has shape {self.rest.shape}, expected N x 3")
        if self.elements.ndim != 2 or self.elements.shape[1] not in (2, 3, 4):
            raise InputError(f"'{path}': elements has shape {self.elements.shape}, expected M x 2/3/4")
        if self.elements.size and (self.elements.min() < 0 or self.elements.max() >= len(self.rest)):
            raise InputError(f"'{path}': element indices out of range for {len(self.rest)} vertices")

    def find_sequence(self, name):
        """(key, name) of a sequence given by name or by group index."""
        for key, seq_name in self.sequences:
            if name in (key, seq_name):
                return key, seq_name
        names = ", ".join(n for _, n in self.sequences)
        raise InputError(f"'{self.path}' has no sequence '{name}' (sequences: {names})")

    def ground_truth(self, key):
        """Positions (T x N x 3) and Dirichlet targets (T x B x 3) of one sequence."""
        with open_h5(self.path) as f:
            try:
                g = f["sequences"][key]
                positions = np.asarray(g["positions"][...], dtype=float)
                targets = np.asarray(g["bc_positions"][...], dtype=float) if "bc_positions" in g else None
            except (KeyError, OSError, ValueError, TypeError) as exc:
                raise InputError(f"'{self.path}': cannot read sequences/{key} ({exc})") from None
        if positions.ndim == 2:
            positions = positions.reshape(positions.shape[0], -1, 3)
        if positions.ndim != 3 or positions.shape[1:] != self.rest.shape:
            raise InputError(f"'{self.path}': sequences/{key}/positions has shape {positions.shape}, "
                             f"expected T x {len(self.rest)} x 3")
        if targets is not None:
            targets = targets.reshape(targets.shape[0], -1, 3)
            if targets.shape[1] != len(self.bc_indices):
                targets = None
        if targets is None:
            targets = positions[:, self.bc_indices, :]
        return positions, targets


def colour_map(labels):
    """Stable colour per label, in order of first appearance."""
    colours = {}
    for label in labels:
        if label not in colours:
            colours[label] = METHOD_COLOURS[len(colours) % len(METHOD_COLOURS)]
    return colours


def style_axes(ax):
    ax.grid(True, which="major", alpha=0.35, linewidth=0.6)
    ax.grid(True, which="minor", alpha=0.12, linewidth=0.4)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def save_figure(fig, path):
    """Save a PNG atomically (temporary name + rename) and close the figure."""
    directory = os.path.dirname(path)
    if directory:
        os.makedirs(directory, exist_ok=True)
    temp = f"{path}.tmp-{os.getpid()}.png"
    try:
        fig.savefig(temp, dpi=150)
        os.replace(temp, path)
    finally:
        plt.close(fig)
        if os.path.exists(temp):
            os.remove(temp)
    return path
