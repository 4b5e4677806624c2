"""latentbench from Python: the same physics, data, metrics and verbs as the command line.

Files load as objects whose arrays are NumPy views into the C++ data (no copies):
``Dataset``, ``Autoencoder``, ``load_artefact``, ``load_rollouts``, ``read_table``. The
physics for prototypes: ``Physics.potential_and_gradient`` (the incremental potential of
implicit Euler at full-space states), ``Autoencoder.encode / decode / vjp`` and
``LatentPotential.value_and_gradient`` (E(D(z)) and its latent gradient). The verbs
(``simulate``, ``train_autoencoder``, ``fit``, ``rollout``, ``evaluate``, ``diagnose``,
``run``) run the command line's own subcommands in-process: keyword arguments are its
options (``max_frames=20`` is ``--max-frames 20``; for ``fit``, any keyword that is not one
of its options is a method option, ``--set key=value``), and an error raises
``latentbench.Error`` carrying the command line's message. docs/python.md has the details.
"""
import json as _json
import os as _os

# The command line's thread environment (src/cli/main.cpp): set before OpenMP is loaded.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from _latentbench import (  # noqa: E402
    Autoencoder, Dataset, Error, LatentPotential, Physics, Rollout, Sequence, Table, TableCell,
    load_artefact, load_rollout_summaries, load_rollouts, metric_columns, read_table, save_rollouts,
)
import _latentbench as _core  # noqa: E402

__all__ = [
    "Autoencoder", "Dataset", "Error", "LatentPotential", "Physics", "Rollout", "Sequence", "Table",
    "TableCell", "cli", "diagnose", "evaluate", "fit", "latent_energy", "load_artefact",
    "load_rollout_summaries", "load_rollouts", "metric_columns", "read_table", "rollout", "run",
    "save_rollouts", "simulate", "status", "train_autoencoder",
]

_GLOBAL = {"threads": "--threads", "quiet": "--quiet", "verbose": "--verbose"}


def cli(*args):
    """Run ``latentbench ARGS...`` in-process; returns its exit status (0, or e.g. 1 from a
    failing ``regress`` gate); raises Error with the message the command line prints."""
    status, error = _core.run_cli([str(a) for a in args])
    if error:
        raise Error(error)
    return status


def _toml(value):
    """A method option's value as TOML text (what ``--set key=value`` takes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return _json.dumps(str(value))


def _command(subcommand, positional, options, method_options=False):
    """The command line of a verb: global options first, then the subcommand, its
    positional arguments and one --option per keyword (True: a flag; None/False: left out;
    a list: repeated). With method_options, keywords that are not the subcommand's options
    become ``--set key=value``."""
    known = set(_core.subcommand_options(subcommand))
    head, args = [], [subcommand] + [str(p) for p in positional]
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if key in _GLOBAL:
            target = head
        elif method_options and flag not in known:
            args += ["--set", f"{key}={_toml(value)}"]
            continue
        else:
            target = args
        if value is None or value is False:
            continue
        if value is True:
            target.append(flag)
        elif isinstance(value, (list, tuple)):
            for v in value:
                target += [flag, str(v)]
        else:
            target += [flag, str(value)]
    return head + args


def _require(value, name, verb):
    if not value:
        raise Error(f"latentbench.{verb}: {name}= is required")
    return str(value)


def simulate(scene, output=None, **options):
    """``latentbench simulate SCENE -o OUTPUT ...``; returns the Dataset (None with check=True)."""
    cli(*_command("simulate", [scene], dict(output=output, **options)))
    return None if options.get("check") else Dataset.load(str(output))


def train_autoencoder(data, output=None, **options):
    """``latentbench train-ae DATA -o OUTPUT ...``; returns the Autoencoder."""
    cli(*_command("train-ae", [data], dict(output=output, **options)))
    return Autoencoder.load(_require(output, "output", "train_autoencoder"), Physics(Dataset.load(str(data))))


def fit(data, method=None, output=None, ae=None, checkpoint=None, **options):
    """``latentbench fit DATA --method METHOD -o OUTPUT [--ae AE] --set key=value ...``: every
    keyword that is not an option of ``fit`` is a method option. Returns load_artefact(output)."""
    cli(*_command("fit", [data], dict(method=method, output=output, ae=ae, checkpoint=checkpoint, **options),
                  method_options=True))
    return load_artefact(_require(output, "output", "fit"))


def rollout(data, output=None, **options):
    """``latentbench rollout DATA -o OUTPUT --integrator ARTEFACT | --method NAME ...``; returns
    load_rollouts(output)."""
    cli(*_command("rollout", [data], dict(output=output, **options)))
    return load_rollouts(_require(output, "output", "rollout"))


def evaluate(*rollouts, **options):
    """``latentbench evaluate ROLLOUTS...`` (prints the summary table); returns the summaries."""
    cli(*_command("evaluate", list(rollouts), options))
    return [r for path in rollouts for r in load_rollout_summaries(str(path))]


def diagnose(data, ae=None, output=None, **options):
    """``latentbench diagnose DATA --ae AE [-o OUTPUT] ...`` (prints the table); returns the
    Table when output is given (read from OUTPUT.csv), else None."""
    cli(*_command("diagnose", [data], dict(ae=ae, output=output, **options)))
    return read_table(str(output) + ".csv") if output else None


def run(suite, **options):
    """``latentbench run SUITE ...``: the whole suite (cached stages), or check=True, unit=,
    merge=True as on the command line."""
    return cli(*_command("run", [suite], options))


def status(suite, output=None):
    """``latentbench status SUITE [-o OUTPUT]`` as data: one dict per work unit, in plan
    order, with ``id``, ``kind`` (scene, fit, eval), ``state`` ("done", "running",
    "running elsewhere", "interrupted", "stopped", "failed", "stale", "not started"),
    ``where`` and ``detail`` (from its status file), and for a unit with a training
    checkpoint ``trainer``, ``epoch``, ``epochs`` (the budget) and ``seconds`` (else None)."""
    return _core.run_status(str(suite), "" if output is None else str(output))


def latent_energy(physics, autoencoder, z, bc_targets, x_prev, x_prev2, penalty_weight=1e5,
                  overwrite_dirichlet=False):
    """One call: (E(D(z)), its gradient with respect to z) for the step with history
    x_prev, x_prev2 and Dirichlet targets bc_targets (3B)."""
    potential = LatentPotential(physics, autoencoder, penalty_weight, overwrite_dirichlet)
    return potential.value_and_gradient(z, bc_targets, x_prev, x_prev2)
