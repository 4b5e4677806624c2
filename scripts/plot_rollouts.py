#!/usr/bin/python3
"""Per-frame metric curves of latentbench rollouts, every method overlaid.

Reads one or more rollout files written by `latentbench rollout` and writes, for
each test sequence, one PNG per metric with every method (every rollout of that
sequence, across all files) overlaid:

  <seq>_rmse.png          position RMSE relative to the rest bounding-box diagonal (log scale),
                          with the stability threshold (0.5) and each method's stable horizon marked
  <seq>_bc_violation.png  boundary violation max_i |x_i - x*_i| in metres (log scale)
  <seq>_kinetic.png       kinetic energy in joules with the ground-truth curve (paper Fig. 12);
  <seq>_kinetic_free.png  the free DOFs' kinetic energy relative to the boundary's rigid motion;
                          log scale when the values span more than three decades

`--train-frames N` marks the end of the training frames (frames >= N are
extrapolation). `--metrics` selects other columns of the file (e.g. elastic,
residual, sted_spatial); energy columns get their ground-truth curve too.
Prints the paths of the PNGs it wrote. A missing or corrupt input is reported
as `plot_rollouts.py: error: ...` with exit status 1.

Example:
  /usr/bin/python3 scripts/plot_rollouts.py results/cloth_rollouts.h5 -o results/figures/cloth \\
      --title "cloth (small)" --train-frames 750
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402

import numpy as np  # noqa: E402

# Thresholds of the stable horizon (src/eval/metrics.hpp, kUnstableRmse).
UNSTABLE_RMSE = 0.5

# Diverging rollouts reach huge values; the y axis stops at a cap so that the
# stable methods stay readable: relative RMSE at 20x the instability threshold,
# energies at CAP_FACTOR x the ground truth's maximum, other metrics at CAP_FACTOR x
# their maximum over the frames where each rollout was still stable.
RMSE_CAP = 20 * UNSTABLE_RMSE
CAP_FACTOR = 100.0
# On log axes, energies are shown down to this fraction of the ground truth's maximum.
FLOOR_BELOW_GT_MAX = 1e-6

# column -> (y label, scale: "log" | "linear" | "auto", ground-truth column or None, cap)
# cap: a number, "gt" (CAP_FACTOR x max ground truth), "stable" (CAP_FACTOR x max over
# the stable frames) or None.
METRICS = {
    "rmse": ("relative position RMSE (÷ rest bbox diagonal)", "log", None, RMSE_CAP),
    "bc_violation": ("boundary violation max |x − x*| (m)", "log", None, "stable"),
    "kinetic": ("kinetic energy (J)", "auto", "kinetic_gt", "gt"),
    "kinetic_free": ("free-DOF kinetic energy rel. to the boundary's rigid motion (J)", "auto", "kinetic_free_gt",
                     "gt"),
    "elastic": ("elastic energy (J)", "auto", "elastic_gt", "gt"),
    "residual": ("physics residual: per-DOF RMS of ∇E on free DOFs / (m̄|g|)", "log", None, "stable"),
    "sted_spatial": ("STED spatial: 1-ring deviation of relative edge-length differences", "log", None, "stable"),
    "sted_temporal": ("STED temporal: relative vertex-speed difference", "log", None, "stable"),
    "integrate_seconds": ("integration time per frame (s)", "log", None, None),
    "decode_seconds": ("decode time per frame (s)", "log", None, None),
}
DEFAULT_METRICS = "rmse,bc_violation,kinetic,kinetic_free"


def positive_finite(values):
    v = np.asarray(values, dtype=float)
    return v[np.isfinite(v) & (v > 0)]


def choose_scale(scale, curves):
    if scale != "auto":
        return scale
    values = np.concatenate([positive_finite(c) for c in curves] or [np.array([])])
    if values.size < 2:
        return "linear"
    low, high = np.percentile(values, [2, 100])
    return "log" if low > 0 and high / low > 1e3 else "linear"


def masked(values, log):
    """Non-finite values (a diverged rollout) and, on log axes, non-positive ones become gaps."""
    v = np.array(values, dtype=float)
    bad = ~np.isfinite(v)
    if log:
        bad |= v <= 0
    v[bad] = np.nan
    return v


def mark_training(ax, train_frames, num_frames):
    if train_frames is None or train_frames <= 0:
        return
    ax.axvline(train_frames, color="0.3", linestyle="--", linewidth=1.0, label=f"end of training frames ({train_frames})")
    if train_frames < num_frames:
        ax.axvspan(train_frames, num_frames, color="0.5", alpha=0.07, linewidth=0)


def plot_metric(rollouts, column, sequence, colours, args):
    ylabel, scale, gt_column, cap = METRICS.get(column, (column.replace("_", " "), "auto", None, "stable"))
    if gt_column is None and f"{column}_gt" in rollouts[0].columns:
        gt_column = f"{column}_gt"
    curves = [r.column(column) for r in rollouts]
    gt = None
    if gt_column is not None and gt_column in rollouts[0].columns:
        # Every rollout of a sequence carries the same ground truth, but a diverged
        # rollout's rows end in NaN: merge, taking each frame from any rollout that has it.
        gt = np.full(max(r.num_frames for r in rollouts), np.nan)
        for r in rollouts:
            values = r.column(gt_column)
            fill = np.isnan(gt[: len(values)]) & np.isfinite(values)
            gt[: len(values)][fill] = values[fill]
    floor = None  # on log axes, the lowest value worth showing
    stable = np.concatenate([positive_finite(c[: int(r.attrs.get("stable_horizon", r.num_frames))])
                             for r, c in zip(rollouts, curves)])
    stable_cap = CAP_FACTOR * stable.max() if stable.size else None
    if cap == "gt":
        # Never hide a stable method's curve, however far it is from the ground truth.
        gt_values = positive_finite(gt) if gt is not None else np.array([])
        caps = [c for c in (CAP_FACTOR * gt_values.max() if gt_values.size else None,
                            2.0 * stable.max() if stable.size else None) if c is not None]
        cap = max(caps) if caps else None
        # Show the ground truth's range but not numerically-zero steady states (1e-18 J).
        floor = (max(0.1 * np.percentile(gt_values, 1), FLOOR_BELOW_GT_MAX * gt_values.max())
                 if gt_values.size else None)
    elif cap == "stable":
        cap = stable_cap
    if cap is not None:
        curves_for_scale = [np.minimum(c, cap) for c in curves]
    else:
        curves_for_scale = curves
    scale = choose_scale(scale, curves_for_scale + ([gt] if gt is not None else []))
    # A log axis needs positive data (rods hold their roots exactly: zero boundary violation).
    log = scale == "log" and any(positive_finite(c).size > 0 for c in curves_for_scale)
    num_frames = max(r.num_frames for r in rollouts)

    fig, ax = pc.plt.subplots(figsize=(9.5, 4.2), layout="constrained")
    if gt is not None:
        ax.plot(np.arange(len(gt)), masked(gt, log), color=pc.GROUND_TRUTH_COLOUR, linewidth=2.2, alpha=0.8,
                label="ground truth", zorder=2)
    for r, values in zip(rollouts, curves):
        label = r.label
        if column == "rmse" and "stable_horizon" in r.attrs:
            label += f" (stable {int(r.attrs['stable_horizon'])}/{r.num_frames})"
        horizon = int(r.attrs.get("stable_horizon", r.num_frames))
        if column != "rmse" and horizon < r.num_frames:
            label += f" (unstable from frame {horizon})"
        elif column in ("kinetic", "kinetic_free"):
            ratios = [f"{w} {float(r.attrs[w + '_ke_ratio']):.2f}" for w in ("train", "test")
                      if w + "_ke_ratio" in r.attrs and np.isfinite(float(r.attrs[w + "_ke_ratio"]))]
            if ratios:
                label += f" (free-DOF KE ratio {', '.join(ratios)})"
        finite = values[2:][np.isfinite(values[2:])] if len(values) > 2 else values[np.isfinite(values)]
        if finite.size > 0 and np.all(finite == 0):
            label += " (exactly 0)"
        y = masked(values, log)
        ax.plot(np.arange(len(y)), y, color=colours[r.label], linewidth=1.3, label=label, zorder=3)
        # Where a rollout stopped being stable (NaN or RMSE > 0.5).
        if column == "rmse" and horizon < r.num_frames:
            finite_idx = np.flatnonzero(np.isfinite(y[: horizon + 1]))
            if finite_idx.size:
                i = finite_idx[-1]
                ax.plot([i], [y[i]], marker="X", markersize=9, color=colours[r.label], markeredgecolor="black",
                        markeredgewidth=0.6, linestyle="none", zorder=4)
    if column == "rmse":
        ax.axhline(UNSTABLE_RMSE, color="firebrick", linestyle=":", linewidth=1.0,
                   label=f"instability threshold ({UNSTABLE_RMSE})")
        if any(int(r.attrs.get("stable_horizon", r.num_frames)) < r.num_frames for r in rollouts):
            ax.plot([], [], marker="X", markersize=8, color="0.6", markeredgecolor="black", markeredgewidth=0.6,
                    linestyle="none", label="end of stable horizon")
    mark_training(ax, args.train_frames, num_frames)
    if log:
        ax.set_yscale("log")
    clipped = cap is not None and any(np.nanmax(np.where(np.isfinite(c), c, np.nan), initial=-np.inf) > cap
                                      for c in curves)
    if log and floor is not None and ax.get_ylim()[0] < floor:
        ax.set_ylim(bottom=floor)
    if clipped:
        bottom, top = ax.get_ylim()
        ax.set_ylim(bottom, min(top, cap))
        ax.text(0.995, 0.99, "axis clipped: diverging curves leave the plot", transform=ax.transAxes,
                ha="right", va="top", fontsize=7, color="0.35")
    ax.set_xlim(0, max(num_frames - 1, 1))
    ax.set_xlabel("frame")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{args.title}: {sequence}" if args.title else sequence, fontsize=11)
    pc.style_axes(ax)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0, frameon=False)
    path = os.path.join(args.output, f"{pc.safe_name(sequence)}_{pc.safe_name(column)}.png")
    return pc.save_figure(fig, path)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("rollouts", nargs="+", help="rollout HDF5 files written by `latentbench rollout`")
    parser.add_argument("-o", "--output", required=True, help="output directory for the PNGs")
    parser.add_argument("--title", default="", help="figure title prefix (e.g. the scene)")
    parser.add_argument("--train-frames", type=int, default=None, help="mark the end of the training frames")
    parser.add_argument("--metrics", default=DEFAULT_METRICS,
                        help=f"comma-separated metric columns to plot (default {DEFAULT_METRICS})")
    args = parser.parse_args(argv)
    pc.require_h5py()

    try:
        rollouts = pc.load_all_rollouts(args.rollouts)
        if not rollouts:
            pc.fail("no rollouts in " + ", ".join(args.rollouts))
        columns = [c.strip() for c in args.metrics.split(",") if c.strip()]
        if args.metrics == DEFAULT_METRICS:
            # Files written before a default column existed (kinetic_free: issue 10) plot the rest.
            columns = [c for c in columns if c in rollouts[0].columns]
        for column in columns:
            if column not in rollouts[0].columns:
                pc.fail(f"unknown metric '{column}' (columns: {', '.join(rollouts[0].columns)})")
        colours = pc.colour_map(r.label for r in rollouts)
        sequences = []
        for r in rollouts:
            if r.sequence not in sequences:
                sequences.append(r.sequence)
        written = []
        for sequence in sequences:
            group = [r for r in rollouts if r.sequence == sequence]
            for column in columns:
                written.append(plot_metric(group, column, sequence, colours, args))
    except pc.InputError as exc:
        pc.fail(str(exc))
    except OSError as exc:
        pc.fail(f"cannot write figures to '{args.output}': {exc}")
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
