#!/usr/bin/python3
"""Training curves of a latentbench suite: the loss per epoch of every training run.

Reads tables/training_<scene>.csv (written by `latentbench run`; columns method, seed,
stage, epoch, train_loss, validation_loss) and writes one PNG per method,

  <output dir>/training_<method>.png

with every seed in one plot (one colour per seed; training loss solid, validation loss
dashed), the loss on a log scale (a symmetric log scale if it takes values <= 0, as a
self-supervised energy may), and the stages of a multi-stage training (the autoencoder's
physics fine-tuning, Tan et al.'s three stages) one after the other with their boundaries
marked. Prints the paths of the PNGs it wrote. A missing or malformed input is reported
as `plot_training.py: error: ...` with exit status 1.

Example:
  /usr/bin/python3 scripts/plot_training.py runs/quickstart/tables/training_cloth.csv \\
      -o runs/quickstart/figures/cloth --title cloth
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402

import numpy as np  # noqa: E402

COLUMNS = ["method", "seed", "stage", "epoch", "train_loss", "validation_loss"]


def number(text, path, line, column):
    """A float from a CSV field ("" -> None); InputError naming the file and line otherwise."""
    if text == "":
        return None
    try:
        return float(text)
    except ValueError:
        raise pc.InputError(f"'{path}' line {line}: {column} '{text}' is not a number") from None


def read_curves(path):
    """{method: {seed: [(stage, epochs, train, validation)]}} in the file's order."""
    if not os.path.isfile(path):
        raise pc.InputError(f"'{path}' does not exist or is not a file")
    with open(path, newline="", encoding="utf-8") as f:
        lines = [(n, text) for n, text in enumerate(f, start=1) if not text.startswith("#")]
    if not lines:
        raise pc.InputError(f"'{path}' has no header (expected columns {', '.join(COLUMNS)})")
    reader = csv.reader([text for _, text in lines])
    header = next(reader)
    if header != COLUMNS:
        raise pc.InputError(f"'{path}': header {header} is not {COLUMNS}")
    methods = {}
    for (line, _), row in zip(lines[1:], reader):
        if len(row) != len(COLUMNS):
            raise pc.InputError(f"'{path}' line {line}: {len(row)} fields, expected {len(COLUMNS)}")
        method, seed, stage = row[0], row[1], row[2]
        epoch = number(row[3], path, line, "epoch")
        if epoch is None or epoch < 1 or epoch != int(epoch):
            raise pc.InputError(f"'{path}' line {line}: epoch '{row[3]}' is not a whole number >= 1")
        train = number(row[4], path, line, "train_loss")
        val = number(row[5], path, line, "validation_loss")
        stages = methods.setdefault(method, {}).setdefault(seed, [])
        if not stages or stages[-1][0] != stage:
            stages.append((stage, [], [], []))
        stages[-1][1].append(int(epoch))
        stages[-1][2].append(math.nan if train is None else train)
        stages[-1][3].append(math.nan if val is None else val)
    return methods


def y_scale(seeds):
    """("log", None) if every recorded loss is positive; else ("symlog", linthresh): a
    self-supervised loss is an energy and may be negative, which a log axis would hide."""
    values = np.array([x for stages in seeds.values() for _, _, train, val in stages for x in train + val], dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0 or (values > 0).all():
        return "log", None
    magnitudes = np.abs(values[values != 0])
    top = magnitudes.max() if magnitudes.size else 1.0
    return "symlog", max(magnitudes.min() if magnitudes.size else 1.0, 1e-6 * top)


def plot_method(method, seeds, title, out_dir):
    fig, ax = pc.plt.subplots(figsize=(7.0, 4.2))
    # Stage offsets shared by every seed (a stage's length is its longest run), so that
    # stage boundaries line up across seeds.
    order, length = [], {}
    for stages in seeds.values():
        for stage, epochs, _, _ in stages:
            if stage not in length:
                order.append(stage)
            length[stage] = max(length.get(stage, 0), max(epochs))
    offset, start = 0, {}
    for stage in order:
        start[stage] = offset
        offset += length[stage]
    colours = pc.colour_map(list(seeds))
    scale, linthresh = y_scale(seeds)
    drawn = any_validation = False
    for seed, stages in seeds.items():
        label = f"seed {seed}" if seed != "" else "run"
        for i, (stage, epochs, train, val) in enumerate(stages):
            x = np.asarray(epochs) + start[stage]
            t, v = np.asarray(train, dtype=float), np.asarray(val, dtype=float)
            if np.isfinite(t).any():
                ax.plot(x, t, color=colours[seed], linewidth=1.2, label=label if i == 0 else None)
                drawn = True
            if np.isfinite(v).any():
                ax.plot(x, v, color=colours[seed], linewidth=1.0, linestyle="--",
                        label=f"{label} (validation)" if i == 0 else None)
                drawn = any_validation = True
    if drawn and scale == "log":
        ax.set_yscale("log")
    elif drawn:
        ax.set_yscale("symlog", linthresh=linthresh)
    if len(order) > 1:
        for stage in order:
            ax.axvline(start[stage] + 0.5, color=pc.GHOST_COLOUR, linewidth=0.8, linestyle=":")
            ax.text(start[stage] + 0.5, 1.0, f" {stage}", transform=ax.get_xaxis_transform(), fontsize=8,
                    va="top", ha="left", color="0.3")
    ax.set_xlabel("epoch" + (" (stages one after the other)" if len(order) > 1 else ""))
    what = "loss" if any_validation else "training loss"
    axis = "log scale" if scale == "log" else "symlog: has values ≤ 0"
    ax.set_ylabel(f"{what} ({axis}{'; validation dashed' if any_validation else ''})")
    ax.set_title(f"{title}: {method}")
    pc.style_axes(ax)
    if drawn:
        ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    return pc.save_figure(fig, os.path.join(out_dir, f"training_{pc.safe_name(method)}.png"))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", help="tables/training_<scene>.csv of a suite")
    parser.add_argument("-o", "--output", required=True, help="directory for training_<method>.png")
    parser.add_argument("--title", default="", help="scene label for the titles (default: the file's name)")
    args = parser.parse_args()
    title = args.title or os.path.splitext(os.path.basename(args.csv))[0]
    try:
        methods = read_curves(args.csv)
    except pc.InputError as exc:
        pc.fail(str(exc))
    for method, seeds in methods.items():
        print(plot_method(method, seeds, title, args.output))


if __name__ == "__main__":
    main()
