"""How commands are declared: each command module registers its function together with its
arguments (``@command``), and shares the argument groups and helpers defined here.

Command modules import only the standard library at import time, so ``bondgraph --help``
stays fast; the framework is imported inside the command functions.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

from ..errors import UsageError


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
    arg("--set", metavar="NAME=VALUE", action="append", default=[], help="override a parameter (repeatable)"),
    arg("--params-file", metavar="FILE.json", help="parameter values, e.g. from 'bondgraph fit'"),
]

DATA_ARGS = [
    arg("data", metavar="DATA", help="measured data (CSV: t, V, x)"),
    arg("--input", metavar="COL", help="data column that drives the model (default: the model input name)"),
    arg("--output", metavar="COL", help="data column to compare with the model output"),
    arg("--model-input", default="V", help="model input (default V)"),
    arg("--model-output", default="x", help="model output (default x)"),
    arg("--validation", type=float, default=0.3, help="share of the data held out (default 0.3)"),
]


def load(args):
    """The model file of ``args`` built with ``--params-file`` and ``--set`` applied."""
    from ..modelfile import load_model
    from ..parameters import parse_assignments, read_params_file

    overrides = {}
    if args.params_file:
        overrides.update(read_params_file(args.params_file))
    overrides.update(parse_assignments(args.set))
    return load_model(args.model, overrides)


def read_data(args):
    """The measured data of ``args``, with ``--input``/``--output`` mapped to the model's names."""
    from ..data import read_csv

    rename = {}
    if args.input:
        rename[args.input] = args.model_input
    if args.output:
        rename[args.output] = args.model_output
    return read_csv(args.data, required=("t", args.model_input, args.model_output), rename=rename or None)


def write_text(path: str | None, text: str):
    """Write ``text`` to ``path`` atomically, or to stdout when no path is given."""
    if path:
        from ..atomic import atomic_write
        with atomic_write(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    else:
        sys.stdout.write(text)


def progress(label: str):
    """A progress callback (fraction done) printing to stderr once a run has taken more than 2 s."""
    state = {"t0": time.time(), "last": 0.0, "shown": False}

    def report(fraction: float):
        now = time.time()
        if fraction < 1.0 and (now - state["last"] < 0.5 or now - state["t0"] < 2.0):
            return
        if fraction >= 1.0 and not state["shown"]:
            return
        state["last"], state["shown"] = now, True
        end = "\n" if fraction >= 1.0 else "\r"
        print(f"{label}: {100 * fraction:5.1f} %  ({now - state['t0']:.1f} s)", end=end, file=sys.stderr, flush=True)
    return report


def counter(label: str):
    """A progress callback for iterative work: prints the evaluation count every 2 s."""
    state = {"t0": time.time(), "last": time.time()}

    def report(count: int):
        now = time.time()
        if now - state["last"] >= 2.0:
            state["last"] = now
            print(f"{label}: {count} simulations ({now - state['t0']:.0f} s)", file=sys.stderr, flush=True)
    return report


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one-line usage errors (exit status 2)."""

    def error(self, message):
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")
