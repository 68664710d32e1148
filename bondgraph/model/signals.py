"""Input signals: step, ramp, sine, chirp, triangle, piecewise-linear, CSV column.

Every signal is encoded as a kind code, a row of parameters and (for tables) a slice of a
shared time/value table, so the compiled integrator evaluates all inputs and their time
derivatives without calling back into Python
(:class:`bondgraph.numerics.signal_bank.SignalBank`).  Times in s, frequencies in Hz, phases in degrees; values in the input's unit.

Command-line syntax (``--input NAME=SPEC``): ``step(amplitude=1, t0=0, offset=0)``,
``ramp(slope=1, t0=0, offset=0)``, ``sine(amplitude=1, frequency=1, phase=0, offset=0)``,
``chirp(amplitude=1, f0=1, f1=100, t1=1, phase=0, offset=0)`` (linear sweep, as
scipy.signal.chirp), ``triangle(amplitude=1, frequency=1, phase=0, offset=0)``,
``pwl(0:0, 1:10, 2:0)`` (time:value pairs) and ``csv(file=data.csv, column=V)``; a plain
number is a constant.
"""

from __future__ import annotations

import inspect
import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ..support.errors import SignalError

#: signal kinds (the compiled integrator, bondgraph.numerics.integrators, switches on them) and the
#: length of a signal's parameter row
CONST, STEP, RAMP, SINE, CHIRP, TRIANGLE, PWL = range(7)
NPAR = 6


@dataclass(frozen=True)
class Signal:
    """An input signal, encoded for the compiled integrator.

    Made by the factories (:func:`Step`, :func:`Sine`, ...) or :func:`parse_signal` rather
    than directly.

    Parameters
    ----------
    kind : int
        The kind code (:data:`CONST`, :data:`STEP`, :data:`RAMP`, :data:`SINE`,
        :data:`CHIRP`, :data:`TRIANGLE`, :data:`PWL`).
    par : tuple of float
        The parameter row, :data:`NPAR` values (times in s, frequencies in Hz, phases in
        rad, values in the input's unit).
    table_t, table_v : tuple of float, optional
        The (time in s, value) table of a piecewise-linear signal.
    label : str, optional
        How the signal is printed.
    """

    kind: int
    par: tuple
    table_t: tuple = ()
    table_v: tuple = ()
    label: str = ""

    def breakpoints(self, t0: float, t1: float, kinks: bool = False) -> list[float]:
        """The times where the signal jumps (the integrator restarts there).

        Parameters
        ----------
        t0, t1 : float
            The open time window, in s.
        kinks : bool, optional
            Also where the slope jumps (ramp start, table knots, triangle corners), for
            models whose laws use input rates or whose memory operators reverse there.

        Returns
        -------
        list of float
            The times in (t0, t1), in s.
        """
        if self.kind == STEP:
            out = [self.par[1]]
        elif not kinks:
            out = []
        elif self.kind == RAMP:
            out = [self.par[1]]
        elif self.kind == PWL:
            tt = np.asarray(self.table_t)
            out = tt[(tt > t0) & (tt < t1)].tolist()
        elif self.kind == TRIANGLE and self.par[1] > 0:  # corners where 2πf·t + φ is a multiple of π
            k0 = math.ceil((2 * math.pi * self.par[1] * t0 + self.par[2]) / math.pi)
            k1 = math.floor((2 * math.pi * self.par[1] * t1 + self.par[2]) / math.pi)
            out = [(k * math.pi - self.par[2]) / (2 * math.pi * self.par[1]) for k in range(k0, k1 + 1)]
        else:
            out = []
        return [b for b in out if t0 < b < t1]

    def __str__(self):
        return self.label


def Constant(value: float = 0.0) -> Signal:
    """A constant input.

    Parameters
    ----------
    value : float, optional
        The value, in the input's unit; 0 by default.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.
    """
    return Signal(CONST, _row(value), label=f"{value:g}")


def Step(amplitude: float = 1.0, t0: float = 0.0, offset: float = 0.0) -> Signal:
    """A step: offset for t < t0, offset + amplitude from t0 on.

    Parameters
    ----------
    amplitude : float, optional
        The jump, in the input's unit.
    t0 : float, optional
        The time of the jump, in s.
    offset : float, optional
        The value before the jump.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.
    """
    return Signal(
        STEP, _row(amplitude, t0, offset), label=f"step(amplitude={amplitude:g}, t0={t0:g}, offset={offset:g})"
    )


def Ramp(slope: float = 1.0, t0: float = 0.0, offset: float = 0.0) -> Signal:
    """A ramp: offset + slope·max(0, t − t0).

    Parameters
    ----------
    slope : float, optional
        The rate, in the input's unit per s.
    t0 : float, optional
        When the ramp starts, in s.
    offset : float, optional
        The value before it starts.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.
    """
    return Signal(RAMP, _row(slope, t0, offset), label=f"ramp(slope={slope:g}, t0={t0:g}, offset={offset:g})")


def Sine(amplitude: float = 1.0, frequency: float = 1.0, phase: float = 0.0, offset: float = 0.0) -> Signal:
    """A sine: offset + amplitude·sin(2π·frequency·t + phase°).

    Parameters
    ----------
    amplitude : float, optional
        The amplitude (half the peak-to-peak), in the input's unit.
    frequency : float, optional
        In Hz.
    phase : float, optional
        In degrees.
    offset : float, optional
        The mean value.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.
    """
    return Signal(
        SINE,
        _row(amplitude, frequency, math.radians(phase), offset),
        label=f"sine(amplitude={amplitude:g}, frequency={frequency:g}, phase={phase:g}, offset={offset:g})",
    )


def Chirp(
    amplitude: float = 1.0, f0: float = 1.0, f1: float = 100.0, t1: float = 1.0, phase: float = 0.0, offset: float = 0.0
) -> Signal:
    """A linear frequency sweep from f0 at t = 0 to f1 at t1 (continuing beyond t1, like
    :func:`scipy.signal.chirp`).

    Parameters
    ----------
    amplitude : float, optional
        In the input's unit.
    f0, f1 : float, optional
        The frequencies at t = 0 and at ``t1``, in Hz.
    t1 : float, optional
        The time at which the frequency is ``f1``, in s; positive.
    phase : float, optional
        In degrees.
    offset : float, optional
        The mean value.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.

    Raises
    ------
    bondgraph.support.errors.SignalError
        If ``t1`` is not positive.
    """
    if t1 <= 0:
        raise SignalError("chirp: t1 must be positive")
    return Signal(
        CHIRP,
        _row(amplitude, f0, f1, t1, math.radians(phase), offset),
        label=f"chirp(amplitude={amplitude:g}, f0={f0:g}, f1={f1:g}, t1={t1:g})",
    )


def Triangle(amplitude: float = 1.0, frequency: float = 1.0, phase: float = 0.0, offset: float = 0.0) -> Signal:
    """A symmetric triangle between offset ± amplitude; like
    ``offset + amplitude·scipy.signal.sawtooth(2π·f·t + phase°, width=0.5)``.

    Parameters
    ----------
    amplitude : float, optional
        In the input's unit.
    frequency : float, optional
        In Hz.
    phase : float, optional
        In degrees.
    offset : float, optional
        The mean value.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.
    """
    return Signal(
        TRIANGLE,
        _row(amplitude, frequency, math.radians(phase), offset),
        label=f"triangle(amplitude={amplitude:g}, frequency={frequency:g}, offset={offset:g})",
    )


def PiecewiseLinear(times, values, label: str = "") -> Signal:
    """Linear interpolation between (time, value) samples, constant outside.

    Parameters
    ----------
    times : array_like
        Sample times in s, strictly increasing.
    values : array_like
        Values at those times, in the input's unit.
    label : str, optional
        How the signal is printed; ``pwl(N points)`` by default.

    Returns
    -------
    Signal
        The signal, for ``inputs={"V": ...}`` of a simulation.

    Raises
    ------
    bondgraph.support.errors.SignalError
        If times and values are not equal-length 1-D arrays, hold NaN or inf, or the times
        do not increase strictly.
    """
    t = np.asarray(times, float)
    v = np.asarray(values, float)
    if t.ndim != 1 or t.shape != v.shape or t.size < 1:
        raise SignalError("piecewise-linear signal needs equal-length 1-D times and values")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise SignalError("piecewise-linear signal has NaN or infinite samples")
    if np.any(np.diff(t) <= 0):
        raise SignalError("piecewise-linear signal: times must be strictly increasing")
    return Signal(PWL, _row(), tuple(t.tolist()), tuple(v.tolist()), label or f"pwl({t.size} points)")


def _row(*vals) -> tuple:
    return tuple(float(v) for v in vals) + (0.0,) * (NPAR - len(vals))


_CALL = re.compile(r"^\s*([a-z]+)\s*\((.*)\)\s*$", re.S)
_FACTORIES = {"step": Step, "ramp": Ramp, "sine": Sine, "chirp": Chirp, "triangle": Triangle}


def parse_signal(spec: str, base_dir: str | None = None) -> Signal:
    """Parse a command-line signal specification (see the module docstring)."""
    from ..data import read_csv  # local import: data reading is only needed for csv inputs

    text = spec.strip()
    try:
        value = float(text)
    except ValueError:
        pass
    else:
        if not math.isfinite(value):
            raise SignalError(f"bad signal {spec!r}: a constant input must be finite")
        return Constant(value)
    m = _CALL.match(text)
    if not m:
        raise SignalError(f"bad signal {spec!r}: write e.g. sine(amplitude=10, frequency=5) or a number")
    kind, body = m.group(1), m.group(2).strip()
    if kind not in _FACTORIES and kind not in ("pwl", "csv"):
        raise SignalError(
            f"unknown signal kind '{kind}' in {spec!r}; known: {', '.join(list(_FACTORIES) + ['pwl', 'csv'])}"
        )
    if kind == "pwl":
        try:
            pairs = [tuple(float(x) for x in item.split(":")) for item in body.split(",") if item.strip()]
            if not pairs or any(len(p) != 2 for p in pairs):
                raise ValueError
        except ValueError:
            raise SignalError(f"bad signal {spec!r}: write pwl(t0:v0, t1:v1, ...)") from None
        t, v = zip(*pairs)
        return PiecewiseLinear(t, v, label=text)
    kwargs = {}
    for item in filter(None, (s.strip() for s in body.split(","))):
        key, sep, val = item.partition("=")
        if not sep:
            raise SignalError(f"bad signal {spec!r}: arguments are key=value, got {item!r}")
        kwargs[key.strip()] = val.strip()
    if kind == "csv":
        unknown = set(kwargs) - {"file", "column"}
        if unknown or "file" not in kwargs:
            raise SignalError(f"bad signal {spec!r}: write csv(file=PATH, column=NAME)")
        path = kwargs["file"]
        if base_dir and not os.path.isabs(path) and not os.path.exists(path):
            path = os.path.join(base_dir, path)
        col = kwargs.get("column", "V")
        ds = read_csv(path, required=("t", col))
        return PiecewiseLinear(ds.t, ds.columns[col], label=f"csv({kwargs['file']}:{col})")
    factory = _FACTORIES[kind]
    names = list(inspect.signature(factory).parameters)
    try:
        args = {k: float(v) for k, v in kwargs.items()}
    except ValueError:
        raise SignalError(f"bad signal {spec!r}: values must be numbers") from None
    if not all(math.isfinite(v) for v in args.values()):
        raise SignalError(f"bad signal {spec!r}: values must be finite")
    unknown = set(args) - set(names)
    if unknown:
        raise SignalError(f"bad signal {spec!r}: {kind} takes {', '.join(names)}; not {', '.join(sorted(unknown))}")
    return factory(**args)
