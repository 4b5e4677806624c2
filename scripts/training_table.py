"""The published copy of a suite's tables/training_<scene>.csv: fewer epochs, the same columns.

A run writes every epoch of every training run (35 fits of 3,000 epochs make a 5.5 MB file).
`make_report.py publish` keeps, of each run (method, seed, stage), epochs 1 to 10, every k-th
epoch, the last one and the one with the lowest validation loss, with k the smallest of
1, 2, 5, 10, 20, ... that leaves at most MAX_ROWS epochs; a comment line says so.
`compare_tables.py` thins a full file the same way before comparing it with a thinned one,
so `scripts/run reproduce` still compares every kept cell. The figures are drawn from the
run's full file before publication.
"""
import csv
import io
import math

MAX_ROWS = 300
MARKER = "# Published copy:"
NOTE = (f"{MARKER} of each run (method, seed, stage) epochs 1-10, every k-th epoch (k the smallest of 1, 2, 5, "
        f"10, 20, ... leaving at most {MAX_ROWS}), the last epoch and the lowest-validation epoch; the run "
        "directory's file has every epoch")


def is_training_table(name):
    return name.startswith("training_") and name.endswith(".csv")


def is_thinned(text):
    return any(line.startswith(MARKER) for line in text.splitlines())


def stride(epochs):
    """The smallest of 1, 2, 5, 10, 20, 50, ... that leaves at most MAX_ROWS of `epochs`."""
    k = 1
    while math.ceil(epochs / k) > MAX_ROWS:
        digits = str(k)
        k = k * 2 if digits[0] in "15" else k * 5 // 2  # 1 -> 2 -> 5 -> 10 -> 20 -> 50
    return k


def _number(text):
    try:
        return float(text)
    except ValueError:
        return math.nan


def thin(text):
    """The thinned file's text (comments kept, the note added after them); a file already thinned,
    or one with nothing to drop, is returned as is."""
    if is_thinned(text):
        return text
    lines = text.splitlines()
    comments = [line for line in lines if line.startswith("#")]
    rows = list(csv.reader(line for line in lines if not line.startswith("#")))
    if not rows:
        return text
    header, body = rows[0], rows[1:]
    try:
        key_cols = [header.index(c) for c in ("method", "seed", "stage")]
        epoch_col, val_col = header.index("epoch"), header.index("validation_loss")
    except ValueError:
        return text  # not a training table: leave it alone
    groups = {}
    for row in body:
        groups.setdefault(tuple(row[c] for c in key_cols), []).append(row)
    keep = set()
    for key, members in groups.items():
        k = stride(len(members))
        last = max(int(r[epoch_col]) for r in members)
        valid = [(v, int(r[epoch_col])) for r in members if not math.isnan(v := _number(r[val_col]))]
        best = min(valid)[1] if valid else None
        for r in members:
            e = int(r[epoch_col])
            if e <= 10 or e % k == 0 or e == last or e == best:
                keep.add((key, e))
    if len(keep) == len(body):
        return text  # nothing to drop: the file as the run wrote it
    out = io.StringIO()
    for line in comments:
        out.write(line + "\n")
    out.write(NOTE + "\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(header)
    for row in body:
        if (tuple(row[c] for c in key_cols), int(row[epoch_col])) in keep:
            writer.writerow(row)
    return out.getvalue()
