"""Parameter spaces for sweeps: distributions and grids, and the designs that draw from them.

A *space* maps parameter names to specifications, written as on the command line
(``--vary NAME=SPEC``) or built in Python:

* ``uniform(lo, hi)``                 uniform between the bounds
* ``normal(mean, sd)``                normal; ``sd`` may be a share of the mean, ``normal(3000, 5%)``
* ``normal(mean, sd, lo, hi)``        normal truncated to [lo, hi]
* ``loguniform(lo, hi)``              log-uniform between the bounds (0 < lo < hi)
* ``linspace(lo, hi, n)``, ``logspace(lo, hi, n)``, ``values(a, b, ...)``   grid levels
  (``values`` also takes integers and choices: ``values(none, bouc-wen)``)

Designs (each returns one dict of parameter values per run, in a fixed order):

* ``random``  (Monte Carlo): independent draws, ``draws`` of them, from ``numpy.random.default_rng(seed)``
* ``lhs``     Latin hypercube (``scipy.stats.qmc``) mapped through each distribution's inverse CDF
* ``grid``    the full factorial of the grid levels
* ``oat``     one at a time: the nominal point, then each parameter at its low and at its high
  value with the others nominal (the tornado design); low/high are a distribution's bounds,
  for an unbounded normal mean ∓ 2 sd, for a grid its first and last level

The same space, design, count and seed always give the same runs.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
from scipy import stats
from scipy.stats import qmc

from ..support.errors import UsageError

DESIGNS = ("random", "lhs", "grid", "oat")


@dataclass(frozen=True)
class Distribution:
    """A continuous distribution (a frozen ``scipy.stats`` one) with its low/high for OAT runs.

    Parameters
    ----------
    text : str
        How it is written, e.g. ``"normal(3000, 150)"``.
    dist : scipy.stats.rv_continuous (frozen)
        The distribution.
    low, high : float
        The values of one-at-a-time runs, in the parameter's unit.
    """

    text: str
    dist: Any
    low: float
    high: float

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Inverse CDF: the values at probabilities ``u`` (0 < u < 1).

        Parameters
        ----------
        u : numpy.ndarray
            Probabilities.

        Returns
        -------
        numpy.ndarray
            The values, in the parameter's unit.
        """
        return np.asarray(self.dist.ppf(u), float)

    def __str__(self):
        return self.text


@dataclass(frozen=True)
class Grid:
    """Grid levels of one parameter (numbers, or choices of a structural parameter).

    Parameters
    ----------
    text : str
        How it is written, e.g. ``"linspace(1, 2, 5)"``.
    levels : tuple
        The levels, in run order.
    """

    text: str
    levels: tuple

    @property
    def low(self):
        """The first level (the low value of one-at-a-time runs)."""
        return self.levels[0]

    @property
    def high(self):
        """The last level (the high value of one-at-a-time runs)."""
        return self.levels[-1]

    def __str__(self):
        return self.text


def uniform(lo: float, hi: float) -> Distribution:
    """Uniform distribution between ``lo`` and ``hi`` (``uniform(lo, hi)``).

    Parameters
    ----------
    lo, hi : float
        Bounds, in the parameter's unit; lo < hi. They are also the OAT low and high.

    Returns
    -------
    Distribution
        The frozen distribution with its low/high values for one-at-a-time runs.

    Raises
    ------
    UsageError
        ``lo`` is not below ``hi``.
    """
    _order(lo, hi, "uniform")
    return Distribution(f"uniform({lo:g}, {hi:g})", stats.uniform(lo, hi - lo), lo, hi)


def normal(mean: float, sd: float, lo: float | None = None, hi: float | None = None) -> Distribution:
    """Normal distribution, truncated to [lo, hi] when bounds are given (``normal(mean, sd)``).

    Parameters
    ----------
    mean : float
        Mean, in the parameter's unit.
    sd : float
        Standard deviation (> 0), same unit; the OAT low and high are mean ∓ 2 sd, clipped to
        the bounds.
    lo, hi : float, optional
        Truncation bounds (one may be left open).

    Returns
    -------
    Distribution
        The frozen distribution with its low/high values for one-at-a-time runs.

    Raises
    ------
    UsageError
        ``sd`` is not positive, or ``lo`` is not below ``hi``.
    """
    if not sd > 0:
        raise UsageError(f"normal({mean:g}, {sd:g}): the standard deviation must be positive")
    if lo is None and hi is None:
        return Distribution(f"normal({mean:g}, {sd:g})", stats.norm(mean, sd), mean - 2 * sd, mean + 2 * sd)
    lo = -math.inf if lo is None else lo
    hi = math.inf if hi is None else hi
    _order(lo, hi, "normal")
    d = stats.truncnorm((lo - mean) / sd, (hi - mean) / sd, loc=mean, scale=sd)
    return Distribution(f"normal({mean:g}, {sd:g}, {lo:g}, {hi:g})", d, max(lo, mean - 2 * sd), min(hi, mean + 2 * sd))


def loguniform(lo: float, hi: float) -> Distribution:
    """Log-uniform distribution between ``lo`` and ``hi`` (``loguniform(lo, hi)``).

    Parameters
    ----------
    lo, hi : float
        Bounds, in the parameter's unit; 0 < lo < hi. They are also the OAT low and high.

    Returns
    -------
    Distribution
        The frozen distribution with its low/high values for one-at-a-time runs.

    Raises
    ------
    UsageError
        The bounds are out of order or not positive.
    """
    _order(lo, hi, "loguniform")
    if lo <= 0:
        raise UsageError(f"loguniform({lo:g}, {hi:g}): the bounds must be positive")
    return Distribution(f"loguniform({lo:g}, {hi:g})", stats.loguniform(lo, hi), lo, hi)


def linspace(lo: float, hi: float, n: int) -> Grid:
    """``n`` evenly spaced grid levels from ``lo`` to ``hi`` (``linspace(lo, hi, n)``).

    Parameters
    ----------
    lo, hi : float
        First and last level, in the parameter's unit.
    n : int
        Number of levels (at least 2).

    Returns
    -------
    Grid
        The levels, first and last being the OAT low and high.

    Raises
    ------
    UsageError
        ``n`` is not an integer of at least 2.
    """
    _levels(n, "linspace")
    return Grid(f"linspace({lo:g}, {hi:g}, {n})", tuple(np.linspace(lo, hi, int(n)).tolist()))


def logspace(lo: float, hi: float, n: int) -> Grid:
    """``n`` geometrically spaced grid levels from ``lo`` to ``hi`` (``logspace(lo, hi, n)``).

    Unlike ``numpy.logspace`` the bounds are the levels themselves, not their exponents.

    Parameters
    ----------
    lo, hi : float
        First and last level (> 0), in the parameter's unit.
    n : int
        Number of levels (at least 2).

    Returns
    -------
    Grid
        The levels, first and last being the OAT low and high.

    Raises
    ------
    UsageError
        ``n`` is not an integer of at least 2, or a bound is not positive.
    """
    _levels(n, "logspace")
    if lo <= 0 or hi <= 0:
        raise UsageError(f"logspace({lo:g}, {hi:g}, {n}): the bounds must be positive")
    return Grid(f"logspace({lo:g}, {hi:g}, {n})", tuple(np.geomspace(lo, hi, int(n)).tolist()))


def values(*levels) -> Grid:
    """Grid levels given one by one: numbers, integers or choices (``values(none, bouc-wen)``).

    Parameters
    ----------
    *levels : float, int or str
        The levels, in the order the runs take them.

    Returns
    -------
    Grid
        The levels, first and last being the OAT low and high.

    Raises
    ------
    UsageError
        No level is given.
    """
    if not levels:
        raise UsageError("values(...): give at least one value")
    return Grid("values(" + ", ".join(str(v) for v in levels) + ")", tuple(levels))


def _order(lo, hi, what):
    if not lo < hi:
        raise UsageError(f"{what}: the lower bound must be below the upper one (got {lo:g}, {hi:g})")


def _levels(n, what):
    if int(n) != n or n < 2:
        raise UsageError(f"{what}: the number of levels must be an integer of at least 2 (got {n})")


_SPEC = re.compile(r"^\s*([a-z]+)\s*\((.*)\)\s*$", re.S)
_KINDS = {
    "uniform": (uniform, 2, 2),
    "normal": (normal, 2, 4),
    "loguniform": (loguniform, 2, 2),
    "linspace": (linspace, 3, 3),
    "logspace": (logspace, 3, 3),
}


def parse_spec(text: str) -> Distribution | Grid:
    """A distribution or grid from its text, e.g. ``normal(3000, 5%)`` (see the module docstring).

    Parameters
    ----------
    text : str
        The specification: ``uniform(lo, hi)``, ``normal(mean, sd[, lo, hi])`` (``sd`` may be a
        percentage of the mean), ``loguniform(lo, hi)``, ``linspace(lo, hi, n)``,
        ``logspace(lo, hi, n)`` or ``values(a, b, ...)``.

    Returns
    -------
    Distribution or Grid
        What the text specifies.

    Raises
    ------
    UsageError
        Unknown kind, wrong number of arguments, a value that is not a finite number, or bad
        bounds.
    """
    m = _SPEC.match(text)
    kinds = ", ".join([*_KINDS, "values"])
    if not m:
        raise UsageError(f"bad parameter spec {text!r}: write e.g. uniform(9e6, 12e6); kinds: {kinds}")
    kind, args = m.group(1), [a.strip() for a in m.group(2).split(",") if a.strip()]
    if kind == "values":
        return values(*(_number_or_text(a) for a in args))
    if kind not in _KINDS:
        raise UsageError(f"unknown spec kind '{kind}' in {text!r}; kinds: {kinds}")
    factory, lo, hi = _KINDS[kind]
    if not lo <= len(args) <= hi:
        raise UsageError(
            f"bad parameter spec {text!r}: {kind} takes {lo}" + (f" to {hi}" if hi > lo else "") + " numbers"
        )
    nums = []
    for i, a in enumerate(args):
        if a.endswith("%") and kind == "normal" and i == 1:  # sd as a share of the mean
            nums.append(abs(_number(a[:-1], text)) / 100 * abs(nums[0]))
        else:
            nums.append(_number(a, text))
    return factory(*nums)


def _number(a: str, text: str) -> float:
    try:
        v = float(a)
    except ValueError:
        raise UsageError(f"bad parameter spec {text!r}: {a!r} is not a number") from None
    if not math.isfinite(v):
        raise UsageError(f"bad parameter spec {text!r}: values must be finite")
    return v


def _number_or_text(a: str):
    try:
        v = float(a)
    except ValueError:
        return a
    return int(v) if v.is_integer() and "." not in a and "e" not in a.lower() else v


def parse_space(items: Sequence[str]) -> dict[str, Distribution | Grid]:
    """``NAME=SPEC`` strings (``--vary``) → space.

    Parameters
    ----------
    items : sequence of str
        ``NAME=SPEC`` strings, e.g. ``"K=uniform(9e6, 12e6)"`` (see :func:`parse_spec`).

    Returns
    -------
    dict of str to Distribution or Grid
        Parameter name → specification, in the order given.

    Raises
    ------
    UsageError
        An item without ``=`` or name, a name given twice, or a bad specification.
    """
    space: dict[str, Distribution | Grid] = {}
    for item in items:
        name, sep, spec = item.partition("=")
        if not sep or not name.strip():
            raise UsageError(f"bad --vary {item!r}: expected NAME=SPEC, e.g. --vary 'K=uniform(9e6, 12e6)'")
        if name.strip() in space:
            raise UsageError(f"--vary {name.strip()} given twice")
        space[name.strip()] = parse_spec(spec)
    return space


def default_design(space: Mapping[str, Distribution | Grid]) -> str:
    """``grid`` when every parameter has grid levels, else ``random``.

    Parameters
    ----------
    space : mapping of str to Distribution or Grid
        The parameter space.

    Returns
    -------
    str
        ``"grid"`` or ``"random"``.
    """
    return "grid" if space and all(isinstance(s, Grid) for s in space.values()) else "random"


def design_points(
    space: Mapping[str, Distribution | Grid],
    design: str,
    draws: int | None = None,
    seed: int | None = None,
    nominal: Mapping[str, Any] | None = None,
) -> list[dict]:
    """The runs of ``design`` over ``space`` (see the module docstring); ``nominal`` holds the
    model's values, needed by ``oat``.

    Parameters
    ----------
    space : mapping of str to Distribution or Grid
        The parameter space.
    design : {"random", "lhs", "grid", "oat"}
        The design.
    draws : int, optional
        Number of runs of ``random`` and ``lhs`` (a positive integer).
    seed : int, optional
        Seed of ``numpy.random.default_rng``.
    nominal : mapping, optional
        The model's values of the parameters (``oat``).

    Returns
    -------
    list of dict
        One ``{parameter: value}`` per run, in a fixed order.

    Raises
    ------
    UsageError
        An empty space, an unknown design, a design that does not fit the space (a grid
        without levels, sampling of grid levels), a missing nominal value, or bad ``draws``.
    """
    if not space:
        raise UsageError("nothing to vary: give at least one parameter, e.g. --vary 'K=uniform(9e6, 12e6)'")
    if design not in DESIGNS:
        raise UsageError(f"unknown design {design!r}; choose one of {', '.join(DESIGNS)}")
    names = list(space)
    if design == "grid":
        loose = [n for n in names if not isinstance(space[n], Grid)]
        if loose:
            raise UsageError(
                f"a grid needs levels for every parameter; {loose[0]} has {space[loose[0]]} "
                f"(use linspace/logspace/values, or --design random)"
            )
        return [dict(zip(names, combo)) for combo in itertools.product(*(space[n].levels for n in names))]
    if design == "oat":
        nominal = dict(nominal or {})
        missing = [n for n in names if n not in nominal]
        if missing:
            raise UsageError(f"one-at-a-time runs need the nominal value of {missing[0]}")
        base = {n: nominal[n] for n in names}
        runs = [dict(base)]
        for n in names:
            runs += [{**base, n: space[n].low}, {**base, n: space[n].high}]
        return runs
    grids = [n for n in names if isinstance(space[n], Grid)]
    if grids:
        raise UsageError(
            f"{design} sampling needs a distribution for every parameter; {grids[0]} has grid "
            f"levels {space[grids[0]]} (use uniform/normal/loguniform, or --design grid)"
        )
    if draws is None or int(draws) != draws or draws < 1:
        raise UsageError(f"give the number of draws (a positive integer), got {draws}")
    draws = int(draws)
    if design == "random":
        u = np.random.default_rng(seed).random((draws, len(names)))
    else:
        u = qmc.LatinHypercube(d=len(names), rng=np.random.default_rng(seed)).random(draws)
    columns = [space[n].ppf(u[:, j]) for j, n in enumerate(names)]
    return [{n: float(columns[j][i]) for j, n in enumerate(names)} for i in range(draws)]
