"""Unit strings as engineers write them, read into SI dimensions (the unit data of sympy.physics.units).

A unit string is a product of unit names with exponents: ``"N/m"``, ``"N*s/m"``, ``"V/(C*m^2)"``,
``"kg^1/2 m"`` (a space multiplies too), ``"1/(kg m^2 s^2)"``, ``"rad/s"``, ``"µm"``, ``"m²"``, ``"1"``
(dimensionless).  The empty string means *not declared*: dimensional analysis infers the unit.
Names: the SI base and derived units (m, g, s, A, K, mol, cd, N, Pa, J, W, C, V, F, ohm or Ω, S, Wb,
T, H, Hz, rad, sr) with an SI prefix (``k``, ``M``, ``m``, ``µ`` or ``u``, ``n``, ...) and a few
others (deg or °, min, h, L, bar, %).  An exponent follows ``^`` or ``**``: an integer or a fraction
(``kg^-1/2``, ``m^(3/2)``); ``/`` divides everything after it up to the next ``*``, ``/`` or space
(``N*s/m`` is N·s per m, ``N/m/s`` is N per m per s).

Only dimensions are compared: a prefixed unit (``V/um``, ``deg``) is read as its dimension, and
the value of a parameter declared in it enters the equations as the number given.

A dimension is a tuple of the exponents of the SI base units (kg, m, s, A, K, mol, cd), each
times :data:`DENOM` (so that kg^(1/2) is the integer 30): integer arithmetic, exact for the
halves, thirds, quarters and fifths that fractional units need.
"""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from itertools import combinations

#: the SI base units, in the order of a dimension tuple
BASE = ("kg", "m", "s", "A", "K", "mol", "cd")
#: exponents are stored times this number
DENOM = 60
#: the dimension of a pure number
ONE = (0,) * len(BASE)

_SYMPY_BASE = ("mass", "length", "time", "current", "temperature", "amount_of_substance", "luminous_intensity")

#: unit name -> name in sympy.physics.units; True: takes an SI prefix
_NAMES = {
    "m": ("meter", True),
    "g": ("gram", True),
    "s": ("second", True),
    "A": ("ampere", True),
    "K": ("kelvin", True),
    "mol": ("mole", True),
    "cd": ("candela", True),
    "N": ("newton", True),
    "Pa": ("pascal", True),
    "J": ("joule", True),
    "W": ("watt", True),
    "C": ("coulomb", True),
    "V": ("volt", True),
    "F": ("farad", True),
    "ohm": ("ohm", True),
    "Ohm": ("ohm", True),
    "Ω": ("ohm", True),
    "S": ("siemens", True),
    "Wb": ("weber", True),
    "T": ("tesla", True),
    "H": ("henry", True),
    "Hz": ("hertz", True),
    "rad": ("radian", True),
    "sr": ("steradian", False),
    "deg": ("degree", False),
    "°": ("degree", False),
    "min": ("minute", False),
    "h": ("hour", False),
    "L": ("liter", True),
    "bar": ("bar", True),
    "%": ("percent", False),
}
_PREFIX_ALIASES = {"µ": "mu", "μ": "mu", "u": "mu"}
_SUPERSCRIPTS = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")
_TOKEN = re.compile(r"\s*(?:(?P<num>\d+)|(?P<name>[A-Za-zµμΩ°%]+)|(?P<sup>[⁰¹²³⁴⁵⁶⁷⁸⁹⁻]+)|(?P<op>\*\*|[*·⋅×/^()+-]))")
EXAMPLES = "write e.g. 'N/m', 'N*s/m', 'V/(C*m^2)', 'kg^1/2 m' or '1' (dimensionless)"


@dataclass(frozen=True)
class Unit:
    """A parsed unit string: its text, dimension (see the module docstring) and its size in
    coherent SI units (1 µm is 1e-6 m, 1 deg is π/180 rad)."""

    text: str
    dim: tuple
    scale: float


def mul(a: tuple, b: tuple) -> tuple:
    """The dimension of a product."""
    return tuple(map(operator.add, a, b))


def div(a: tuple, b: tuple) -> tuple:
    """The dimension of a quotient."""
    return tuple(map(operator.sub, a, b))


def power(a: tuple, p: Fraction) -> tuple | None:
    """The dimension of ``a`` to the rational power ``p``; None if it has no exact exponents here."""
    if p.denominator == 1:
        n = int(p)
        return tuple(x * n for x in a)
    out = []
    for x in a:
        y = x * p
        if y.denominator != 1:
            return None
        out.append(int(y))
    return tuple(out)


@lru_cache(maxsize=None)
def _table() -> dict[str, tuple[tuple, Fraction | float]]:
    """name -> (dimension, SI scale) from sympy.physics.units (imported on first use)."""
    import sympy.physics.units as u
    from sympy.physics.units.systems.si import SI, dimsys_SI

    out = {}
    for name, (attr, _) in _NAMES.items():
        q = getattr(u, attr)
        deps = {d.name.name: e for d, e in dimsys_SI.get_dimensional_dependencies(SI.get_quantity_dimension(q)).items()}
        dim = tuple(int(Fraction(str(deps.get(b, 0))) * DENOM) for b in _SYMPY_BASE)
        scale = SI.get_quantity_scale_factor(q) / 1000 ** deps.get("mass", 0)  # sympy's scales count grams
        out[name] = (dim, Fraction(str(scale)) if scale.is_Rational else float(scale))
    return out


@lru_cache(maxsize=None)
def _prefixes() -> dict[str, Fraction]:
    from sympy.physics.units.prefixes import PREFIXES

    return {k: Fraction(str(v.scale_factor)) for k, v in PREFIXES.items()}


def _name(word: str) -> tuple[tuple, Fraction | float]:
    table = _table()
    if word in table:
        return table[word]
    prefixes = _prefixes()
    for n in (2, 1):
        head, rest = word[:n], word[n:]
        key = _PREFIX_ALIASES.get(head, head)
        if rest in table and key in prefixes and _NAMES[rest][1] and head != "mu":
            dim, scale = table[rest]
            return dim, scale * prefixes[key]
    raise ValueError(f"unknown unit '{word}'")


class _Parser:
    def __init__(self, text: str):
        self.text = text
        self.tokens: list[tuple[str, str]] = []
        pos, stripped = 0, text.rstrip()
        while pos < len(stripped):
            m = _TOKEN.match(stripped, pos)
            if not m or m.end() == pos:
                raise ValueError(f"unexpected '{stripped[pos:].strip()[:1]}'")
            kind = m.lastgroup
            self.tokens.append((kind, m.group(kind)))
            pos = m.end()
        self.i = 0

    def peek(self) -> tuple[str, str] | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def take(self) -> tuple[str, str]:
        tok = self.peek()
        if tok is None:
            raise ValueError("unexpected end")
        self.i += 1
        return tok

    def parse(self) -> tuple[tuple, Fraction | float]:
        dim, scale = self.product()
        if self.peek() is not None:
            raise ValueError(f"unexpected '{self.peek()[1]}'")
        return dim, scale

    def product(self):
        dim, scale = self.factor()
        while True:
            tok = self.peek()
            if tok is None or tok[1] == ")":
                return dim, scale
            if tok[0] == "op" and tok[1] in "*·⋅×":
                self.take()
                d, s = self.factor()
                dim, scale = mul(dim, d), scale * s
            elif tok[0] == "op" and tok[1] == "/":
                self.take()
                d, s = self.factor()
                dim, scale = div(dim, d), scale / s
            elif tok[0] in ("name", "num") or tok[1] == "(":  # a space multiplies
                d, s = self.factor()
                dim, scale = mul(dim, d), scale * s
            else:
                raise ValueError(f"unexpected '{tok[1]}'")

    def factor(self):
        kind, value = self.take()
        if kind == "num":
            before = self.tokens[self.i - 2] if self.i >= 2 else None
            if value != "1" and before is not None and before[0] == "name":
                raise ValueError(f"write {before[1]}^{value} for a power")
            if value != "1":
                raise ValueError(f"a number ({value}) is not a unit; only '1' is (a pure number)")
            dim, scale = ONE, Fraction(1)
        elif kind == "name":
            dim, scale = _name(value)
        elif value == "(":
            dim, scale = self.product()
            if self.peek() != ("op", ")"):
                raise ValueError("a '(' is not closed")
            self.take()
        else:
            raise ValueError(f"unexpected '{value}'")
        p = self.exponent()
        if p is None:
            return dim, scale
        return power(dim, p) or _too_fine(p), scale**p if p.denominator == 1 else float(scale) ** float(p)

    def exponent(self) -> Fraction | None:
        tok = self.peek()
        if tok is not None and tok[0] == "sup":
            self.take()
            return Fraction(int(tok[1].translate(_SUPERSCRIPTS)))
        if tok is None or tok[1] not in ("^", "**"):
            return None
        self.take()
        paren = self.peek() == ("op", "(")
        if paren:
            self.take()
        sign = 1
        if self.peek() in (("op", "-"), ("op", "+")):
            sign = -1 if self.take()[1] == "-" else 1
        kind, num = self.take()
        if kind != "num":
            raise ValueError(f"expected an exponent after '^', got '{num}'")
        p = Fraction(int(num))
        after = self.tokens[self.i + 1] if self.i + 1 < len(self.tokens) else None
        if self.peek() == ("op", "/") and after is not None and after[0] == "num":
            self.take()
            p /= int(self.take()[1])
        if paren:
            if self.peek() != ("op", ")"):
                raise ValueError("a '(' is not closed")
            self.take()
        return sign * p


def _too_fine(p: Fraction):
    raise ValueError(f"exponent {p} is finer than 1/{DENOM}")


@lru_cache(maxsize=1024)
def parse_unit(text: str) -> Unit | None:
    """Read a unit string (see the module docstring); None for ``""`` (not declared).

    Parameters
    ----------
    text : str
        The unit as written, e.g. ``"N*s/m"``.

    Returns
    -------
    Unit or None

    Raises
    ------
    ValueError
        Naming what cannot be read (an unknown name, a stray character); callers turn it into
        the error of what declared the unit.
    """
    if not isinstance(text, str):
        raise ValueError(f"a unit must be a string, not {type(text).__name__}")
    if not text.strip():
        return None
    dim, scale = _Parser(text.strip()).parse()
    return Unit(text, dim, float(scale))


def unit_problem(text) -> str | None:
    """Why ``text`` is not a unit string, for the error of what declares it.

    Parameters
    ----------
    text : str
        A unit string as declared.

    Returns
    -------
    str or None
        One phrase naming the problem and the way to write units; None if ``text`` reads.
    """
    try:
        parse_unit(text)
    except ValueError as exc:
        return f"cannot read unit {text!r} ({exc}); {EXAMPLES}"
    return None


#: units tried, in order of preference, when a dimension is written out (no Pa or J: N/m^2 and
#: N*m read better beside the N/m and m/N of bond graphs)
_VOCABULARY = ("m", "s", "kg", "N", "V", "A", "C", "W", "F", "ohm", "H", "K", "mol", "cd")


@lru_cache(maxsize=None)
def _spellings() -> dict[tuple, tuple]:
    """dimension -> ((unit, exponent), ...): the shortest product of one or two units of the
    vocabulary (smallest exponents, earliest units first)."""
    table = _table()
    dims = {n: (table[n][0] if n != "kg" else (DENOM,) + ONE[1:]) for n in _VOCABULARY}
    best: dict[tuple, tuple] = {}

    def offer(parts):
        d = ONE
        for n, e in parts:
            d = mul(d, tuple(x * e for x in dims[n]))
        key = (len(parts), sum(abs(e) for _, e in parts), sum(_VOCABULARY.index(n) for n, _ in parts))
        if d not in best or key < best[d][0]:
            best[d] = (key, parts)

    exps = (1, -1, 2, -2, 3, -3, 4, -4)
    for n in _VOCABULARY:
        for e in exps:
            offer(((n, e),))
    for a, b in combinations(_VOCABULARY, 2):
        for ea in exps[:6]:
            for eb in exps[:6]:
                offer(((a, ea), (b, eb)))
    return {d: parts for d, (_, parts) in best.items()}


def _exp_text(e: Fraction) -> str:
    if e == 1:
        return ""
    return f"^{e}" if e.denominator == 1 else f"^({e})"


def format_dim(dim: tuple) -> str:
    """A dimension written as a unit string that :func:`parse_unit` reads back.

    Parameters
    ----------
    dim : tuple
        Exponents of :data:`BASE`, times :data:`DENOM`.

    Returns
    -------
    str
        ``"1"`` for a pure number, a product of one or two familiar units where one fits
        (``"N/m"``, ``"m/N"``, ``"C*m"``), SI base units otherwise.
    """
    if dim == ONE:
        return "1"
    parts = _spellings().get(dim)
    if parts is None:
        parts = tuple((b, Fraction(x, DENOM)) for b, x in zip(BASE, dim) if x)
    parts = sorted(parts, key=lambda part: part[0] in ("m", "s", "kg"))  # derived units first: C*m, A*s
    num = [f"{n}{_exp_text(Fraction(e))}" for n, e in parts if e > 0]
    den = [f"{n}{_exp_text(-Fraction(e))}" for n, e in parts if e < 0]
    top = "*".join(num) or "1"
    if not den:
        return top
    bottom = den[0] if len(den) == 1 else "(" + "*".join(den) + ")"
    return f"{top}/{bottom}"
