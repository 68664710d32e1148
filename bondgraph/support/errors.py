"""Typed exceptions.

Every error a user can cause by a bad model, bad data or a bad command line is a
:class:`BondGraphError`; the CLI prints it as one line and exits with status 2.
Each subclass also derives from the builtin that fits it, so ``except ValueError``
keeps working for library users.
"""

from __future__ import annotations

import difflib


class BondGraphError(Exception):
    """Base of all user-facing errors (bad model, data, or arguments)."""


class ModelError(BondGraphError, ValueError):
    """The bond graph is malformed: unknown names, bad connections, bad laws."""


class CausalityError(ModelError):
    """Causality cannot be assigned, or a derivative causality / algebraic loop remains."""


class ParameterError(BondGraphError, ValueError):
    """Unknown parameter name or a value of the wrong kind."""


class DataError(BondGraphError, ValueError):
    """A measured-data file is unreadable or inconsistent."""


class SignalError(BondGraphError, ValueError):
    """An input-signal specification is malformed."""


class UsageError(BondGraphError, ValueError):
    """A command-line usage error."""


def did_you_mean(name: str, known, what: str = "name") -> str:
    """One-sentence hint naming the closest known names, for error messages."""
    known = sorted(set(known))
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.5)
    if close:
        return f"unknown {what} '{name}'; did you mean {', '.join(repr(c) for c in close)}?"
    shown = ", ".join(known[:12]) + (", ..." if len(known) > 12 else "")
    return f"unknown {what} '{name}'; known: {shown}"
