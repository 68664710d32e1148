"""Command-line interface: ``bondgraph COMMAND MODEL ...`` (see ``bondgraph --help``).

Each command lives in its own module, its arguments declared next to its function
(:func:`registry.command`).  Exit status: 0 success, 2 usage or input error (one line on
stderr, no traceback), 1 internal failure (``--debug`` shows the traceback), 130 interrupted.
"""
from __future__ import annotations

import math
import sys
import traceback
import warnings

from ..errors import BondGraphError, UsageError
from . import batch, causality, diagnose, equations, fit, linearize, params, simulate  # noqa: F401 (registration)
from .registry import COMMANDS, Parser


def build_parser() -> Parser:
    parser = Parser(prog="bondgraph", description="Bond-graph modelling of piezoelectric actuators.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for cmd in COMMANDS.values():
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        for flags, kw in cmd.args:
            p.add_argument(*flags, **kw)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    debug = "--debug" in argv
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if not args.command:
            raise UsageError(f"no command given; choose one of {', '.join(COMMANDS)} (see bondgraph --help)")
        _check_numbers(args)
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = _show_warning
            COMMANDS[args.command].run(args)
        return 0
    except BondGraphError as exc:
        if debug:
            traceback.print_exc()
        print(f"bondgraph: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bondgraph: interrupted; no output file was written partially", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # noqa: BLE001 - internal failure: one line unless --debug
        if debug:
            traceback.print_exc()
        print(f"bondgraph: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
              file=sys.stderr)
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


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"bondgraph: warning: {message}", file=sys.stderr)
