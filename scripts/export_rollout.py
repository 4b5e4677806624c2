#!/usr/bin/python3
"""Export latentbench rollouts (and the ground truth) as ParaView time series.

Reads rollout files written by `latentbench rollout` (positions kept) and the
dataset they were rolled out on (`latentbench simulate`: it holds the mesh), and
writes one time series per rollout (method x sequence) into the output folder,
with meshio (Debian's python3-meshio):

  --format vtu   (default) <series>.pvd + <series>/<series>_<frame>.vtu: one
                 VTU per frame with the deformed positions as its points, so the
                 mesh moves when ParaView plays the .pvd.
  --format xdmf  <series>.xdmf + <series>.h5: the rest mesh once and the fields
                 per frame (meshio's XDMF time series cannot move points): apply
                 ParaView's "Warp By Vector" with `displacement`, scale 1, to see
                 the deformed shape.

Per-vertex fields of every frame:
  displacement  x_t - rest (m), 3 components
  error         x_t - x_t(ground truth) (m), 3 components; zero for the ground truth
  dirichlet     1 on the Dirichlet (prescribed) vertices, 0 elsewhere

Cells keep the element type of the dataset: tetrahedra (solids), triangles
(cloth), line segments (rods; VTK_LINE, shown as polylines in ParaView). The
time of frame t is t * dt seconds (the dataset's dt), so ParaView's time shows
seconds; the frame number is time / dt. A rollout that diverged (non-finite
positions from some frame on) is exported up to its last finite frame, with a
note on stderr; finite frames after the stable horizon are exported as they are
(a note names the horizon). `--ground-truth` also exports the ground truth of the
rollouts' sequences (series `ground_truth_<sequence>`); with no rollout file
it exports the ground truth of --sequence (default: every sequence).

Series are named `<method>_<sequence>` (the file name is added when the same
method and sequence appear in several files). Every series is written under a
temporary name and renamed when complete. Prints the .pvd / .xdmf paths it
wrote, one per line. Errors: `export_rollout.py: error: ...`, exit status 1.

Examples:
  /usr/bin/python3 scripts/export_rollout.py runs/quickstart/cloth_small/rollouts/ours.h5 \\
      --data runs/quickstart/cloth_small/data.h5 -o /tmp/cloth_vtk --ground-truth --every 5
  /usr/bin/python3 scripts/export_rollout.py --data data.h5 -o gt_only --format xdmf
"""
import argparse
import os
import shutil
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402

import numpy as np  # noqa: E402

try:
    import meshio  # noqa: E402
except ImportError:  # reported in main()
    meshio = None

# meshio cell type of each element width of a dataset (elements M x K).
CELL_TYPES = {2: "line", 3: "triangle", 4: "tetra"}
FORMATS = ("vtu", "xdmf")


class Series:
    """One time series to write: positions per frame and the ground truth they are compared with."""

    def __init__(self, name, positions, ground_truth, description):
        self.name = name
        self.positions = positions  # T x N x 3
        self.ground_truth = ground_truth  # T' x N x 3, T' >= T
        self.description = description


def finite_prefix(positions):
    """Number of leading frames whose positions are all finite."""
    finite = np.isfinite(positions).all(axis=(1, 2))
    bad = np.flatnonzero(~finite)
    return int(bad[0]) if bad.size else len(positions)


def frame_fields(x, x_gt, rest, dirichlet):
    return {
        "displacement": np.ascontiguousarray(x - rest),
        "error": np.ascontiguousarray(x - x_gt),
        "dirichlet": dirichlet,
    }


def write_pvd(path, entries):
    """ParaView's collection file: one DataSet per frame (time, relative file name).
    meshio writes the VTU files; this index is built with ElementTree."""
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    collection = ET.SubElement(root, "Collection")
    for time, file in entries:
        ET.SubElement(collection, "DataSet", timestep=repr(float(time)), group="", part="0", file=file)
    ET.indent(root)
    ET.ElementTree(root).write(path, xml_declaration=True, encoding="utf-8")


def export_vtu(series, frames, mesh, out_dir, temp_dir):
    """<name>.pvd and <name>/<name>_<frame>.vtu, built in temp_dir and moved into out_dir."""
    rest, cells, dirichlet, dt = mesh
    frame_dir = os.path.join(temp_dir, series.name)
    os.makedirs(frame_dir)
    entries = []
    width = max(5, len(str(frames[-1])))
    for t in frames:
        x = series.positions[t]
        file = f"{series.name}_{t:0{width}d}.vtu"
        m = meshio.Mesh(x, cells, point_data=frame_fields(x, series.ground_truth[t], rest, dirichlet))
        meshio.write(os.path.join(frame_dir, file), m, file_format="vtu")
        entries.append((t * dt, f"{series.name}/{file}"))
    write_pvd(os.path.join(temp_dir, series.name + ".pvd"), entries)
    final_dir = os.path.join(out_dir, series.name)
    if os.path.isdir(final_dir):
        shutil.rmtree(final_dir)
    os.replace(frame_dir, final_dir)
    final = os.path.join(out_dir, series.name + ".pvd")
    os.replace(os.path.join(temp_dir, series.name + ".pvd"), final)
    return final


def fix_polyline_topology(xdmf_path):
    """meshio 5.0's XDMF TimeSeriesWriter writes line cells as TopologyType="Polyline"
    without NodesPerElement, which XDMF readers need for polylines; add it (2 nodes)."""
    tree = ET.parse(xdmf_path)
    changed = False
    for topology in tree.getroot().iter("Topology"):
        if topology.get("TopologyType") == "Polyline" and "NodesPerElement" not in topology.attrib:
            topology.set("NodesPerElement", "2")
            changed = True
    if changed:
        ET.register_namespace("xi", "http://www.w3.org/2003/XInclude")  # keep meshio's prefix
        tree.write(xdmf_path, xml_declaration=True, encoding="utf-8")


def export_xdmf(series, frames, mesh, out_dir, temp_dir):
    """<name>.xdmf + <name>.h5 (rest geometry, fields per frame), built in temp_dir."""
    rest, cells, dirichlet, dt = mesh
    # meshio writes the .h5 beside the current directory, named after the .xdmf's stem.
    cwd = os.getcwd()
    os.chdir(temp_dir)
    try:
        with meshio.xdmf.TimeSeriesWriter(series.name + ".xdmf") as writer:
            writer.write_points_cells(rest, cells)
            for t in frames:
                writer.write_data(t * dt, point_data=frame_fields(series.positions[t], series.ground_truth[t], rest,
                                                                  dirichlet))
    finally:
        os.chdir(cwd)
    fix_polyline_topology(os.path.join(temp_dir, series.name + ".xdmf"))
    os.replace(os.path.join(temp_dir, series.name + ".h5"), os.path.join(out_dir, series.name + ".h5"))
    final = os.path.join(out_dir, series.name + ".xdmf")
    os.replace(os.path.join(temp_dir, series.name + ".xdmf"), final)
    return final


def collect_series(dataset, rollout_paths, sequence_arg, ground_truth):
    """The series to write: every rollout (with positions) of the chosen sequences, then
    the ground truth of those sequences if asked."""
    rollouts = pc.load_all_rollouts(rollout_paths)
    if sequence_arg is not None:
        _, name = dataset.find_sequence(sequence_arg)
        rollouts = [r for r in rollouts if r.sequence == name]
        if rollout_paths and not rollouts:
            raise pc.InputError(f"no rollout of sequence '{name}' in {', '.join(rollout_paths)}")
    truth = {}  # sequence name -> T x N x 3

    def gt(name):
        if name not in truth:
            key, _ = dataset.find_sequence(name)
            truth[name] = dataset.ground_truth(key)[0]
        return truth[name]

    series = []
    for r in rollouts:
        if not r.has_positions():
            print(f"export_rollout.py: warning: {r.path}: {r.method} on {r.sequence} stores no positions; skipped",
                  file=sys.stderr)
            continue
        x = r.positions()
        x_gt = gt(r.sequence)
        if x.shape[1] != x_gt.shape[1]:
            raise pc.InputError(f"'{r.path}': {r.method} on {r.sequence} has {x.shape[1]} vertices, the dataset "
                                f"'{dataset.path}' {x_gt.shape[1]}: not the same scene/variant")
        if len(x) > len(x_gt):
            raise pc.InputError(f"'{r.path}': {r.method} on {r.sequence} has {len(x)} frames, the dataset's "
                                f"sequence {len(x_gt)}")
        finite = finite_prefix(x)
        if finite < len(x):
            print(f"export_rollout.py: note: {r.method} on {r.sequence} is non-finite from frame {finite} on; "
                  f"exporting frames 0-{finite - 1}", file=sys.stderr)
        horizon = int(r.attrs.get("stable_horizon", len(x)))
        if horizon < finite:
            print(f"export_rollout.py: note: {r.method} on {r.sequence} diverged at frame {horizon} (stable "
                  "horizon); its later frames are exported as they are", file=sys.stderr)
        series.append(Series(pc.safe_name(f"{r.label}_{r.sequence}"), x[:finite], x_gt,
                             f"{r.label} on {r.sequence}"))
    if ground_truth or not rollout_paths:
        if rollout_paths:
            names = list(dict.fromkeys(r.sequence for r in rollouts))
        elif sequence_arg is not None:
            names = [dataset.find_sequence(sequence_arg)[1]]
        else:
            names = [n for _, n in dataset.sequences]
        for name in names:
            x = gt(name)
            series.append(Series(pc.safe_name(f"ground_truth_{name}"), x, x, f"ground truth of {name}"))
    return series


def mesh_of(dataset):
    """(rest positions, meshio cells, dirichlet flags, dt) shared by every frame."""
    cell_type = CELL_TYPES[dataset.elements.shape[1]]
    cells = [(cell_type, np.ascontiguousarray(dataset.elements, dtype=np.int64))]
    dirichlet = np.zeros(len(dataset.rest), dtype=np.int32)
    dirichlet[dataset.bc_indices] = 1
    return dataset.rest, cells, dirichlet, dataset.dt


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("rollouts", nargs="*", help="rollout HDF5 files written by `latentbench rollout`")
    parser.add_argument("--data", required=True, help="the dataset HDF5 the rollouts were made on (the mesh)")
    parser.add_argument("-o", "--output", required=True, help="output folder (created if missing)")
    parser.add_argument("--format", choices=FORMATS, default="vtu", help="vtu (.pvd + .vtu, default) or xdmf")
    parser.add_argument("--every", type=int, default=1, metavar="K", help="export every K-th frame (default 1)")
    parser.add_argument("--sequence", default=None, help="only this sequence (name or index)")
    parser.add_argument("--ground-truth", action="store_true",
                        help="also export the ground truth of the rollouts' sequences")
    args = parser.parse_args(argv)
    if args.every < 1:
        pc.fail("--every must be at least 1")
    if meshio is None:
        pc.fail("meshio is not importable; run with /usr/bin/python3 (Debian package python3-meshio)")
    pc.require_h5py()

    try:
        dataset = pc.Dataset(args.data)
        series = collect_series(dataset, args.rollouts, args.sequence, args.ground_truth)
    except pc.InputError as exc:
        pc.fail(str(exc))
    if not series:
        pc.fail("nothing to export (no rollout stores positions)")

    out_dir = os.path.abspath(args.output)
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        pc.fail(f"cannot create '{args.output}': {exc}")
    mesh = mesh_of(dataset)
    export = export_vtu if args.format == "vtu" else export_xdmf
    for s in series:
        frames = list(range(0, len(s.positions), args.every))
        if not frames:
            pc.fail(f"{s.description} has no frames")
        temp_dir = os.path.join(out_dir, f".{s.name}.tmp-{os.getpid()}")
        try:
            os.makedirs(temp_dir)
            print(export(s, frames, mesh, out_dir, temp_dir))
        except OSError as exc:
            pc.fail(f"cannot write {s.description} to '{args.output}': {exc}")
        finally:
            shutil.rmtree(temp_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
