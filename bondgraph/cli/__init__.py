"""Command-line interface: ``bondgraph COMMAND MODEL ...`` (see ``bondgraph --help``).

Each command lives in its own module, its arguments declared next to its function
(:func:`registry.command`).  Exit status: 0 success, 2 usage or input error (one line on
stderr, no traceback), 1 internal failure (``--debug`` shows the traceback), 130 interrupted
by Ctrl-C and 143 by SIGTERM (one line; temporary files removed, worker processes killed,
existing files untouched: see :mod:`bondgraph.support.interrupt`).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import traceback
import warnings

from ..support import interrupt, progress
from ..support.errors import BondGraphError, UsageError
from . import (  # noqa: F401 - importing a command's module registers it
    batch,
    causality,
    check,
    compensate,
    diagnose,
    equations,
    export,
    figure,
    fit,
    linearize,
    params,
    simulate,
)
from .registry import COMMANDS, Parser

DEBUG_HELP = "show the traceback of an error"


def build_parser() -> Parser:
    parser = Parser(
        prog="bondgraph",
        description="Acausal bond-graph modelling: equations, simulation, "
        "fitting and diagnosis of model files (.py) against measured data (.csv).",
        epilog="Exit status: 0 success, 2 bad input (one line on stderr), 1 internal failure, "
        "130 interrupted (Ctrl-C). 'bondgraph COMMAND --help' describes a command.",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for cmd in COMMANDS.values():
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        for flags, kw in cmd.args:
            p.add_argument(*flags, **kw)
        p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    debug = "--debug" in argv
    with interrupt.handle_signals():
        try:
            parser = build_parser()
            try:
                args = parser.parse_args(argv)
            except SystemExit as exc:  # --help and --version: argparse printed what was asked
                return exc.code or 0
            if not args.command:
                raise UsageError(f"no command given; choose one of {', '.join(COMMANDS)} (see bondgraph --help)")
            _check_numbers(args)
            with warnings.catch_warnings(), progress.quiet_if(getattr(args, "quiet", False)):
                warnings.simplefilter("default")
                warnings.simplefilter("ignore", RuntimeWarning)  # numpy's overflow/invalid notes: results are checked
                warnings.showwarning = _show_warning
                interrupt.run(COMMANDS[args.command].run, args)
            return 0
        except BondGraphError as exc:
            if debug:
                traceback.print_exception(exc)
            print(f"bondgraph: error: {exc}", file=sys.stderr)
            return 2
        except BrokenPipeError:  # e.g. 'bondgraph simulate ... | head': stop quietly
            _silence_stdout()
            return 0
        except KeyboardInterrupt:  # only without signal handlers (not in the main thread)
            print("bondgraph: interrupted; no output file was changed", file=sys.stderr)
            return 130
        except SystemExit as exc:  # the command (a library it calls) called sys.exit: report it, do not obey it
            print(
                f"bondgraph: internal error: unexpected exit (status {exc.code}) (run with --debug for the traceback)",
                file=sys.stderr,
            )
            if debug:
                traceback.print_exception(exc)
            return 1
        except Exception as exc:  # noqa: BLE001 - internal failure: one line unless --debug
            if debug:
                traceback.print_exception(exc)
            print(
                f"bondgraph: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
                file=sys.stderr,
            )
            return 1


def _check_numbers(args):
    """Refuse nonsensical numeric options with a one-line message."""
    for name in ("rtol", "atol"):
        v = getattr(args, name, None)
        if v is None:
            continue
        if not math.isfinite(v) or v <= 0 or (name == "rtol" and v >= 1):
            bound = "between 0 and 1" if name == "rtol" else "a positive number"
            raise UsageError(f"--{name.replace('_', '-')} must be {bound}, got {v}")
    for name in ("dt", "t_end"):
        v = getattr(args, name, None)
        if v is not None and not (math.isfinite(v) and v > 0):
            what = "the output sample interval" if name == "dt" else "the end time"
            raise UsageError(
                f"--{name.replace('_', '-')} is {what} in s; it must be a positive number (got {name}={v:g})"
            )
    v = getattr(args, "validation", None)
    if v is not None and not 0 < v < 1:
        raise UsageError(f"--validation is the share of the data held out; it must be between 0 and 1, got {v}")
    for name in ("workers", "starts"):
        v = getattr(args, name, None)
        if v is not None and v < 1:
            raise UsageError(f"--{name} must be at least 1, got {v}")


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"bondgraph: warning: {message}", file=sys.stderr)


def _silence_stdout():
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
