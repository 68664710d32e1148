"""How commands are declared: each command module registers its function together with its
arguments (``@command``), and shares the argument groups and helpers defined here.

Command modules import only the standard library at import time, so ``bondgraph --help``
stays fast; the framework is imported inside the command functions.
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass, field
from typing import Callable

from ..support.errors import UsageError


@dataclass
class Command:
    """A subcommand: its function, one-line help and argument declarations."""

    name: str
    run: Callable
    help: str
    args: list = field(default_factory=list)


COMMANDS: dict[str, Command] = {}


def arg(*flags, **kw) -> tuple:
    """One argument declaration, as for ``argparse.ArgumentParser.add_argument``."""
    return flags, kw


def command(name: str, help: str, args: list):
    """Register ``fn(args)`` as subcommand ``name`` with the argument declarations ``args``."""

    def deco(fn):
        COMMANDS[name] = Command(name, fn, help, list(args))
        return fn

    return deco


MODEL_ARGS = [
    arg("model", metavar="MODEL", help="model file (.py)"),
    arg(
        "--set",
        metavar="NAME=VALUE",
        action="append",
        default=[],
        help="override a parameter (repeatable; each name at most once)",
    ),
    arg(
        "--params-file",
        metavar="FILE.json",
        help="parameter values, e.g. the fit file of 'bondgraph fit' "
        "(its output offset is applied too); --set overrides it",
    ),
]

DATA_ARGS = [
    arg("data", metavar="DATA", help="measured data: CSV with a header line, time column t in s"),
    arg(
        "--input",
        metavar="COL",
        help="data column that drives the model (default: the column named like the model input)",
    ),
    arg(
        "--output",
        metavar="COL",
        help="data column to compare with the model output (default: the column named like the model output)",
    ),
    arg("--model-input", metavar="NAME", help="model input driven by the data (default: the model's first input)"),
    arg(
        "--model-output", metavar="NAME", help="model output compared with the data (default: the model's first output)"
    ),
    arg("--validation", type=float, default=0.3, help="share of the data held out (default 0.3)"),
]

QUIET_ARG = arg("--quiet", action="store_true", help="no progress or summary on stderr")

#: figure formats that --plot options accept
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def load(args):
    """The model file of ``args`` built with ``--params-file`` and ``--set`` applied.

    Also fills in ``args.model_input``/``args.model_output`` (when the command has them and
    they were not given) with the model's first declared input and output."""
    from ..model.modelfile import load_model
    from ..model.parameters import parse_assignments, read_fit_file

    overrides, offsets = {}, {}
    if args.params_file:
        overrides, offsets = read_fit_file(args.params_file)
    overrides.update(parse_assignments(args.set))
    lm = load_model(args.model, overrides)
    lm.offsets = offsets
    for attr, declared, what in (
        ("model_input", lm.model.inputs, "input"),
        ("model_output", lm.model.outputs, "output"),
    ):
        if not hasattr(args, attr):
            continue
        if getattr(args, attr) is None:
            if not declared:
                raise UsageError(f"model {args.model} declares no {what}; a command on measured data needs one")
            setattr(args, attr, next(iter(declared)))
        elif getattr(args, attr) not in declared:
            from ..support.errors import did_you_mean

            option = "--" + attr.replace("_", "-")
            raise UsageError(f"{option}: " + did_you_mean(getattr(args, attr), declared, f"{what} of {args.model}"))
    return lm


def read_data(args):
    """The measured data of ``args``, with ``--input``/``--output`` mapped to the model's names
    (call :func:`load` first: it resolves the model's input and output names)."""
    from ..data import read_csv

    rename = {}
    if args.input:
        rename[args.input] = args.model_input
    if args.output:
        rename[args.output] = args.model_output
    return read_csv(args.data, required=("t", args.model_input, args.model_output), rename=rename or None)


def outputs(args, *dests: str, inputs=()):
    """An :class:`~bondgraph.support.atomic.Outputs` with the output options ``dests`` of ``args``
    (e.g. ``"out", "plot"``) checked now, before any work: directory exists and is writable,
    not an input file of the run, not given twice, a figure format for ``plot``, matplotlib
    installed for figures, an ``.html`` name and bokeh for ``report``.  ``inputs``: further files the run reads."""
    from ..support.atomic import Outputs

    data = getattr(args, "data", None)
    out = Outputs(
        [
            getattr(args, "model", None),
            *(data if isinstance(data, list) else [data]),
            getattr(args, "params_file", None),
            *inputs,
        ]
    )
    try:
        for dest in dests:
            path = getattr(args, dest, None)
            if path is None:
                continue
            option = "--" + dest.replace("_", "-")
            if dest == "plot":
                need_matplotlib()
                out.add(path, option, suffixes=PLOT_SUFFIXES)
            elif dest == "report":
                from ..plotting.html_report import need_bokeh

                need_bokeh()
                out.add(path, option, suffixes=(".html",))
            else:
                out.add(path, option)
    except BaseException:
        out.discard()
        raise
    return out


def need_matplotlib():
    """UsageError unless matplotlib (the ``plot`` extra) is installed."""
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        raise UsageError("plots need matplotlib: pip install 'bondgraph[plot]' (or leave out --plot)")


def write_text(path: str | None, text: str, out=None):
    """Write ``text`` to ``path`` (through the run's :class:`Outputs` ``out`` if given, else
    atomically on its own), or to stdout when no path is given."""
    if not path:
        sys.stdout.write(text)
    elif out is not None:
        with out.open(path, "w") as fh:
            fh.write(text)
    else:
        from ..support.atomic import atomic_write

        with atomic_write(path, "w", encoding="utf-8") as fh:
            fh.write(text)


def progress(label: str, quiet: bool = False):
    """A :class:`~bondgraph.support.progress.Progress` for a fraction done (0..1), e.g. for
    ``Simulator.run(progress=...)``; silent with ``quiet``."""
    from ..support.progress import Progress

    return Progress(label, total=1.0, mode="quiet" if quiet else "auto")


def counter(label: str, unit: str = "simulations", quiet: bool = False):
    """A :class:`~bondgraph.support.progress.Progress` for a count with no known end, e.g. for
    ``Identification.fit(progress=...)``; silent with ``quiet``."""
    from ..support.progress import Progress

    return Progress(label, unit=unit, mode="quiet" if quiet else "auto")


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one-line usage errors (exit status 2).

    Negative numbers in every notation (``-1``, ``-.5``, ``-1e-3``) are read as values, not
    options, so ``--dt -1e-3`` reaches the check that says what is wrong with it."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")

    def error(self, message):
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")


def module_constant(module: str, name: str) -> tuple:
    """A tuple constant of a framework module (``module_constant("bondgraph.numerics.simulate",
    "METHODS")``) read from the module's source without importing it, so argument choices
    come from the module that defines them while ``--help`` stays fast (no sympy, no numba).
    Falls back to importing the module if the constant is not a plain top-level literal."""
    import ast
    import importlib
    import importlib.util

    spec = importlib.util.find_spec(module)
    try:
        with open(spec.origin, encoding="utf-8") as fh:
            tree = ast.parse(fh.read())
        for node in tree.body:
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
                return tuple(ast.literal_eval(node.value))
    except (OSError, TypeError, ValueError, SyntaxError, AttributeError):
        pass
    return tuple(getattr(importlib.import_module(module), name))
