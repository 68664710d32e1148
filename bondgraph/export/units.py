"""SI unit strings (``"N/m"``, ``"V/(C*m^2)"``, ``"1/(C^2 s^2)"``) as FMI base units: exponents of
kg, m, s, A, K, mol, cd, rad and a factor, so a simulation tool importing an FMU can check and
convert them (FMI 2.0, section 2.2.2, ``<BaseUnit>``).

Grammar: products (``*``, a space, or ``.``) and quotients (``/``) of unit symbols with integer
powers (``^2``, ``^-1``, or a trailing digit: ``m2``), in parentheses as needed; ``1`` is
dimensionless.  Symbols: the SI base units, the derived units N, Pa, J, W, C, V, ohm (Ω), F, H,
S, Hz, T, Wb, g, deg, rad, min, h, with the prefixes p, n, u (µ), m, c, k, M, G.  A string that
does not parse gives no base unit (the unit is still declared by name).
"""

from __future__ import annotations

import math
import re

#: base-unit attributes of FMI 2.0 in their order
BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _u(factor=1.0, **exps) -> tuple[float, tuple[int, ...]]:
    return factor, tuple(exps.get(b, 0) for b in BASE)


_SYMBOLS = {
    "kg": _u(kg=1),
    "g": _u(1e-3, kg=1),
    "m": _u(m=1),
    "s": _u(s=1),
    "A": _u(A=1),
    "K": _u(K=1),
    "mol": _u(mol=1),
    "cd": _u(cd=1),
    "rad": _u(rad=1),
    "deg": _u(math.pi / 180.0, rad=1),
    "min": _u(60.0, s=1),
    "h": _u(3600.0, s=1),
    "Hz": _u(s=-1),
    "N": _u(kg=1, m=1, s=-2),
    "Pa": _u(kg=1, m=-1, s=-2),
    "J": _u(kg=1, m=2, s=-2),
    "W": _u(kg=1, m=2, s=-3),
    "C": _u(A=1, s=1),
    "V": _u(kg=1, m=2, s=-3, A=-1),
    "ohm": _u(kg=1, m=2, s=-3, A=-2),
    "Ω": _u(kg=1, m=2, s=-3, A=-2),
    "F": _u(kg=-1, m=-2, s=4, A=2),
    "H": _u(kg=1, m=2, s=-2, A=-2),
    "S": _u(kg=-1, m=-2, s=3, A=2),
    "T": _u(kg=1, s=-2, A=-1),
    "Wb": _u(kg=1, m=2, s=-2, A=-1),
}
_PREFIXES = {"p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "m": 1e-3, "c": 1e-2, "k": 1e3, "M": 1e6, "G": 1e9}
_TOKEN = re.compile(r"(?P<num>\d+)|(?P<sym>[A-Za-zΩµ]+)(?P<tail>-?\d+)?|(?P<op>[*/^().]|-\d+)|(?P<sp>\s+)")


def _symbol(name: str):
    if name in _SYMBOLS:
        return _SYMBOLS[name]
    if len(name) > 1 and name[0] in _PREFIXES and name[1:] in _SYMBOLS and name[1:] != "kg":
        f, e = _SYMBOLS[name[1:]]
        return _PREFIXES[name[0]] * f, e
    raise ValueError(name)


def base_unit(unit: str) -> tuple[float, dict[str, int]] | None:
    """(factor, {base: exponent}) of ``unit`` in SI base units, or None if it does not parse.

    Parameters
    ----------
    unit : str
        A unit string such as ``"N*s/m"`` or ``"V/um"``.

    Returns
    -------
    tuple or None
        The factor to SI (``"um"`` → 1e-6) and the nonzero exponents, or None.
    """
    try:
        tokens = _tokens(unit)
        pos, (factor, exps) = _product(tokens, 0)
        if pos != len(tokens):
            return None
    except (ValueError, IndexError):
        return None
    return factor, {b: e for b, e in zip(BASE, exps) if e}


def _tokens(text: str) -> list[str]:
    out, pos = [], 0
    text = text.strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            raise ValueError(text)
        pos = m.end()
        if m.group("sym"):
            out.append(("sym", m.group("sym")))
            if m.group("tail"):
                out += [("op", "^"), ("num", m.group("tail"))]
        elif m.group("num"):
            out.append(("num", m.group("num")))
        elif m.group("op"):
            op = m.group("op")
            out.append(("num", op) if op.lstrip("-").isdigit() else ("op", "*" if op == "." else op))
        else:
            out.append(("op", "*"))
    # a space next to an operator or parenthesis is no product
    clean = []
    for t in out:
        if t == ("op", "*") and (not clean or clean[-1] in (("op", "*"), ("op", "/"), ("op", "("), ("op", "^"))):
            continue
        if clean and clean[-1] == ("op", "*") and t in (("op", "*"), ("op", "/"), ("op", ")"), ("op", "^")):
            clean.pop()
        clean.append(t)
    return clean


def _mul(a, b, sign=1):
    return a[0] * b[0] ** sign, tuple(x + sign * y for x, y in zip(a[1], b[1]))


def _product(tokens, pos):
    pos, acc = _power(tokens, pos)
    while pos < len(tokens) and tokens[pos][0] == "op" and tokens[pos][1] in "*/":
        sign = 1 if tokens[pos][1] == "*" else -1
        pos, rhs = _power(tokens, pos + 1)
        acc = _mul(acc, rhs, sign)
    return pos, acc


def _power(tokens, pos):
    kind, val = tokens[pos]
    if kind == "op" and val == "(":
        pos, base = _product(tokens, pos + 1)
        if tokens[pos] != ("op", ")"):
            raise ValueError("unbalanced")
        pos += 1
    elif kind == "sym":
        base, pos = _symbol(val), pos + 1
    elif kind == "num" and val == "1":
        base, pos = (1.0, (0,) * len(BASE)), pos + 1
    else:
        raise ValueError(val)
    if pos < len(tokens) and tokens[pos] == ("op", "^"):
        n = int(tokens[pos + 1][1])
        base = base[0] ** n, tuple(e * n for e in base[1])
        pos += 2
    return pos, base
