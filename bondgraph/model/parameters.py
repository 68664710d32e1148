"""Model parameters: declaration, typed values, ``--set`` parsing.

A model file declares its parameters as a list of :class:`Parameter`.  Real-valued
parameters are *symbolic* by default: the model sees a sympy symbol, the equations keep the
name, and the numeric value travels separately (so fitting never recompiles).  Integers,
booleans and choices are *structural*: the model sees the value and may build a different
graph from it.  A real parameter declared ``symbolic=False`` is passed as a number (for
quantities the model must compute with numerically, e.g. beam geometry for mode shapes).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

import sympy as sp

from ..support.errors import ParameterError, did_you_mean
from .units import unit_problem

_TRUE = {"true", "yes", "on", "1"}
_FALSE = {"false", "no", "off", "0"}


@dataclass(frozen=True)
class Parameter:
    """A declared model parameter.

    Parameters
    ----------
    name : str
        An identifier (letters, digits, ``_`` and ``.``).
    default : float or int or bool or str
        The default value; its type fixes the kind: float (real, symbolic unless
        ``symbolic=False``), int, bool, or str (then ``choices`` lists the allowed values).
    unit : str, optional
        A unit string (:mod:`bondgraph.model.units`: ``"N/m"``, ``"N*s/m"``, ``"1"`` for a
        pure number); ``""`` when not declared: dimensional analysis then infers it.
    doc : str, optional
        One line on what it is.
    choices : tuple of str, optional
        The allowed values of a text parameter.
    symbolic : bool, optional
        Whether the model sees a sympy symbol (True) or the number; by default True for a
        real parameter, False for the others.
    bounds : tuple of (float, float), optional
        (lower, upper), in ``unit``: used by fitting and checked by ``--set``.

    Raises
    ------
    bondgraph.support.errors.ParameterError
        If the name is not an identifier, the unit cannot be read, a text parameter has no
        choices, or the default is not one of them.
    """

    name: str
    default: Any
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] | None = None
    symbolic: bool | None = None
    bounds: tuple[float, float] | None = None

    def __post_init__(self):
        if not self.name.replace("_", "a").replace(".", "a").isalnum() or self.name[0].isdigit():
            raise ParameterError(f"parameter name '{self.name}' must be an identifier (letters, digits, _ and .)")
        problem = unit_problem(self.unit)
        if problem:
            raise ParameterError(f"parameter '{self.name}': {problem}")
        if isinstance(self.default, str) and not self.choices:
            raise ParameterError(f"parameter '{self.name}': a text parameter needs choices=(...)")
        if self.choices and self.default not in self.choices:
            raise ParameterError(f"parameter '{self.name}': default {self.default!r} is not one of {self.choices}")
        if self.symbolic is None:
            object.__setattr__(self, "symbolic", self.kind == "real")

    @property
    def kind(self) -> str:
        """The kind the default fixes: ``"bool"``, ``"int"``, ``"choice"`` or ``"real"``."""
        if isinstance(self.default, bool):
            return "bool"
        if isinstance(self.default, int):
            return "int"
        if isinstance(self.default, str):
            return "choice"
        return "real"

    @property
    def symbol(self) -> sp.Symbol:
        """The real sympy symbol of the parameter's name."""
        return sp.Symbol(self.name, real=True)

    def parse(self, text: str) -> Any:
        """Convert a command-line string to this parameter's kind.

        Parameters
        ----------
        text : str
            The value as typed (``"1.2e7"``, ``"yes"``); a non-string goes to :meth:`coerce`.

        Returns
        -------
        float or int or bool or str
            The value, checked against choices and bounds.

        Raises
        ------
        bondgraph.support.errors.ParameterError
            If the text is not a value of this kind, not finite, or out of bounds.
        """
        if not isinstance(text, str):
            return self.coerce(text)
        s = text.strip()
        kind = self.kind
        try:
            if kind == "bool":
                low = s.lower()
                if low in _TRUE:
                    return True
                if low in _FALSE:
                    return False
                raise ValueError
            if kind == "int":
                return self.coerce(int(s))
            if kind == "choice":
                return self.coerce(s)
            v = float(s)
            if not math.isfinite(v):
                raise ParameterError(f"bad value {text!r} for parameter '{self.name}': must be a finite number")
            return self.coerce(v)
        except ParameterError:
            raise  # out of bounds, not one of the choices: already says so
        except (ValueError, OverflowError):
            raise ParameterError(
                f"bad value {text!r} for parameter '{self.name}': expected {self.expected()}"
            ) from None

    def coerce(self, value: Any) -> Any:
        """Check a Python value against kind, choices and bounds.

        Parameters
        ----------
        value : object
            The value (a string for a bool is parsed).

        Returns
        -------
        float or int or bool or str
            The value normalised to the kind (an integral float becomes an int for an int
            parameter, an int a float for a real one).

        Raises
        ------
        bondgraph.support.errors.ParameterError
            If the value is not of the kind, not finite, not one of the choices, or out of
            bounds.
        """
        kind = self.kind
        if kind == "bool":
            if isinstance(value, bool):
                return value
            if isinstance(value, str):
                return self.parse(value)
        elif kind == "int":
            if isinstance(value, (int, float)) and not isinstance(value, bool) and float(value).is_integer():
                return self._in_bounds(int(value))
        elif kind == "choice":
            if value in self.choices:
                return value
            raise ParameterError(
                f"bad value {value!r} for parameter '{self.name}': expected one of {', '.join(self.choices)}"
            )
        else:
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                v = float(value)
                if not math.isfinite(v):
                    raise ParameterError(f"bad value {value!r} for parameter '{self.name}': must be finite")
                return self._in_bounds(v)
        raise ParameterError(f"bad value {value!r} for parameter '{self.name}': expected {self.expected()}")

    def _in_bounds(self, v):
        if self.bounds is not None:
            lo, hi = self.bounds
            if not (lo <= v <= hi):
                raise ParameterError(f"value {v!r} for parameter '{self.name}' is outside its bounds [{lo}, {hi}]")
        return v

    def expected(self) -> str:
        """What a value of this kind looks like, for error messages.

        Returns
        -------
        str
            E.g. ``"a real number"``, ``"one of fast, exact"``.
        """
        return {
            "bool": "true or false",
            "int": "an integer",
            "real": "a real number",
            "choice": "one of " + ", ".join(self.choices or ()),
        }[self.kind]


class ParameterValues:
    """What a model's ``build`` function receives: ``p.name`` or ``p["name"]``.

    Symbolic parameters come back as sympy symbols, the others as values;
    ``p.value(name)`` always gives the number.
    """

    def __init__(self, declared: Iterable[Parameter], overrides: Mapping[str, Any] | None = None):
        self._decl = {d.name: d for d in declared}
        self._values = {n: d.default for n, d in self._decl.items()}
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def set(self, name: str, value: Any) -> None:
        decl = self.declaration(name)
        self._values[name] = decl.parse(value) if isinstance(value, str) else decl.coerce(value)

    def declaration(self, name: str) -> Parameter:
        if name not in self._decl:
            raise ParameterError(did_you_mean(name, self._decl, "parameter"))
        return self._decl[name]

    def value(self, name: str) -> Any:
        self.declaration(name)
        return self._values[name]

    def __getitem__(self, name: str):
        decl = self.declaration(name)
        return decl.symbol if decl.symbolic else self._values[name]

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        return self[name]

    def __iter__(self):
        return iter(self._decl.values())

    def items(self):
        return [(d, self._values[d.name]) for d in self._decl.values()]

    def symbolic_values(self) -> dict[sp.Symbol, float]:
        return {d.symbol: float(self._values[d.name]) for d in self._decl.values() if d.symbolic}

    def as_dict(self) -> dict[str, Any]:
        return dict(self._values)


def parse_assignments(items: Iterable[str]) -> dict[str, str]:
    """Split ``NAME=VALUE`` strings (from ``--set``) into a dict; ParameterError if malformed
    or if a name is given twice."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ParameterError(f"bad --set {item!r}: expected NAME=VALUE, e.g. --set K=1.2e7")
        name = name.strip()
        if name in out:
            raise ParameterError(
                f"--set {name} given twice ({name}={out[name]} and {name}={value.strip()}); give each parameter once"
            )
        out[name] = value.strip()
    return out


def read_params_file(path: str | Path) -> dict[str, Any]:
    """Parameter values from a JSON file: a fit file of ``bondgraph fit`` (its ``params``)
    or a flat ``{name: value}`` object.  See :func:`read_fit_file` for the output offset."""
    return read_fit_file(path)[0]


#: the ``format`` entry of the fit files this version writes and reads (``bondgraph fit --out``)
FIT_FORMAT = "bondgraph-fit/1"


def read_fit_file(path: str | Path) -> tuple[dict[str, Any], dict[str | None, float]]:
    """(parameter values, output offsets) from a JSON parameter file.

    A fit file (``bondgraph fit --out``) holds ``params`` (every parameter value of the fitted
    model), ``output`` and ``offset`` (the output offset the fit solved: measured ≈ model
    output + offset), and the fit's settings and scores.  A flat ``{name: value}`` object is
    read as parameter values with no offset.  The offset key is the output name, or ``None``
    for a file that does not name its output (then it applies to the model's first output).
    Values are numbers, booleans or text; a name given twice is an error."""
    p = Path(path)

    def no_duplicates(pairs):
        seen = {}
        for key, value in pairs:
            if key in seen:
                raise ParameterError(f"parameter file {path}: {key!r} is given twice; keep one value")
            seen[key] = value
        return seen

    try:
        data = json.loads(p.read_text(encoding="utf-8"), object_pairs_hook=no_duplicates)
    except FileNotFoundError:
        raise ParameterError(f"parameter file {path}: not found") from None
    except IsADirectoryError:
        raise ParameterError(f"parameter file {path}: is a directory; give a .json file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"parameter file {path}: cannot read ({exc})") from None
    except json.JSONDecodeError as exc:
        raise ParameterError(f"parameter file {path}:{exc.lineno}: not valid JSON ({exc.msg})") from None
    offsets: dict[str | None, float] = {}
    if isinstance(data, dict) and "format" in data and data["format"] != FIT_FORMAT:
        raise ParameterError(
            f"parameter file {path}: format {data['format']!r} is not one this version reads "
            f"({FIT_FORMAT}); write it again with this version's 'bondgraph fit --out', or upgrade bondgraph"
        )
    if isinstance(data, dict) and "params" in data:
        if not isinstance(data["params"], dict):
            raise ParameterError(f"parameter file {path}: 'params' must be an object of name: value")
        offset = data.get("offset")
        if offset is not None:
            if isinstance(offset, bool) or not isinstance(offset, (int, float)) or not math.isfinite(offset):
                raise ParameterError(f"parameter file {path}: 'offset' must be a finite number, got {offset!r}")
            output = data.get("output")
            offsets[output if isinstance(output, str) else None] = float(offset)
        data = data["params"]
    if not isinstance(data, dict):
        raise ParameterError(f"parameter file {path}: expected a JSON object of name: value")
    for key, value in data.items():
        if value is None or isinstance(value, (list, dict)):
            raise ParameterError(
                f"parameter file {path}: value of {key!r} must be a number, true/false or text, got {json.dumps(value)}"
            )
    return data, offsets
