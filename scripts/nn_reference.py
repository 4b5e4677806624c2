#!/usr/bin/python3
"""NumPy-only reference forward pass for networks saved by latentbench (lb::nn).

Reads a network written by lb::nn::save_network (PyTorch state_dict-style datasets
such as ``decoder.0.f.0.weight`` plus the JSON attribute ``decoder.architecture``
on the file root) and evaluates it in eval mode (BatchNorm uses running
statistics) on inputs from an HDF5 dataset, a .npy file or the command line.

Layout: by default one sample per ROW (NumPy convention, inputs (B, in), outputs
(B, out)); with --columns one sample per COLUMN, the C++ layout (features × batch,
as lb::h5 writes an Eigen matrix), for both inputs and outputs.

Examples (run with the Debian interpreter, which has numpy and h5py):
  /usr/bin/python3 scripts/nn_reference.py model.h5 --prefix decoder. --values 0.1,0.2,0.3,0.4
  /usr/bin/python3 scripts/nn_reference.py model.h5 --prefix integrator. \\
      --input batch.h5 --dataset inputs --columns --output out.h5
"""
import argparse
import json
import sys

import numpy as np

FORMAT = "latentbench.nn/1"


def swish(x):
    return x / (1.0 + np.exp(-x))


ACTIVATIONS = {
    "Swish": swish,
    "Tanh": np.tanh,
    "ReLU": lambda x: np.maximum(x, 0.0),
    "Identity": lambda x: x,
}


class Network:
    """A saved network: architecture description + parameters, evaluated with NumPy."""

    def __init__(self, h5file, prefix):
        key = prefix + "architecture"
        if key not in h5file.attrs:
            raise KeyError(f"{h5file.filename}: no attribute '{key}' (no network under prefix '{prefix}')")
        raw = h5file.attrs[key]
        self.description = json.loads(raw.decode() if isinstance(raw, bytes) else str(raw))
        if self.description.get("format") != FORMAT:
            raise ValueError(f"unsupported architecture format {self.description.get('format')!r}")
        self.prefix = prefix
        self.params = {name: np.asarray(h5file[name][()], dtype=np.float64)
                       for name in h5file.keys() if name.startswith(prefix)}
        self.mean = self.std = None
        if self.description["standardizer"]:
            self.mean = self.params[prefix + "standardizer.mean"]
            self.std = self.params[prefix + "standardizer.std"]

    def __call__(self, x):
        """x: (B, in) -> (B, out)."""
        x = np.asarray(x, dtype=np.float64)
        if self.mean is not None:
            x = (x - self.mean) / self.std
        return self._forward(self.description["network"], self.prefix, x)

    def _p(self, name):
        if name not in self.params:
            raise KeyError(f"dataset '{name}' missing")
        return self.params[name]

    def _forward(self, layer, name, x):
        kind = layer["type"]
        if kind == "Sequential":
            for i, child in enumerate(layer["layers"]):
                x = self._forward(child, f"{name}{i}.", x)
            return x
        if kind == "Linear":
            return x @ self._p(name + "weight").T + self._p(name + "bias")
        if kind == "BatchNorm1d":
            mean, var = self._p(name + "running_mean"), self._p(name + "running_var")
            return (x - mean) / np.sqrt(var + layer["eps"]) * self._p(name + "weight") + self._p(name + "bias")
        if kind == "ResidualBlock":
            y = self._forward(layer["f"], name + "f.", x)
            skip = layer["skip"]
            return y + (x if skip is None else self._forward(skip, name + "skip.", x))
        if kind in ACTIVATIONS:
            return ACTIVATIONS[kind](x)
        raise ValueError(f"unknown layer type {kind!r}")


def read_inputs(args):
    if args.values is not None:
        x = np.array([float(v) for v in args.values.split(",")], dtype=np.float64)
    elif args.input is None:
        raise SystemExit("give --input FILE or --values v1,v2,...")
    elif args.input.endswith(".npy"):
        x = np.load(args.input)
    else:
        import h5py
        with h5py.File(args.input, "r") as f:
            x = np.asarray(f[args.dataset][()], dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        return x[None, :], True
    return (x.T if args.columns else x), False


def write_outputs(args, y, single):
    out = y[0] if single else (y.T if args.columns else y)
    if args.output is None:
        for row in np.atleast_2d(y):
            print(" ".join(repr(float(v)) for v in row))
    elif args.output.endswith(".npy"):
        np.save(args.output, out)
    else:
        import h5py
        with h5py.File(args.output, "w") as f:
            f.create_dataset("output", data=out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model", help="HDF5 file written by lb::nn::save_network")
    parser.add_argument("--prefix", default="", help="network prefix, e.g. 'decoder.' (default: none)")
    parser.add_argument("--input", help="inputs: .npy file or HDF5 file (see --dataset)")
    parser.add_argument("--dataset", default="inputs", help="dataset name in the HDF5 input file")
    parser.add_argument("--values", help="one sample given inline, comma separated")
    parser.add_argument("--columns", action="store_true",
                        help="one sample per column (C++ features x batch layout) for input and output")
    parser.add_argument("--output", help="write outputs to .npy or HDF5 (dataset 'output'); default: print")
    args = parser.parse_args(argv)

    import h5py
    with h5py.File(args.model, "r") as f:
        net = Network(f, args.prefix)
    x, single = read_inputs(args)
    write_outputs(args, net(x), single)
    return 0


if __name__ == "__main__":
    sys.exit(main())
