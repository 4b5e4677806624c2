"""The host of a Python integrator (``method = "python"``): run by latentbench as
``/usr/bin/python3 -m latentbench.plugin_host`` with pipes on stdin and stdout, never by a
user. It imports the suite entry's ``module`` and ``class``, makes one instance, and answers
the harness's requests until stdin closes.

A request is an 8-byte little-endian length, a JSON header ``{"op": ..., "arrays": [[name,
shape], ...], ...}`` and the listed arrays as raw float64 in C order; a reply is the same
with a TOML header (``ok``, ``error``, ``arrays``). The class's interface (docs/python.md,
"Python integrators"):

- ``__init__(self, **options)``: the entry's ``options`` table;
- ``fit(self, data, seed) -> dict[str, ndarray]``: ``data.latents``, ``data.params`` and
  ``data.targets`` are lists (one per sequence) of (frames, width) arrays of the training
  frames, encoded by the scene's autoencoder; ``data.dt``, ``data.sequences`` (names),
  ``data.dataset_path`` and ``data.autoencoder_path`` (None when built in memory). The
  returned arrays are the artefact;
- ``load(self, arrays)``: the artefact's arrays, before a rollout;
- ``reset(self, z_prev2, z_prev, p_prev2, p_prev)``: the two starting latents and their
  boundary parameters;
- ``step(self, p) -> ndarray``: the next latent under the new frame's boundary parameters.
"""
import importlib
import json
import struct
import sys
import traceback
import types

import numpy as np


def _toml_string(text):
    return json.dumps(str(text), ensure_ascii=True)


class _Pipe:
    def __init__(self):
        self.inp = sys.stdin.buffer
        self.out = sys.stdout.buffer

    def read(self):
        head = self.inp.read(8)
        if len(head) < 8:
            return None, None
        (n,) = struct.unpack("<Q", head)
        header = json.loads(self.inp.read(n).decode("utf-8"))
        arrays = {}
        for name, shape in header.get("arrays", []):
            count = int(np.prod(shape)) if shape else 1
            raw = self.inp.read(8 * count)
            arrays[name] = np.frombuffer(raw, dtype="<f8").reshape(shape).copy()
        return header, arrays

    def reply(self, ok=True, error="", arrays=None, **fields):
        arrays = arrays or {}
        lines = [f"ok = {'true' if ok else 'false'}", f"error = {_toml_string(error)}"]
        for key, value in fields.items():
            lines.append(f"{key} = {_toml_string(value)}")
        listed = ", ".join(f"[{_toml_string(k)}, [{', '.join(str(d) for d in a.shape)}]]" for k, a in arrays.items())
        lines.append(f"arrays = [{listed}]")
        text = ("\n".join(lines) + "\n").encode("utf-8")
        self.out.write(struct.pack("<Q", len(text)))
        self.out.write(text)
        for a in arrays.values():
            self.out.write(np.ascontiguousarray(a, dtype="<f8").tobytes())
        self.out.flush()


def _where(exc):
    """'ValueError: message (at linear_map.py:42 in step)': the innermost frame of the user's code."""
    frames = traceback.extract_tb(exc.__traceback__)
    user = [f for f in frames if not f.filename.endswith("plugin_host.py")]
    at = ""
    if user:
        f = user[-1]
        at = f" (at {f.filename.rsplit('/', 1)[-1]}:{f.lineno} in {f.name})"
    return f"{type(exc).__name__}: {exc}{at}"


def _artefact(result, what):
    if result is None:
        return {}
    if not isinstance(result, dict):
        raise TypeError(f"{what} must return a dict of NumPy arrays (got {type(result).__name__})")
    out = {}
    for key, value in result.items():
        if not isinstance(key, str) or not key or not all(c.isalnum() or c in "_-" for c in key):
            raise ValueError(f"{what}: artefact key {key!r} must be a non-empty name of letters, digits, '_' or '-'")
        try:
            a = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise TypeError(f"{what}: artefact entry {key!r} is not numeric: {e}") from None
        if a.ndim == 0:
            a = a.reshape(1)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{what}: artefact entry {key!r} holds NaN or inf")
        out[key] = a
    return out


def main():
    pipe = _Pipe()
    obj = None
    latent_dim = None
    while True:
        header, arrays = pipe.read()
        if header is None:
            return 0
        op = header["op"]
        try:
            if op == "init":
                if header.get("path"):
                    sys.path.insert(0, header["path"])
                module = importlib.import_module(header["module"])
                cls = getattr(module, header["class"], None)
                if cls is None:
                    raise AttributeError(f"module '{header['module']}' ({getattr(module, '__file__', '?')}) "
                                         f"has no class '{header['class']}'")
                obj = cls(**header.get("options", {}))
                pipe.reply(file=getattr(module, "__file__", "") or "")
            elif op == "fit":
                n = sum(1 for k in arrays if k.startswith("latents."))
                data = types.SimpleNamespace(
                    latents=[arrays[f"latents.{k}"] for k in range(n)],
                    params=[arrays[f"params.{k}"] for k in range(n)],
                    targets=[arrays[f"targets.{k}"] for k in range(n)],
                    sequences=header.get("sequences", []), dt=header.get("dt"),
                    dataset_path=header.get("dataset_path") or None,
                    autoencoder_path=header.get("autoencoder_path") or None)
                pipe.reply(arrays=_artefact(obj.fit(data, int(header.get("seed", 0))), "fit"))
            elif op == "load":
                latent_dim = int(header["latent_dim"])
                obj.load(arrays)
                pipe.reply()
            elif op == "reset":
                obj.reset(arrays["z_prev2"], arrays["z_prev"], arrays["params_prev2"], arrays["params_prev"])
                pipe.reply()
            elif op == "step":
                z = obj.step(arrays["params"])
                z = np.asarray(z, dtype=np.float64)
                pipe.reply(arrays={"z": z.reshape(-1) if z.ndim <= 2 and z.size == latent_dim else z})
            else:
                pipe.reply(ok=False, error=f"unknown request '{op}' (protocol error)")
        except Exception as e:  # every failure of the user's class goes back as a message
            pipe.reply(ok=False, error=_where(e))


if __name__ == "__main__":
    sys.exit(main())
