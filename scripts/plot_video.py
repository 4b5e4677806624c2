#!/usr/bin/python3
"""Side-by-side MP4 of rollouts against the ground truth, one camera for all.

Reads a dataset written by `latentbench simulate` and rollout files written by
`latentbench rollout` (positions kept) and writes an H.264 MP4 (30 fps,
yuv420p, at most 1280 px wide: plays in a browser) of one sequence: the ground
truth in the first panel, then one panel per method with the ground truth as a
faint grey ghost behind it. Every panel uses the same axes box and view, fixed
for the whole video: the ground truth's box over the shown frames, grown by the
methods' frames only before their stable horizon and by at most a quarter of
the ground truth's extent (the filmstrip's rule), so a method that blows up
cannot zoom the camera out. When the prescribed motion carries the object
further than half its size (cloth, translated rods), the box instead moves with
the mean of the Dirichlet targets (`--camera auto`; `fixed` / `track` force it):
still one camera for all panels, never following a method. Prescribed Dirichlet targets are red dots (a large
Dirichlet set, e.g. the bunny's head, is tinted red). Above the panels: the
frame number and whether it lies in the training or the test window; below, a
timeline with the end of the training window and each method's stable horizon.
From its stable horizon on (first frame with RMSE > 0.5 of the rest diagonal
or a non-finite state) a method is drawn greyed out and labelled "diverged at
frame h"; it is never dropped (a non-finite frame, or one reaching far outside
the box, is labelled instead of drawn).

Long sequences are subsampled so the video has at most --max-frames frames
(default 450, 15 s at 30 fps); the frame counter shows the sequence's frame
numbers. matplotlib's FFMpegWriter runs Debian's ffmpeg (an argument vector,
no shell). The file is written under a temporary name and renamed when done.
Prints the MP4's path. Errors: `plot_video.py: error: ...`, exit status 1.

Example:
  /usr/bin/python3 scripts/plot_video.py runs/quickstart/cloth_small/data.h5 \\
      runs/quickstart/cloth_small/rollouts/{ours,supervised_l2,linear_pca}.h5 -o cloth.mp4
"""
import argparse
import math
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402
import plot_filmstrip as fs  # noqa: E402  (geometry, framing and panel layout are shared)

import numpy as np  # noqa: E402
from matplotlib import animation  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from matplotlib.transforms import Bbox, TransformedBbox  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402

FPS = 30
MAX_WIDTH_PX = 1280
MAX_HEIGHT_PX = 720
DPI = 100
MAX_COLUMNS = 4
HEADER_INCHES = 0.55  # title and frame counter
FOOTER_INCHES = 0.45  # timeline
LABEL_INCHES = 0.22  # method name above each panel
# A diverged method keeps a faded version of its colour (mixed with this grey), so it
# stays distinguishable from the grey ground-truth ghost.
DIVERGED_GREY = 0.82
DIVERGED_MIX = 0.7
DIVERGED_ALPHA = 0.6
# --camera auto tracks the Dirichlet set when it travels more than this many object sizes.
TRACK_TRAVEL = 0.5


def find_ffmpeg():
    path = shutil.which("ffmpeg")
    if path is None and os.path.exists("/usr/bin/ffmpeg"):
        path = "/usr/bin/ffmpeg"
    return path


class Panel:
    """One panel: a mesh artist updated in place every frame, an optional ghost of the
    ground truth, the Dirichlet targets and a status line."""

    def __init__(self, fig, cell, geometry, colour, lo, hi, view, zoom, label, label_colour, ghost):
        self.geometry = geometry
        self.colour = colour
        self.ax = fig.add_axes(cell, projection="3d", proj_type="ortho")
        fs.setup_axes(self.ax, lo, hi, view, zoom)
        self.ax.computed_zorder = False  # draw in creation order: ghost, mesh, targets
        self.ghost = self._make_artist(ghost=True) if ghost else None
        self.mesh = self._make_artist(ghost=False)
        self.targets = None
        if geometry.bc_as_dots:
            self.targets = self.ax.scatter([], [], [], s=9, c=pc.BC_COLOUR, depthshade=False, linewidths=0)
        # mplot3d does not clip to its axes; clip to the panel (see plot_filmstrip.py).
        clip = TransformedBbox(Bbox.from_bounds(*cell), fig.transFigure)
        for artist in self.ax.collections:
            artist.set_clip_path(None)
            artist.set_clip_box(clip)
            artist.set_clip_on(True)
        x0, y0, w, h = cell
        fig.text(x0 + 0.5 * w, y0 + h, label, ha="center", va="bottom", fontsize=10, color=label_colour,
                 fontweight="bold")
        self.status = fig.text(x0 + 0.5 * w, y0 + 0.02 * h, "", ha="center", va="bottom", fontsize=9,
                               color="firebrick")

    def _make_artist(self, ghost):
        if self.geometry.segments is not None:
            artist = Line3DCollection([], linewidths=0.6 if ghost else 1.1)
        else:
            artist = Poly3DCollection([], linewidths=0.2)
        self.ax.add_collection3d(artist)
        return artist

    def _shade(self, tri, colour):
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals / np.where(lengths > 0, lengths, 1.0)
        shade = 0.45 + 0.55 * np.abs(normals @ fs.LIGHT)
        base = np.tile(np.asarray(to_rgb(colour)), (len(tri), 1))
        if self.geometry.bc_faces is not None:
            base[self.geometry.bc_faces] = 0.35 * base[self.geometry.bc_faces] + 0.65 * fs.BC_TINT
        return np.clip(base * shade[:, None] + 0.08, 0, 1)

    def _set(self, artist, x, colour, alpha, ghost):
        g = self.geometry
        if x is None:
            artist.set_visible(False)
            return
        artist.set_visible(True)
        if g.segments is not None:
            artist.set_segments(x[g.segments])
            artist.set_color(pc.GHOST_COLOUR if ghost else colour)
            artist.set_alpha(0.45 if ghost else alpha)
            return
        tri = x[g.triangles]
        artist.set_verts(tri)
        if ghost:
            artist.set_facecolor(pc.GHOST_COLOUR)
            artist.set_edgecolor("none")
            artist.set_alpha(0.18)
        else:
            faces = self._shade(tri, colour)
            rgba = np.column_stack([faces, np.full(len(faces), alpha)])
            artist.set_facecolor(rgba)
            artist.set_edgecolor((0.0, 0.0, 0.0, 0.12 * alpha) if g.kind == "shell" else "none")

    def set_box(self, lo, hi):
        self.ax.set_xlim(lo[0], hi[0])
        self.ax.set_ylim(lo[1], hi[1])
        self.ax.set_zlim(lo[2], hi[2])

    def update(self, x, ghost, targets, diverged_at, box):
        """Draw frame positions x, the ground-truth ghost and the targets in the axes box
        (lo, hi). A diverged method (from frame diverged_at on) is greyed out, and not
        drawn at all once it is non-finite or reaches far outside the box."""
        lo, hi = box
        status = ""
        colour, alpha = self.colour, 1.0
        if diverged_at is not None:
            colour = tuple((1 - DIVERGED_MIX) * np.asarray(to_rgb(self.colour)) + DIVERGED_MIX * DIVERGED_GREY)
            alpha = DIVERGED_ALPHA
            status = f"diverged at frame {diverged_at}"
        hidden = None
        if x is not None and not np.isfinite(x).all():
            hidden = "non-finite"
        elif x is not None and fs.exploded(x, lo, hi):
            hidden = "out of view"
        if hidden:
            x = None
            status = f"{status} ({hidden})" if status else hidden
        self._set(self.mesh, x, colour, alpha, ghost=False)
        if self.ghost is not None:
            self._set(self.ghost, ghost, colour, alpha, ghost=True)
        if self.targets is not None:
            self.targets._offsets3d = (targets[:, 0], targets[:, 1], targets[:, 2])
        self.status.set_text(status)


def camera_anchor(gt, targets, used):
    """Per-frame point the tracking camera follows (T x 3): the mean of the Dirichlet
    targets (the prescribed motion), or the ground truth's box centre without them."""
    if targets.shape[1] > 0:
        return targets.mean(axis=1)
    g = gt[:, used]
    return 0.5 * (g.min(axis=1) + g.max(axis=1))


def should_track(gt, anchor, used):
    """Track when the prescribed motion carries the object further than half its own size
    (e.g. the cloth's corners travel 4 m with a 0.8 m cloth): a fixed camera would show a
    small object crossing a large empty box."""
    g = gt[:, used]
    size = np.max(g.max(axis=1) - g.min(axis=1))
    travel = np.max(anchor.max(axis=0) - anchor.min(axis=0))
    return bool(travel > TRACK_TRAVEL * size)


def grid_shape(num_panels):
    """(columns, rows): at most MAX_COLUMNS columns, rows as full as possible."""
    rows = int(math.ceil(num_panels / MAX_COLUMNS))
    cols = int(math.ceil(num_panels / rows))
    return cols, rows


def video_layout(lo, hi, view, num_panels):
    """Figure size (inches, at DPI giving even pixel sizes within MAX_WIDTH_PX x
    MAX_HEIGHT_PX), panel size (inches) and zoom."""
    panel_w, panel_h, zoom = fs.panel_layout(lo, hi, view)
    panel_h += LABEL_INCHES
    cols, rows = grid_shape(num_panels)
    width, height = cols * panel_w, rows * panel_h + HEADER_INCHES + FOOTER_INCHES
    scale = min(MAX_WIDTH_PX / (width * DPI), MAX_HEIGHT_PX / (height * DPI))
    # Panels scale with the figure (zoom is relative to the panel); header and footer keep their size.
    panel_w, panel_h = panel_w * scale, panel_h * scale
    width_px = 2 * int(cols * panel_w * DPI / 2)
    height_px = 2 * int(math.ceil((rows * panel_h + HEADER_INCHES + FOOTER_INCHES) * DPI / 2))
    # matplotlib truncates inches x dpi to whole pixels: nudge up so it lands on the even size.
    return ((width_px + 0.01) / DPI, (height_px + 0.01) / DPI), (panel_w, panel_h), zoom


def draw_timeline(fig, num_frames, train_frames, horizons, colours):
    """A strip below the panels: the training window shaded, its end marked, each
    method's stable horizon as a tick in its colour; returns the moving cursor."""
    height = fig.get_figheight()
    ax = fig.add_axes([0.06, 0.12 / height, 0.88, 0.16 / height])
    ax.set_xlim(0, max(num_frames - 1, 1))
    ax.set_ylim(0, 1)
    ax.set_yticks([])
    ax.tick_params(axis="x", labelsize=7, length=2, pad=1)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)
    if train_frames <= 0:
        ax.text(0, 1.05, "no training frames in this sequence: every frame is a test frame", fontsize=7,
                color="#b35900", va="bottom", ha="left")
    else:
        ax.axvspan(0, min(train_frames, num_frames - 1), color="#cfe3f5", lw=0)
        if train_frames < num_frames:
            ax.axvline(train_frames, color="#1f77b4", lw=1.2)
            ax.text(train_frames, 1.05, " end of training window", fontsize=7, color="#1f77b4", va="bottom",
                    ha="left" if train_frames < 0.7 * num_frames else "right", transform=ax.transData)
    for label, h in horizons.items():
        if h is not None:
            ax.plot([h, h], [0, 0.6], color=colours[label], lw=2)
    cursor = ax.axvline(0, color="black", lw=1.5)
    return cursor


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("dataset", help="dataset HDF5 written by `latentbench simulate`")
    parser.add_argument("rollouts", nargs="*", help="rollout HDF5 files written by `latentbench rollout`")
    parser.add_argument("-o", "--output", required=True, help="output MP4")
    parser.add_argument("--sequence", default=None, help="sequence name or index (default: first one with rollouts)")
    parser.add_argument("--max-frames", type=int, default=450,
                        help="subsample to at most this many video frames (default 450 = 15 s at 30 fps)")
    parser.add_argument("--every", type=int, default=1, metavar="K", help="use every K-th frame at least (default 1)")
    parser.add_argument("--view", type=float, nargs=2, metavar=("ELEV", "AZIM"), default=(12.0, -70.0),
                        help="camera elevation and azimuth in degrees (default 12 -70)")
    parser.add_argument("--camera", choices=("auto", "fixed", "track"), default="auto",
                        help="fixed: one box over all frames; track: the box moves with the Dirichlet set "
                             "(never with a method); auto (default): track if the set travels further than half "
                             "the object's size")
    parser.add_argument("--no-ghost", action="store_true", help="no ground-truth ghost behind the methods")
    parser.add_argument("--title", default=None, help="title, followed by the sequence (default: the scene)")
    args = parser.parse_args(argv)
    if args.max_frames < 2:
        pc.fail("--max-frames must be at least 2")
    if args.every < 1:
        pc.fail("--every must be at least 1")
    pc.require_h5py()
    ffmpeg = find_ffmpeg()
    if ffmpeg is None:
        pc.fail("ffmpeg is not installed (Debian package ffmpeg; scripts/run setup installs it)")
    pc.plt.rcParams["animation.ffmpeg_path"] = ffmpeg

    dataset, key, name, gt, targets, shown, predictions = fs.load_scene_rollouts(args.dataset, args.rollouts,
                                                                                 args.sequence)

    num_frames = min([len(gt)] + [len(x) for x in predictions])
    stride = max(args.every, int(math.ceil(num_frames / args.max_frames)))
    frames = np.arange(0, num_frames, stride)
    train_frames = dataset.train_frames.get(key, 0)
    labels = [r.label for r in shown]
    colours = pc.colour_map(labels)
    # Stable horizon: the rollout's own attribute (first frame with RMSE > 0.5 or non-finite).
    horizons = {}
    for r, x in zip(shown, predictions):
        h = int(r.attrs.get("stable_horizon", len(x)))
        finite = np.isfinite(x).all(axis=(1, 2))
        if not finite.all():
            h = min(h, int(np.flatnonzero(~finite)[0]))
        horizons[r.label] = h if h < num_frames else None

    # One camera for every panel. Its box is framed on the ground truth and on each
    # method's frames before its horizon only (capped growth, see fs.axes_box); when
    # tracking, on positions relative to the anchor, and the box moves with the anchor.
    geometry = fs.Geometry(dataset)
    used = geometry.used_vertices
    anchor = camera_anchor(gt[:num_frames], targets[:num_frames], used)
    track = args.camera == "track" or (args.camera == "auto" and should_track(gt[frames], anchor[frames], used))
    offset = anchor if track else np.zeros_like(anchor)
    framing = []
    for r, x in zip(shown, predictions):
        h = horizons[r.label]
        f = frames if h is None else frames[frames < h]
        framing.append(x[f][:, used] - offset[f][:, None, :])
    lo, hi = fs.axes_box(gt[frames][:, used] - offset[frames][:, None, :], framing)

    (fig_w, fig_h), (panel_w, panel_h), zoom = video_layout(lo, hi, args.view, 1 + len(shown))
    fig = pc.plt.figure(figsize=(fig_w, fig_h), dpi=DPI)
    cols, rows = grid_shape(1 + len(shown))
    pw, ph = panel_w / fig_w, panel_h / fig_h
    lh = LABEL_INCHES / fig_h
    top = 1.0 - HEADER_INCHES / fig_h
    x_margin = (1.0 - cols * pw) / 2
    panels = []
    for i, label in enumerate(["ground truth"] + labels):
        row, col = divmod(i, cols)
        cell = [x_margin + col * pw, top - (row + 1) * ph, pw, ph - lh]
        colour = "0.6" if i == 0 else colours[label]
        panels.append(Panel(fig, cell, geometry, colour, lo, hi, args.view, zoom, label,
                            "black" if i == 0 else colours[label], ghost=(i > 0 and not args.no_ghost)))
    title = " · ".join(s for s in (args.title if args.title is not None else dataset.scene, name) if s)
    legend = "red dots: Dirichlet targets" if geometry.bc_as_dots else "red: Dirichlet set"
    fig.text(0.01, 1.0 - 0.08 / fig_h, title, ha="left", va="top", fontsize=11, fontweight="bold")
    camera = "camera follows the Dirichlet set" if track else "fixed camera"
    fig.text(0.01, 1.0 - 0.32 / fig_h, f"{legend}; grey ghost: ground truth; greyed out: diverged; {camera}",
             ha="left", va="top", fontsize=8, color="0.3")
    counter = fig.text(0.99, 1.0 - 0.08 / fig_h, "", ha="right", va="top", fontsize=11, family="monospace")
    window = fig.text(0.99, 1.0 - 0.32 / fig_h, "", ha="right", va="top", fontsize=9)
    cursor = draw_timeline(fig, num_frames, train_frames, horizons, colours)

    output = args.output
    directory = os.path.dirname(output)
    if directory:
        os.makedirs(directory, exist_ok=True)
    temp = f"{output}.tmp-{os.getpid()}.mp4"
    writer = animation.FFMpegWriter(fps=FPS, codec="libx264", bitrate=-1,
                                    extra_args=["-pix_fmt", "yuv420p", "-preset", "veryfast", "-crf", "23",
                                                "-movflags", "+faststart"],
                                    metadata={"title": title, "comment": "latentbench scripts/plot_video.py"})
    try:
        with writer.saving(fig, temp, dpi=DPI):
            for t in frames:
                t = int(t)
                counter.set_text(f"frame {t:>{len(str(num_frames - 1))}d} / {num_frames - 1}")
                in_training = t < train_frames
                window.set_text("training window" if in_training else "test window (beyond training)")
                window.set_color("#1f77b4" if in_training else "#b35900")
                box = (lo + offset[t], hi + offset[t])
                for panel in panels:
                    panel.set_box(*box)
                panels[0].update(gt[t], None, targets[t], None, box)
                for panel, r, x in zip(panels[1:], shown, predictions):
                    h = horizons[r.label]
                    diverged = h is not None and t >= h
                    panel.update(x[t], gt[t], targets[t], h if diverged else None, box)
                cursor.set_xdata([t, t])
                writer.grab_frame()
        os.replace(temp, output)
    except (OSError, RuntimeError, ValueError, subprocess.SubprocessError) as exc:
        pc.fail(f"cannot write '{output}': {exc}")
    finally:
        pc.plt.close(fig)
        if os.path.exists(temp):
            os.remove(temp)
    print(output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
