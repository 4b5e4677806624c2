#!/usr/bin/python3
"""Filmstrip of rollouts against ground truth, in the style of the paper's figures.

Reads a dataset written by `latentbench simulate` and one or more rollout files
written by `latentbench rollout` (with positions kept) and draws about six
evenly spaced frames of one sequence: the first row is the ground truth (grey),
then one row per method (its colour) with the ground truth as a faint ghost
behind it. Rods are drawn as line segments, cloth as a shaded triangle mesh,
solids as their shaded boundary surface; the prescribed Dirichlet targets are
red dots. Every panel shares the same axes limits and view, so motion and
drift are comparable across frames and methods. A diverged frame (non-finite
positions) is marked as such.

Example:
  /usr/bin/python3 scripts/plot_filmstrip.py data/cloth.h5 results/cloth_rollouts.h5 \\
      -o results/figures/cloth_filmstrip.png --frames 6
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402

import numpy as np  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from matplotlib.transforms import Bbox, TransformedBbox  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402

LIGHT = np.array([0.35, -0.55, 0.76])
LIGHT = LIGHT / np.linalg.norm(LIGHT)
PANEL_INCHES = 2.3
# Methods that fly away must not shrink everybody else: their extent counts only up
# to this multiple of the ground truth's extent beyond the ground-truth box, and a
# frame reaching further than EXPLODED_EXTENT extents outside it is not drawn at all.
MAX_EXTENT_GROWTH = 0.25
EXPLODED_EXTENT = 0.5
# Fraction of a panel the projected axes box may fill.
PANEL_FILL = 0.94
# A Dirichlet set larger than this on a triangle mesh (e.g. the bunny's rigid head) is
# shown by tinting its faces red instead of one dot per vertex.
MAX_BC_DOTS = 48
BC_TINT = np.array(to_rgb("#d62728"))


def boundary_faces(tets):
    """Triangles of a tet mesh that belong to exactly one tet (its surface)."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    keys = np.sort(faces, axis=1)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    return faces[first[counts == 1]]


class Geometry:
    """What to draw for one mesh: segments (rods) or triangles (cloth, solid surface)."""

    def __init__(self, dataset):
        k = dataset.elements.shape[1]
        self.kind = {2: "rods", 3: "shell", 4: "solid"}[k]
        self.segments = dataset.elements if k == 2 else None
        self.triangles = {2: None, 3: dataset.elements, 4: boundary_faces(dataset.elements) if k == 4 else None}[k]
        # Vertices that are drawn at all (for the axes limits).
        used = self.segments if self.segments is not None else self.triangles
        self.used_vertices = np.unique(used) if used is not None and used.size else np.arange(len(dataset.rest))
        # Large Dirichlet sets on surfaces: tint the faces whose vertices are all prescribed.
        self.bc_faces = None
        if self.triangles is not None and len(dataset.bc_indices) > MAX_BC_DOTS:
            is_bc = np.zeros(len(dataset.rest), dtype=bool)
            is_bc[dataset.bc_indices] = True
            self.bc_faces = is_bc[self.triangles].all(axis=1)

    @property
    def bc_as_dots(self):
        return self.bc_faces is None

    def draw(self, ax, x, colour, ghost=False):
        if self.segments is not None:
            lines = Line3DCollection(x[self.segments], colors=[pc.GHOST_COLOUR if ghost else colour],
                                     linewidths=0.5 if ghost else 0.9, alpha=0.45 if ghost else 1.0)
            ax.add_collection3d(lines)
            return
        tri = x[self.triangles]
        if ghost:
            poly = Poly3DCollection(tri, facecolors=pc.GHOST_COLOUR, edgecolors="none", alpha=0.18)
        else:
            normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            lengths = np.linalg.norm(normals, axis=1, keepdims=True)
            normals = normals / np.where(lengths > 0, lengths, 1.0)
            shade = 0.45 + 0.55 * np.abs(normals @ LIGHT)  # two-sided: cloth has no outside
            base = np.tile(np.asarray(to_rgb(colour)), (len(tri), 1))
            if self.bc_faces is not None:
                base[self.bc_faces] = 0.35 * base[self.bc_faces] + 0.65 * BC_TINT
            faces = np.clip(base * shade[:, None] + 0.08, 0, 1)
            edge = (0.0, 0.0, 0.0, 0.12) if self.kind == "shell" else "none"
            poly = Poly3DCollection(tri, facecolors=faces, edgecolors=edge, linewidths=0.2)
        ax.add_collection3d(poly)


def exploded(x, lo, hi):
    """A frame that reaches far outside a box (lo, hi): a diverging rollout."""
    reach = EXPLODED_EXTENT * np.max(hi - lo)
    return bool(np.any(x < lo - reach) or np.any(x > hi + reach))


def axes_box(gt_frames, method_frames):
    """Common (lo, hi) corners: the ground truth's box over the shown frames, grown by the
    methods' frames up to MAX_EXTENT_GROWTH (exploded frames do not count)."""
    gt = gt_frames[np.isfinite(gt_frames).all(axis=-1)]
    gt_lo, gt_hi = gt.min(axis=0), gt.max(axis=0)
    extent = np.maximum(gt_hi - gt_lo, 1e-3 * max(np.max(gt_hi - gt_lo), 1e-9))
    lo, hi = gt_lo.copy(), gt_hi.copy()
    for frames in method_frames:
        for x in frames:
            if not np.isfinite(x).all() or exploded(x, gt_lo, gt_hi):
                continue
            lo = np.minimum(lo, np.maximum(x.min(axis=0), gt_lo - MAX_EXTENT_GROWTH * extent))
            hi = np.maximum(hi, np.minimum(x.max(axis=0), gt_hi + MAX_EXTENT_GROWTH * extent))
    pad = 0.04 * np.max(hi - lo)
    return lo - pad, hi + pad


def box_aspect(lo, hi):
    return np.maximum(hi - lo, 1e-3 * np.max(hi - lo))


def setup_axes(ax, lo, hi, view, zoom):
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(box_aspect(lo, hi), zoom=zoom)
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_axis_off()


def panel_layout(lo, hi, view):
    """Panel (width, height) in inches and the zoom that makes the projected axes box
    fill it. mplot3d scales a scene with the smaller side of its axes, so measure the
    projected box once in a 1 x 1 inch axes at zoom 1 and scale from there."""
    fig = pc.plt.figure(figsize=(1.0, 1.0))
    ax = fig.add_axes([0, 0, 1, 1], projection="3d", proj_type="ortho")
    setup_axes(ax, lo, hi, view, 1.0)
    fig.canvas.draw()
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    xs, ys, _ = proj3d.proj_transform(corners[:, 0], corners[:, 1], corners[:, 2], ax.get_proj())
    screen = ax.transData.transform(np.column_stack([xs, ys])) / fig.dpi
    pc.plt.close(fig)
    bw, bh = max(np.ptp(screen[:, 0]), 1e-6), max(np.ptp(screen[:, 1]), 1e-6)
    aspect = bh / bw
    if aspect <= 1.0:  # wide scenes: full width, shorter panels
        width, height = PANEL_INCHES, max(PANEL_INCHES * aspect, 0.45 * PANEL_INCHES)
    else:  # tall scenes (hanging rods): taller but narrower panels
        height = min(PANEL_INCHES * aspect, 1.5 * PANEL_INCHES)
        width = max(height / aspect, 0.45 * PANEL_INCHES)
    zoom = PANEL_FILL * min(width / bw, height / bh) / min(width, height)
    return width, height, zoom


def out_of_view(x, lo, hi):
    """True if part of a (finite) frame lies clearly outside the common axes box."""
    tol = 0.02 * np.max(hi - lo)
    return bool(np.any(x < lo - tol) or np.any(x > hi + tol))


def draw_panel(ax, geometry, x, ghost, bc_targets, colour, lo, hi):
    """One frame of one row: the faint ground-truth ghost (method rows), the mesh, the red
    Dirichlet targets on top; a non-finite or exploded frame is labelled instead."""
    ax.computed_zorder = False  # draw in call order: ghost, mesh, then the red dots
    used = geometry.used_vertices
    if ghost is not None and np.isfinite(ghost).all():
        geometry.draw(ax, ghost, None, ghost=True)
    message = None
    if not np.isfinite(x).all():
        message = "diverged\n(non-finite)"
    elif ghost is not None and exploded(x[used], lo, hi):
        message = "out of view\n(diverging)"
    else:
        geometry.draw(ax, x, colour)
        if ghost is not None and out_of_view(x[used], lo, hi):
            ax.text2D(0.5, 0.02, "partly out of view", transform=ax.transAxes, ha="center", va="bottom",
                      color="firebrick", fontsize=7)
    if message:
        ax.text2D(0.5, 0.5, message, transform=ax.transAxes, ha="center", va="center", color="firebrick",
                  fontsize=9, zorder=10, bbox=dict(facecolor="white", edgecolor="none", alpha=0.75, pad=1.5))
    if bc_targets.shape[0] > 0 and geometry.bc_as_dots:
        ax.scatter(bc_targets[:, 0], bc_targets[:, 1], bc_targets[:, 2], s=7, c=pc.BC_COLOUR, depthshade=False,
                   linewidths=0)


def select_rollouts(rollouts, dataset, sequence_arg):
    """The sequence to show and the rollouts of it that carry positions."""
    with_positions = [r for r in rollouts if r.has_positions()]
    if sequence_arg is not None:
        key, name = dataset.find_sequence(sequence_arg)
    else:
        rollout_sequences = [r.sequence for r in with_positions]
        candidates = [(k, n) for k, n in dataset.sequences if n in rollout_sequences]
        if not candidates:
            if not with_positions:
                raise pc.InputError("no rollout stores positions; rerun `latentbench rollout` with positions kept")
            raise pc.InputError("no rollout matches a sequence of the dataset (rollout sequences: "
                                f"{', '.join(sorted(set(rollout_sequences)))}; dataset: "
                                f"{', '.join(n for _, n in dataset.sequences)})")
        key, name = candidates[0]
    chosen = [r for r in rollouts if r.sequence == name]
    if not chosen:
        print(f"plot_filmstrip.py: warning: no rollout of sequence '{name}'; drawing the ground truth only",
              file=sys.stderr)
    missing = [r for r in chosen if not r.has_positions()]
    for r in missing:
        print(f"plot_filmstrip.py: warning: {r.path}: {r.method} on {name} stores no positions; skipped",
              file=sys.stderr)
    return key, name, [r for r in chosen if r.has_positions()]


def load_scene_rollouts(dataset_path, rollout_paths, sequence):
    """The dataset, the chosen sequence's key and name, ground truth and Dirichlet targets, and the
    rollouts shown with their positions (each checked against the dataset's vertex count).
    Exits with an error line on bad input (pc.fail)."""
    try:
        dataset = pc.Dataset(dataset_path)
        rollouts = pc.load_all_rollouts(rollout_paths)
        if rollouts:
            key, name, shown = select_rollouts(rollouts, dataset, sequence)
        else:
            key, name = dataset.find_sequence(sequence) if sequence else dataset.sequences[0]
            shown = []
        gt, targets = dataset.ground_truth(key)
        predictions = []
        for r in shown:
            x = r.positions()
            if x.shape[1] != gt.shape[1]:
                raise pc.InputError(f"'{r.path}': {r.method} on {name} has {x.shape[1]} vertices, the dataset "
                                    f"'{dataset_path}' {gt.shape[1]}: not the same scene/variant")
            predictions.append(x)
    except pc.InputError as exc:
        pc.fail(str(exc))
    return dataset, key, name, gt, targets, shown, predictions


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("dataset", help="dataset HDF5 written by `latentbench simulate`")
    parser.add_argument("rollouts", nargs="*", help="rollout HDF5 files written by `latentbench rollout`")
    parser.add_argument("-o", "--output", required=True, help="output PNG")
    parser.add_argument("--sequence", default=None, help="sequence name or index (default: first one with rollouts)")
    parser.add_argument("--frames", type=int, default=6, help="number of evenly spaced frames (default 6)")
    parser.add_argument("--view", type=float, nargs=2, metavar=("ELEV", "AZIM"), default=(12.0, -70.0),
                        help="camera elevation and azimuth in degrees (default 12 -70)")
    parser.add_argument("--title", default=None, help="figure title (default: scene and sequence)")
    args = parser.parse_args(argv)
    if args.frames < 1:
        pc.fail("--frames must be at least 1")
    pc.require_h5py()

    dataset, _, name, gt, targets, shown, predictions = load_scene_rollouts(args.dataset, args.rollouts, args.sequence)

    num_frames = min([len(gt)] + [len(x) for x in predictions]) if predictions else len(gt)
    frames = np.unique(np.linspace(0, num_frames - 1, min(args.frames, num_frames)).round().astype(int))
    geometry = Geometry(dataset)
    used = geometry.used_vertices
    lo, hi = axes_box(gt[frames][:, used], [x[frames][:, used] for x in predictions])

    colours = pc.colour_map(r.label for r in shown)
    row_labels = ["ground truth"] + [r.label for r in shown]
    row_data = [gt] + predictions
    rows, cols = len(row_labels), len(frames)
    panel_w, panel_h, zoom = panel_layout(lo, hi, args.view)
    fig = pc.plt.figure(figsize=(0.35 + panel_w * cols, 0.55 + panel_h * rows))
    left, top = 0.35 / fig.get_figwidth(), 1.0 - 0.55 / fig.get_figheight()
    width, height = (1.0 - left) / cols, top / rows
    for i, (label, data) in enumerate(zip(row_labels, row_data)):
        colour = pc.GROUND_TRUTH_COLOUR if i == 0 else colours[label]
        for j, t in enumerate(frames):
            cell = [left + j * width, top - (i + 1) * height, width, height]
            ax = fig.add_axes(cell, projection="3d", proj_type="ortho")
            setup_axes(ax, lo, hi, args.view, zoom)
            draw_panel(ax, geometry, data[t], gt[t] if i > 0 else None, targets[t],
                       "0.6" if i == 0 else colour, lo, hi)
            # mplot3d does not clip to the axes; clip to the panel (not to ax.patch: mplot3d
            # shrinks the axes to a square, which the zoomed scene overflows on purpose).
            clip = TransformedBbox(Bbox.from_bounds(*cell), fig.transFigure)
            for artist in ax.collections:
                artist.set_clip_path(None)
                artist.set_clip_box(clip)
                artist.set_clip_on(True)
            if i == 0:  # on the figure: mplot3d's own title sits on its shrunken square axes
                fig.text(cell[0] + 0.5 * width, top + 0.04 / fig.get_figheight(), f"frame {t}", ha="center",
                         va="bottom", fontsize=9)
        fig.text(left * 0.55, top - (i + 0.5) * height, label, rotation=90, ha="center", va="center", fontsize=9,
                 color=colour if i > 0 else "black")
    title = args.title if args.title is not None else " · ".join(s for s in (dataset.scene, name) if s)
    legend = "red dots: Dirichlet targets" if geometry.bc_as_dots else "red: Dirichlet set"
    fig.suptitle(f"{title}   ({legend}; grey ghost: ground truth)", fontsize=10,
                 y=1.0 - 0.12 / fig.get_figheight(), va="top")
    try:
        pc.save_figure(fig, args.output)
    except OSError as exc:
        pc.fail(f"cannot write '{args.output}': {exc}")
    print(args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
